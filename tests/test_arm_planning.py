"""`plan` and `replay` on the UR5: an obstacle crossing the forearm of the free optimum at
mid-time is avoided by every link, MuJoCo replays the plan as planned; bad input is one
line, exit 2 and no file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from harness.bench import replay
from harness.cli import main
from harness.plan.arm_config import bench_motion, planner_config
from harness.report.results import Context, SectionResult
from harness.robots.arm import Arm
from planning.formulation.clearance import link_clearances
from planning.penalty.solver import Planner
from planning.replanning import execute
from planning.scenarios import crossing_scenario
from tests.helpers import segments

ROBOT = "ur5"
ARM = Arm.of(ROBOT)


def _csv(values) -> str:
    return ",".join(repr(float(v)) for v in values)


@pytest.fixture(scope="module")
def crossing():
    """The bench's UR5 motion and an obstacle through the middle of its forearm at t = 1 s."""
    base, link = bench_motion(ARM)
    config = planner_config(ARM)
    free = execute(segments(Planner(ARM.nominal, config)), base, avoid=False)
    return crossing_scenario(free.segments[0].trajectory, config.geometry, base=base, link=link)


def _plan_args(scenario, out, **extra) -> list[str]:
    args = {"start": _csv(scenario.start), "goal": _csv(scenario.goal),
            "obstacle-from": _csv(scenario.obstacle.start),
            "obstacle-to": _csv(scenario.obstacle.end), **extra}
    return ["plan", "--robot", ROBOT, "--model", "pinocchio", "--out", str(out),
            *(x for k, v in args.items() for x in (f"--{k}", v))]


@pytest.mark.slow
def test_ur5_plan_avoids_with_every_link_and_replays_as_planned(tmp_path, crossing):
    plan_path, replay_path = tmp_path / "plan.json", tmp_path / "replay.json"
    assert main(_plan_args(crossing, plan_path)) == 0
    plan = json.loads(plan_path.read_text())
    q = np.asarray(plan["q"])
    assert q.shape[1] == 6 and plan["robot"] == ROBOT and plan["replans"] >= 1
    assert plan["closest_link"] == "link 3 (forearm_link)"
    assert plan["end_error"] <= 1e-6
    # every link's capsule (plan's default: fitted to the meshes), recomputed here on the
    # plan's own samples
    geometry = ARM.capsules()
    clearance = link_clearances(geometry, q, np.asarray(plan["obstacle"]))
    assert clearance.shape[1] == 6
    assert clearance.min() >= plan["threshold"] - 2e-3
    np.testing.assert_allclose(clearance.min(axis=0), plan["link_min_clearance"])
    assert main(["replay", "--plan", str(plan_path), "--out", str(replay_path)]) == 0
    replayed = json.loads(replay_path.read_text())
    assert replayed["robot"] == ROBOT and len(replayed["link_min_clearance"]) == 6
    assert replayed["tracking_rms"] <= 1e-3
    assert abs(replayed["energy"] / plan["energy"] - 1) <= 0.02
    assert replayed["min_clearance"] >= plan["threshold"] - 5e-3
    # the bench's replay section on the same plan: its checks, per-link figure
    ctx = Context(ARM, tmp_path, quick=True, video=False,
                  earlier={"planning": SectionResult("", outputs={"plans": {"ur5_pinocchio": plan}})})
    section = replay.run(ctx)
    assert section.checks and all(c.passed for c in section.checks)
    assert any(f.name == "replay_ur5_pinocchio_clearance.png" for f in section.figures)
    assert all(Path(f).is_file() for f in section.figures)


def _potential(model, q) -> float:
    return pin.computePotentialEnergy(model, model.createData(), np.asarray(q, float))


