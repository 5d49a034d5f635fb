"""The "paper" extra the Lynxmotion's registry entry declares (Robot.extras), loaded by name
through harness.robots.extras: the paper's reproduction on its arm beside the bench's common
sections. `identification(ctx)`: Table IV and the published library (tables);
`planning(ctx, models)`: the paper's planning scenario and formulation (scenario)."""

from __future__ import annotations

from harness.paper.sections.scenario import run as planning
from harness.paper.sections.tables import run as identification

__all__ = ["identification", "planning"]
