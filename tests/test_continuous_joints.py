"""Continuous (unbounded revolute) joints, as in Kinova Gen3 descriptions, through every
command. tests/data/gen3_like.urdf has joints 1, 3, 5, 7 continuous: Pinocchio would read
them as (cos, sin) configurations (nq = 2 per joint); the harness reads a continuous joint
as a revolute joint over one turn, so both engines see one angle per joint, and MuJoCo's
inverse dynamics and Pinocchio's RNEA agree on it."""

from __future__ import annotations

import json
from math import pi
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.identify.scoring import closed_form_gap, sines_motion
from harness.robots.arm import Arm

URDF = str(Path(__file__).resolve().parent / "data" / "gen3_like.urdf")
START, GOAL = "0,0.3,0,1.5,0,1.0,0", "1.0,0.5,0.3,1.2,0.2,0.8,0.5"


def test_continuous_joints_are_one_angle_each_in_both_engines():
    model, mj = Arm.of(URDF).pinocchio, Arm.of(URDF).mujoco
    assert model.nq == model.nv == mj.nq == mj.nv == 7
    continuous = [0, 2, 4, 6]
    np.testing.assert_allclose(mj.jnt_range[continuous], [[-pi, pi]] * 4)
    np.testing.assert_allclose(model.upperPositionLimit[continuous], pi)
    np.testing.assert_allclose(model.effortLimit, [39] * 4 + [9] * 3)  # the file's own
    assert closed_form_gap(Arm.of(URDF), sines_motion(Arm.of(URDF), 400, 3)) <= 1e-12


@pytest.mark.slow
def test_generate_identify_predict_plan_replay_closeloop(tmp_path):
    data, model, pred = tmp_path / "d.npz", tmp_path / "m.json", tmp_path / "p.npz"
    plan, replay = tmp_path / "plan.json", tmp_path / "replay.json"
    assert main(["generate", "--robot", URDF, "--samples", "1000", "--noise", "0", "--seed",
                 "1", "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--robot", URDF, "--out", str(model)]) == 0
    assert max(json.loads(model.read_text())["metrics"]["heldout_rel_rmse"]) <= 1e-9
    assert main(["predict", "--model", str(model), "--robot", URDF, "--data", str(data),
                 "--out", str(pred)]) == 0
    clean = np.load(data)["tau_clean"]
    assert np.max(np.abs(np.load(pred)["tau"] - clean)) <= 1e-8 * np.max(np.abs(clean))
    assert main(["plan", "--robot", URDF, "--model", str(model), "--start", START, "--goal",
                 GOAL, "--obstacle-from", "3,3,3", "--obstacle-to", "3,3,4",
                 "--out", str(plan)]) == 0
    p = json.loads(plan.read_text())
    assert np.allclose(p["q"][-1], [float(x) for x in GOAL.split(",")], atol=1e-6)
    assert np.max(np.abs(p["qd"][-1])) <= 1e-6 and p["energy"] > 0
    assert main(["replay", "--plan", str(plan), "--out", str(replay)]) == 0
    r = json.loads(replay.read_text())
    assert r["tracking_rms"] <= 1e-3 and abs(r["energy"] / p["energy"] - 1) <= 0.02
    assert main(["closeloop", "--plant", URDF, "--robot", URDF, "--out",
                 str(tmp_path / "cl")]) == 0
    loop = json.loads((tmp_path / "cl" / "closeloop.json").read_text())
    assert loop["effects"] == [] and not loop["unexplained"]  # the plant is the model


@pytest.mark.slow
def test_closeloop_section_on_an_arm_with_massless_frames(tmp_path):
    """The bench's closeloop plants written from this URDF (its end_effector_link has no mass:
    the plants give it an explicit zero inertial, which Pinocchio's MJCF reader needs)."""
    out = tmp_path / "out"
    assert main(["bench", "--quick", "--no-video", "--robot", URDF, "--sections", "closeloop",
                 "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["ok"] and report["checks"]["total"] >= 3
