"""The bench's sections, one per stage in data-flow order; each serves every robot.

A section is the module harness.sections.<name> (for a package, its `section` module) with
`run(context) -> SectionResult` (harness.sections.base). Work only some robots need is
declared in the robot's registry entry (Robot.extras, harness.sections.paper), not branched
on here.
"""

from __future__ import annotations

import importlib

SECTIONS = ("identification", "planning", "replay", "closeloop", "real_data")


def load_section(name: str):
    """The entry module of section name (ValueError if it is not one)."""
    if name not in SECTIONS:
        raise ValueError(f"unknown section {name!r} (known: {', '.join(SECTIONS)})")
    module = importlib.import_module(f"harness.sections.{name}")
    if hasattr(module, "__path__"):
        module = importlib.import_module(f"harness.sections.{name}.section")
    return module
