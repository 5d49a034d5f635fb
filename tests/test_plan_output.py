"""What `plan` gives a robot and what `replay` checks it on (issue #43, items 4-6): the
control-rate trajectory CSV (its columns, rate, rest at the goal, limits held, the
feed-forward torque), velocity limits in the NLP, link radii from collision geometry,
`replay --plant` with other dynamics and its summary line; bad input one line, exit 2."""

from __future__ import annotations

import copy
import dataclasses
import json
import re

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.cli import main
from harness.plan.trajectory_csv import read_trajectory
from harness.robots.arm import Arm
from harness.robots.inertials import set_standard_parameters
from models import MODELS
from planning.formulation.clearance import link_clearances
from planning.penalty.solver import Planner
from planning.types import Segment
from tests.helpers import lynx_config, lynx_scenario

RATE = 200.0


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """The paper's plan on the Lynxmotion with its trajectory at RATE Hz."""
    folder = tmp_path_factory.mktemp("plan")
    plan, csv = folder / "plan.json", folder / "traj.csv"
    assert main(["plan", "--model", "pinocchio", "--out", str(plan), "--trajectory", str(csv),
                 "--rate", str(RATE)]) == 0
    return json.loads(plan.read_text()), read_trajectory(str(csv)), plan


def test_trajectory_columns_rate_and_rest_at_goal(planned):
    plan, (header, rows), _ = planned
    assert header == ["t", "q1", "q2", "q3", "qd1", "qd2", "qd3", "qdd1", "qdd2", "qdd3",
                      "tau1", "tau2", "tau3"]
    t = rows[:, 0]
    assert t[0] == 0.0 and t[-1] == pytest.approx(plan["duration"])
    assert np.allclose(np.diff(t), 1 / RATE)
    assert np.allclose(rows[-1, 1:4], plan["goal"], atol=1e-6)
    assert np.allclose(rows[-1, 4:7], 0.0, atol=1e-9)


def test_trajectory_is_the_executed_motion(planned):
    """The CSV is what PLAN.json says was executed (every re-plan), not the first plan: on
    the paper's scenario the re-plans move the motion away from the first plan (#56 item 4)."""
    plan, (_, rows), _ = planned
    t, q, qd = (np.asarray(plan[key]) for key in ("t", "q", "qd"))
    first = plan["segments"][0]
    s = (t - first["t_begin"]) / first["duration"]
    first_q = np.stack([np.polynomial.polynomial.polyval(s, c) for c in plan["coefficients"][0]], 1)
    assert plan["replans"] > 0 and np.abs(first_q - q).max() > 0.05  # re-planning changed it
    # the CSV's times on PLAN.json's grid (1/RATE s against 1/500 s: every 0.01 s)
    where = np.searchsorted(t, rows[:, 0])
    common = (where < len(t)) & np.isclose(t[np.minimum(where, len(t) - 1)], rows[:, 0],
                                           rtol=0, atol=1e-12)
    assert common.sum() > 100
    assert np.allclose(rows[common, 1:4], q[where[common]], rtol=0, atol=1e-9)
    assert np.allclose(rows[common, 4:7], qd[where[common]], rtol=0, atol=1e-9)


def test_trajectory_keeps_the_urdf_limits(planned):
    plan, (_, rows), _ = planned
    model = Arm.of("lynxmotion").pinocchio
    q, qd, tau = rows[:, 1:4], rows[:, 4:7], rows[:, 10:13]
    lower, upper = Arm.of("lynxmotion").position_limits
    assert np.all(q >= lower - 1e-6) and np.all(q <= upper + 1e-6)
    assert np.all(np.abs(qd) <= model.velocityLimit) and plan["velocity_limit"] is not None
    assert np.all(np.abs(tau) <= np.asarray(plan["torque_limit"]))


def test_feedforward_is_pinocchio_rnea_at_the_rows(planned):
    _, (_, rows), _ = planned
    model = Arm.of("lynxmotion").pinocchio
    data = model.createData()
    for row in rows[::37]:
        q, qd, qdd = row[1:4], row[4:7], row[7:10]
        tau = pin.rnea(model, data, q, qd, qdd) + np.asarray(model.damping) * qd
        assert np.allclose(row[10:13], tau, atol=1e-9)


