"""Work a robot's registry entry can declare beside the common sections (Robot.extras).

Each extra names one function per stage section it adds to: `identification(ctx)` and
`planning(ctx, models)`, each returning a SectionResult the section takes in under the
extra's name (SectionResult.extend). "paper": the paper's reproduction on its arm (Table IV
and the published library; the paper's planning scenario and formulation).
"""

from __future__ import annotations

from typing import NamedTuple

from harness.sections.paper.scenario import run as scenario_run
from harness.sections.paper.tables import run as tables_run


class Extra(NamedTuple):
    identification: object
    planning: object


EXTRAS = {"paper": Extra(tables_run, scenario_run)}
