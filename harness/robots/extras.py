"""Reproductions a robot's registry entry names, imported on first use by name: the product
never imports one (harness.paper) at module level, only through here.

An extra (Robot.extras) is a module with `identification(ctx)` and `planning(ctx, models)`,
each returning a SectionResult the stage's section takes in under the extra's name
(SectionResult.extend). A published library is one `identify --library NAME` fits.
"""

from __future__ import annotations

from importlib import import_module

EXTRAS = {"paper": "harness.paper.sections"}  # name -> its module
LIBRARIES = {"paper": "harness.paper.identification.published_library:paper_library"}


def extra(name: str):
    """The module of the extra name (Robot.extras)."""
    return import_module(EXTRAS[name])


def published_library(name: str):
    """The published library name (an identification.library.base.Library)."""
    module, function = LIBRARIES[name].split(":")
    return getattr(import_module(module), function)()