def test_velocity_limit_holds_between_the_nlp_samples():
    scenario = lynx_scenario(obstacle=None)
    model = Arm.of("lynxmotion").nominal
    free = Planner(model, lynx_config(rest_at_goal=True)).solve(Segment.of(scenario))
    t = np.linspace(0, scenario.duration, 2001)
    peak = np.abs(free.trajectory.state(t)[1]).max()
    limit = 0.9 * peak
    limited = Planner(model, lynx_config(rest_at_goal=True, velocity_limit=(limit,) * 3)).solve(
        Segment.of(scenario))
    assert limited.success
    assert np.abs(limited.trajectory.state(t)[1]).max() <= limit


def test_link_radii_from_the_collision_meshes():
    for robot in ("panda", "ur5"):
        fitted = Arm.of(robot).capsules()
        radii = np.asarray(fitted.link_radii)
        assert len(radii) == len(fitted.links)  # the Panda's: + link 5
        assert np.all(radii > 0.03) and np.all(radii < 0.3)  # arms, not points or rooms
    # no <collision>: the default
    assert tuple(Arm.of("lynxmotion").capsules(0.012).link_radii) == (0.012,) * 2


def test_clearance_is_to_the_capsules_surfaces():
    geometry = Arm.of("ur5").geometry
    fat = dataclasses.replace(geometry, radii=tuple(map(float, Arm.of("ur5").capsules().link_radii)))
    q, centre = np.zeros((1, 6)), np.array([0.3, 0.2, 0.4])
    assert np.allclose(link_clearances(fat, q, centre),
                       link_clearances(geometry, q, centre) - np.asarray(fat.radii))


def test_standard_parameters_rebuild_the_same_plant():
    panda = Arm.of("panda")
    parameters = panda.nominal.atom_parameters()
    lower, upper = panda.position_limits
    state = np.random.default_rng(3).uniform(size=(3, 7))
    state[0] = lower + (upper - lower) * state[0]  # inside the limits: no limit forces

    def inverse(model):
        data = mujoco.MjData(model)
        data.qpos[:], data.qvel[:], data.qacc[:] = state
        mujoco.mj_inverse(model, data)
        return data.qfrc_inverse.copy()

    own = inverse(panda.mujoco)
    # a copy: the Arm's model is shared by everything in this process
    assert np.allclose(inverse(set_standard_parameters(copy.deepcopy(panda.mujoco), parameters)), own,
                       rtol=1e-6, atol=1e-6)


def test_replay_on_a_heavier_urdf_spends_more(planned, tmp_path, capsys):
    _, _, plan = planned
    heavy = tmp_path / "heavy.urdf"
    text = (MODELS / "lynxmotion" / "lynxmotion.urdf").read_text()
    heavy.write_text(re.sub(r'<mass value="([0-9.eE+-]+)"',
                            lambda m: f'<mass value="{2 * float(m.group(1))}"', text))
    capsys.readouterr()
    assert main(["replay", "--plan", str(plan), "--out", str(tmp_path / "r.json")]) == 0
    own = json.loads((tmp_path / "r.json").read_text())
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"replayed {plan} on lynxmotion: energy ") and "tracking rms" in line
    assert abs(own["energy_error"]) < 0.02
    assert main(["replay", "--plan", str(plan), "--plant", str(heavy),
                 "--out", str(tmp_path / "h.json")]) == 0
    other = json.loads((tmp_path / "h.json").read_text())
    assert other["plant"] == str(heavy) and other["energy"] > 1.2 * own["energy"]


@pytest.mark.parametrize("extra, message", [
    (["--rate", "100"], "--rate needs --trajectory"),
    (["--trajectory", "T.csv", "--rate", "-5"], "--rate must be a finite number > 0"),
    (["--link-radius", "-1"], "--link-radius must be >= 0"),
    (["--accel-limit", "0"], "--accel-limit must be positive"),
    (["--velocity-limit", "1,2"], "--velocity-limit must be 3"),
])
def test_bad_plan_output_options_one_line(tmp_path, capsys, extra, message):
    out = tmp_path / "plan.json"
    assert main(["plan", "--model", "pinocchio", "--out", str(out), *extra]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_replay_plant_model_without_bodies_one_line(planned, tmp_path, capsys):
    _, _, plan = planned
    model = tmp_path / "model.json"
    model.write_text(json.dumps({"dof": 3, "method": "sparse"}))
    assert main(["replay", "--plan", str(plan), "--plant", str(model),
                 "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert "no per-body inertial parameters" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "r.json").exists()