@pytest.mark.slow
def test_ur5_plan_ends_at_rest_and_spends_what_it_descends(tmp_path):
    """Between two poses with the obstacle far away: by default the plan arrives at rest and
    spends at least |V(T) - V(0) + dissipated| (the kinetic energy is zero at both ends);
    with --free-end (the paper's formulation, solved by its penalty loop) it may arrive
    moving."""
    base, _ = bench_motion(ARM)
    args = ["plan", "--robot", ROBOT, "--model", "pinocchio", "--start", _csv(base.start),
            "--goal", _csv(base.goal), "--obstacle-from", "5,5,5", "--obstacle-to", "5,5,6"]
    rest, free = tmp_path / "rest.json", tmp_path / "free.json"
    assert main([*args, "--out", str(rest)]) == 0
    assert main([*args, "--free-end", "--out", str(free)]) == 0
    model = ARM.pinocchio
    for path in (rest, free):
        plan = json.loads(path.read_text())
        t, qd = np.asarray(plan["t"]), np.asarray(plan["qd"])
        p = np.sum(np.asarray(model.damping) * qd**2, axis=1)
        dissipated = float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(t)))
        drop = _potential(model, plan["q"][0]) - _potential(model, plan["q"][-1])
        # the anytime SQP by default; the penalty loop with the paper's free end
        assert plan["replanner"] == ("sqp" if path == rest else "fatrop")
        if path == rest:
            assert np.max(np.abs(qd[-1])) <= 1e-6 and plan["rest_at_goal"] is True
            assert plan["energy"] >= abs(drop - dissipated) - 1e-3, (plan["energy"], drop)
        else:
            assert plan["rest_at_goal"] is False


def _bad_inputs(scenario):
    start = np.asarray(scenario.start)
    points = planner_config(ARM).geometry.points(start)[0]
    elbow = _csv(points[2])  # an obstacle on the elbow joint at t = 0
    return {
        "start outside limits": (dict(start=_csv(start + [0, 0, 3.0, 0, 0, 0])),
                                 "outside the joint limits"),
        "goal with 3 angles": (dict(goal="0.1,0.2,0.3"), "--goal must be 6"),
        "start inside obstacle": ({"obstacle-from": elbow}, "start is inside the obstacle"),
    }


# (a goal the torque limits cannot reach: tests/test_planning_torque.py, on the Lynxmotion;
# the same code path, where the failing IPOPT search is 5x cheaper than on the UR5)
@pytest.mark.parametrize("case", ["start outside limits", "goal with 3 angles",
                                  "start inside obstacle"])
def test_ur5_bad_input_is_one_line_exit_2_no_plan(tmp_path, capsys, crossing, case):
    extra, message = _bad_inputs(crossing)[case]
    out = tmp_path / "plan.json"
    assert main(_plan_args(crossing, out, **extra)) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_other_robot_needs_its_own_angles(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert main(["plan", "--robot", "double_pendulum", "--model", "pinocchio", "--out",
                 str(out)]) == 2  # no registered motion
    assert not out.exists()
    err = capsys.readouterr().err.strip()  # both missing options named in one line
    assert "--start and --goal are needed on robot double_pendulum" in err and ": 2 " in err
    assert len(err.splitlines()) == 1
    assert main(["plan", "--robot", "double_pendulum", "--model", "pinocchio", "--goal", "0,0",
                 "--out", str(out)]) == 2
    assert "--start is needed on robot double_pendulum" in capsys.readouterr().err


def test_another_robot_past_the_default_obstacle_is_told_so(tmp_path, capsys):
    """A plan of another robot with no obstacle options goes past the Lynxmotion paper
    scenario's obstacle path: written, with one note that it is not the robot's; with the
    options given, no note."""
    out = tmp_path / "plan.json"
    angles = ["--start", "0.2,0.1", "--goal", "1.0,-0.5"]
    assert main(["plan", "--no-compile", "--robot", "double_pendulum", "--model", "pinocchio",
                 *angles, "--out", str(out)]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("note:")]
    assert out.exists() and len(err) == 1 and "--obstacle-from" in err[0]
    assert "from (0.15, 0.4, 0.22) to (0.18, -0.35, 0.28) m" in err[0]  # where it is
    assert main(["plan", "--no-compile", "--robot", "double_pendulum", "--model", "pinocchio",
                 *angles, "--obstacle-from", "0.3,0.3,0.5", "--obstacle-to", "0.3,0.3,0.9",
                 "--out", str(tmp_path / "own.json")]) == 0
    assert "note:" not in capsys.readouterr().err
