"""The bench's sections, one per stage in data-flow order; each serves every robot.

A section is the module harness.bench.<name> (for a package, its `section` module) with
`run(context) -> SectionResult` (harness.report.results). Work only some robots need is
declared in the robot's registry entry (Robot.extras, harness.robots.extras), not branched
on here.
"""

from __future__ import annotations

import importlib

SECTIONS = ("identification", "planning", "replay", "closeloop", "real_data")


def entry_module(kind: str, name: str, known, module: str):
    """The module (dotted path) with run(context) of the kind's entry name, or for a package
    its `section` module (ValueError if name is not one of known)."""
    if name not in known:
        raise ValueError(f"unknown {kind} {name!r} (known: {', '.join(known)})")
    entry = importlib.import_module(module)
    if hasattr(entry, "__path__"):
        entry = importlib.import_module(f"{module}.section")
    return entry


def load_section(name: str):
    """The entry module of section name."""
    return entry_module("sections", name, SECTIONS, f"harness.bench.{name}")
