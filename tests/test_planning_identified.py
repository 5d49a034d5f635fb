"""The acceptance check with a model identified by the CLI pipeline (not a stand-in)."""

from __future__ import annotations

import json

import numpy as np

from harness.cli import main
from harness.robots.arm import Arm
from planning.formulation.energy import absolute_energy


def test_identified_plan_energy_matches_pinocchio_plan(tmp_path):
    data, model = tmp_path / "data.npz", tmp_path / "model.json"
    assert main(["generate", "--plant", "lynxmotion", "--samples", "4000", "--noise", "0.05",
                 "--seed", "0", "--mode", "inverse", "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0
    baseline = Arm.of("lynxmotion").nominal
    energies = []
    for spec in ("pinocchio", str(model)):
        out = tmp_path / "plan.json"
        assert main(["plan", "--no-compile", "--model", spec, "--out", str(out)]) == 0
        plan = json.loads(out.read_text())
        arrays = [np.asarray(plan[k]) for k in ("t", "q", "qd", "qdd")]
        energies.append(absolute_energy(baseline, *arrays))
        assert plan["end_error"] <= 1e-6
        assert plan["min_clearance"] >= plan["threshold"] - 2e-3
    assert abs(energies[1] - energies[0]) / energies[0] <= 0.02
