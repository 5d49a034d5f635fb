"""The bench's planning section runs end to end (quick mode) and returns replayable plans."""

from __future__ import annotations

import json
from pathlib import Path

from harness.replay.reference import plan_reference
from harness.sections.planning import section
from tests.helpers import heavier_model as _heavier


def test_section_quick(tmp_path):
    out = section.run(tmp_path, quick=True, identified_model=_heavier(1.01))
    json.dumps(out["results"])  # serializable as is
    assert {"paper_pinocchio", "paper_identified", "crossing_obstacle"} <= set(out["plans"])
    for plan in out["plans"].values():
        plan_reference(json.loads(json.dumps(plan, default=lambda a: a.tolist())))
    assert all(Path(f).is_file() for f in out["figures"])
    acceptance = out["results"]["acceptance"]
    for key in ("pinocchio_clearance_held", "identified_clearance_held",
                "identified_energy_within_2pct", "crossing_avoidance_active",
                "crossing_clearance_held"):
        assert acceptance[key], key
    assert "| pinocchio |" in out["markdown"]
