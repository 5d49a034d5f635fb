"""Any model plans (issue 43): a consistent fit (MODEL.json from `identify --prior nominal`)
whose friction laws are a sigmoid steep enough that its logistic overflows at the slack
check's random points plans with both planners."""

from __future__ import annotations

import json

import pytest

from harness.cli import main


def _steep_consistent_fit(tmp_path, robot: str, samples: int) -> str:
    """A consistent fit of generated measurements, every joint's Coulomb atom replaced by
    Gaz's sigmoid of slope 1e4 s/rad (its logistic overflows beyond 0.07 rad/s)."""
    data, path = tmp_path / "data.npz", tmp_path / "MODEL.json"
    assert main(["generate", "--robot", robot, "--samples", str(samples), "--noise", "0.05",
                 "--seed", "1", "--mode", "measured", "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--prior", "nominal", "--robot", robot,
                 "--out", str(path)]) == 0
    model = json.loads(path.read_text())
    assert model["method"] == "consistent"
    for j, joint in enumerate(model["joints"]):
        model["friction"][j] = {"law": "sigmoid", "shape": [1e4, 0.0]}
        terms, coulomb = joint["terms"], f"coulomb{j + 1}"
        if coulomb in terms:
            terms[terms.index(coulomb)] = f"sigmoid{j + 1}"
        else:  # a Coulomb fitted to exactly 0 (its law dropped it) is not listed
            terms.append(f"sigmoid{j + 1}")
            joint["coefficients"].append(0.0)
    path.write_text(json.dumps(model))
    return str(path)


@pytest.mark.slow
def test_a_steep_consistent_fit_plans_with_both_planners(tmp_path):
    model = _steep_consistent_fit(tmp_path, "lynxmotion", 1000)
    for replanner in ("sqp", "fatrop"):
        out = tmp_path / f"{replanner}.json"
        assert main(["plan", "--no-compile", "--model", model, "--replanner", replanner,
                     "--out", str(out)]) == 0
        assert json.loads(out.read_text())["feasible"]


@pytest.mark.slow
def test_a_steep_consistent_fit_plans_on_a_7_dof_arm(tmp_path):
    """The Panda (the penalty loop on it takes some 20 minutes uncompiled: the anytime SQP
    here, whose build checked the slacks through the model's calls)."""
    model = _steep_consistent_fit(tmp_path, "panda", 2000)
    out = tmp_path / "plan.json"
    # the default obstacle (the paper's, placed for the Lynxmotion) lies inside the Panda's
    # fitted link capsules at the start: the centre lines, as this test was written for
    assert main(["plan", "--no-compile", "--robot", "panda", "--model", model,
                 "--link-radius", "0", "--out", str(out)]) == 0
