"""The bench's sections, one per stage in data-flow order; each serves every robot.

A section is the module harness.sections.<name> (for a package, its `section` module) with
`run(context) -> SectionResult` (harness.sections.base). Work only some robots need is
declared in the robot's registry entry (Robot.extras, harness.sections.paper), not branched
on here.
"""

from __future__ import annotations

import importlib

SECTIONS = ("identification", "planning", "replay", "closeloop", "real_data")


def entry_module(package: str, name: str, known):
    """The module package.<name> with run(context), or for a sub-package its `section`
    module (ValueError if name is not one of known)."""
    if name not in known:
        raise ValueError(f"unknown {package.rsplit('.', 1)[-1]} {name!r} (known: "
                         f"{', '.join(known)})")
    module = importlib.import_module(f"{package}.{name}")
    if hasattr(module, "__path__"):
        module = importlib.import_module(f"{package}.{name}.section")
    return module


def load_section(name: str):
    """The entry module of section name."""
    return entry_module("harness.sections", name, SECTIONS)
