"""The paper's scenario end to end, bad input, and the `plan` command."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from harness.cli import main
from harness.robots.arm import Arm
from planning.config import PenaltyOptions
from planning.errors import PlanningError
from planning.formulation.energy import absolute_energy
from planning.penalty.solver import Planner
from planning.replanning import execute
from planning.result import evaluate
from planning.types import Segment
from tests.helpers import lynx_config, lynx_scenario, perturbed_model, segments


@pytest.fixture(scope="module")
def baseline():
    return Arm.of("lynxmotion").nominal


@pytest.fixture(scope="module")
def paper(baseline):
    planner = Planner(baseline, lynx_config())
    scenario = lynx_scenario()
    free = evaluate(execute(segments(planner), scenario, avoid=False), scenario, baseline, planner.config)
    avoided = evaluate(execute(segments(planner), scenario), scenario, baseline, planner.config)
    return planner, scenario, free, avoided


def test_paper_scenario_reaches_goal_and_keeps_clearance(paper):
    planner, scenario, free, avoided = paper
    assert avoided.feasible, avoided.problems
    assert avoided.end_error <= 1e-6
    needed = free.sample_clearance < planner.config.threshold
    assert needed.any()  # the unobstructed optimum would pass too close
    assert np.all(avoided.sample_clearance[needed] >= planner.config.threshold - 2e-3)
    assert len(avoided.execution.segments) >= 2  # Algorithm 2 re-planned
    assert avoided.limit_violation <= 1e-6


def test_executed_trajectory_is_continuous_at_replans(paper):
    _, _, _, avoided = paper
    segments = avoided.execution.segments
    for previous, segment in zip(segments, segments[1:], strict=False):
        t = segment.trajectory.t_begin
        for old, new in zip(previous.trajectory.state(t)[:2], segment.trajectory.state(t)[:2],
                            strict=True):
            assert np.allclose(old, new, atol=1e-12)  # same position and velocity
    assert np.max(np.abs(np.diff(avoided.q, axis=0))) < 0.05  # no jumps on the 2 ms grid


def test_stand_in_model_energy_close_to_baseline(paper, baseline):
    """A model perturbed body by body (masses, centres of mass, inertias: 5 %, 5 mm) plans
    another motion; under the true model it spends within 2 % of the true optimum and
    keeps the clearance."""
    planner, scenario, _, reference = paper
    model = perturbed_model()
    result = evaluate(execute(segments(Planner(model, lynx_config())), scenario), scenario, model,
                      planner.config)
    assert result.feasible, result.problems
    assert np.max(np.abs(result.q - reference.q)) > 1e-3  # another plan, not the same one
    energy = absolute_energy(baseline, result.t, result.q, result.qd, result.qdd)
    assert abs(energy - reference.energy) / reference.energy < 0.02


@pytest.mark.parametrize("change, message", [
    ({"goal": (2.0, 1.0, -1.0)}, "outside the joint limits"),
    ({"duration": 0.0}, "duration must be > 0"),
    ({"duration": -1.0}, "duration must be > 0"),
    ({"start": (np.nan, 0.5, -0.5)}, "finite"),
])
def test_bad_input_is_an_error(baseline, change, message):
    scenario = dataclasses.replace(lynx_scenario(obstacle=None), **change)
    with pytest.raises(PlanningError, match=message):
        execute(segments(Planner(baseline, lynx_config())), scenario)


def test_start_inside_threshold_is_an_error(paper):
    planner, scenario, _, _ = paper
    obstacle = dataclasses.replace(scenario.obstacle, start=(0.0, 0.15, 0.2))
    with pytest.raises(PlanningError, match="inside the obstacle threshold"):
        execute(segments(planner), dataclasses.replace(scenario, obstacle=obstacle))


def test_solver_failure_is_flagged(baseline):
    # no solve may finish: cold and warm capped, no IPOPT rescue (it has its own warm cap)
    config = lynx_config(penalty=PenaltyOptions(max_iterations=2, warm_max_iterations=2,
                                                   solver="ipopt"))
    scenario = lynx_scenario()
    result = evaluate(execute(segments(Planner(baseline, config)), scenario), scenario, baseline, config)
    assert not result.feasible
    assert any("solver failed" in p for p in result.problems)


def test_plan_command_writes_the_contract(tmp_path):
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    for key in ("coefficients", "t", "q", "qd", "qdd", "obstacle", "threshold", "energy",
                "min_clearance", "replans", "solve_ms"):
        assert key in plan
    t = np.asarray(plan["t"])
    assert len(t) == len(plan["q"]) == len(plan["obstacle"])
    samples = 2.0 * np.arange(1, 201) / 200
    assert np.all(np.min(np.abs(t[:, None] - samples[None]), axis=0) < 1e-12)
    assert plan["replans"] == len(plan["coefficients"]) - 1
    # one entry per solve: the plans followed, failed re-plans, and a bank's re-plans of its
    # other classes only (the arm going on as it was)
    kept = plan["bank"]["kept"] if plan["bank"] else 0
    assert len(plan["solve_ms"]) == plan["replans"] + 1 + len(plan["replan_failures"]) + kept


def test_plan_command_bad_input_exits_2_without_file(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--goal", "0,4,-1", "--out", str(out)]) == 2
    assert not out.exists()
    assert "outside the joint limits" in capsys.readouterr().err
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--replan-iterations", "-1",
                 "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "--replan-iterations must be >= 0" in err and len(err.strip().splitlines()) == 1
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--replanner", "sqp",
                 "--replan-budget-ms", "0", "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "--replan-budget-ms must be" in err and len(err.strip().splitlines()) == 1
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--warm-radius", "nan",
                 "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "--warm-radius must be" in err and len(err.strip().splitlines()) == 1
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--settle-horizon", "-0.1",
                 "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "--settle-horizon must be" in err and len(err.strip().splitlines()) == 1


def test_plan_command_with_the_anytime_sqp(tmp_path):
    """plan --replanner sqp writes a feasible plan of the paper scenario, recording it."""
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--replanner", "sqp",
                 "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["replanner"] == "sqp" and plan["feasible"]
    assert plan["min_clearance"] >= plan["threshold"] - 2e-3


def test_an_infeasible_anytime_plan_says_what_its_re_plans_had(tmp_path, capsys):
    """Re-plans with 0.01 ms of CPU follow the first plan into the moving obstacle: exit 2,
    no file, one error line that names the budget and what may find a plan. The global search
    off: under --realtime its worker, ready from the first plan, may offer the way out."""
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--replanner", "sqp",
                 "--realtime", "--replan-budget-ms", "0.01", "--no-global-search",
                 "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no feasible plan: clearance" in err
    assert "within 0.01 ms of CPU" in err and "--replanner fatrop" in err


def test_obstacle_parked_on_the_goal_is_flagged(paper, baseline):
    planner, scenario, _, _ = paper
    tip = planner.config.geometry.flange_position(np.asarray([scenario.goal]))
    parked = dataclasses.replace(scenario.obstacle, start=tuple(tip[0]), end=tuple(tip[0]))
    blocked = dataclasses.replace(scenario, obstacle=parked)
    result = evaluate(execute(segments(planner), blocked), blocked, baseline, planner.config)
    assert not result.feasible
    # the closest approach is the flange's (on the last link) at the goal, at the end: the
    # problem names that link, that time and the clearance reached
    found = [re.search(r"clearance (-?[0-9.]+) m < .* \(link '(.+?)' at t = ([0-9.]+) s\)", p)
             for p in result.problems]
    clearance, link, t = next(f.groups() for f in found if f)
    assert link == planner.config.geometry.link_names[-1]
    assert float(t) == pytest.approx(scenario.duration, abs=1e-9)
    assert float(clearance) == pytest.approx(-planner.config.geometry.link_radii[-1], abs=1e-4)


def test_warm_replan_finds_the_cold_optimum(paper, baseline):
    """Warm starting changes the solve time, not the answer."""
    planner, scenario, _, avoided = paper
    from planning.penalty.loop import plan_segment
    from planning.replanning import forecast_at

    plan, t = avoided.execution.segments[-1], 0.5
    q, qd, _ = plan.trajectory.state(t)
    segment = Segment(q[0], qd[0], t, scenario.duration - t, scenario.goal,
                      forecast_at(scenario.obstacle, t))
    warm, _, _ = plan_segment(planner, segment, warm=plan)
    cold, _, _ = plan_segment(planner, segment)
    assert warm.success and cold.success
    assert np.isclose(warm.energy + warm.penalty, cold.energy + cold.penalty, rtol=1e-6)
    assert np.allclose(warm.trajectory.coefficients, cold.trajectory.coefficients, atol=1e-4)


def test_rest_at_goal_on_a_joint_limit(baseline):
    """The paper's goal has q1 on its lower limit; arriving at rest there stays inside."""
    config = lynx_config(rest_at_goal=True)
    scenario = lynx_scenario()
    result = evaluate(execute(segments(Planner(baseline, config)), scenario), scenario, baseline, config)
    assert result.feasible, result.problems
    assert np.allclose(result.qd[-1], 0.0, atol=1e-8)
    assert result.limit_violation <= 1e-9


def test_crossing_obstacle_is_avoided_at_every_sample(paper, baseline):
    """An obstacle through the forearm of the unobstructed optimum at t = 1 s: the plan
    detours and holds the threshold at every one of the K samples (not one instant)."""
    from planning.scenarios import crossing_scenario

    planner, _, free, _ = paper
    crossing = crossing_scenario(free.execution.segments[0].trajectory, planner.config.geometry,
                                 lynx_scenario())
    blind = evaluate(execute(segments(planner), crossing, avoid=False), crossing, baseline, planner.config)
    result = evaluate(execute(segments(planner), crossing), crossing, baseline, planner.config)
    needed = blind.sample_clearance < planner.config.threshold
    assert needed.sum() > 20 and blind.sample_clearance.min() < 1e-6  # it really crosses
    assert result.feasible, result.problems
    assert np.all(result.sample_clearance >= planner.config.threshold - 2e-3)
    assert result.energy > blind.energy  # the detour costs energy


def test_penalty_weight_rises_until_the_threshold_holds(paper, baseline):
    """Exterior penalty method: a weak alpha is raised; without raising it the plan fails."""
    from planning.scenarios import crossing_scenario

    planner, _, free, _ = paper
    crossing = crossing_scenario(free.execution.segments[0].trajectory, planner.config.geometry,
                                 lynx_scenario())
    results = {}
    for ceiling in (2.0, 2e5):
        config = lynx_config(penalty_weight=2.0, penalty=PenaltyOptions(max_weight=ceiling))
        results[ceiling] = evaluate(execute(segments(Planner(baseline, config)), crossing), crossing,
                                    baseline, config)
    assert not results[2.0].feasible
    held = results[2e5]
    assert held.feasible, held.problems
    assert max(s.penalty_weight for s in held.execution.segments) > 2.0


def test_plan_command_takes_vectors_starting_with_a_minus(tmp_path):
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--goal", "-1.0,1.0,-1.2",
                 "--obstacle-from", "-0.1,0.3,0.2", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert np.allclose(plan["q"][-1], [-1.0, 1.0, -1.2], atol=1e-6)
    assert np.allclose(plan["obstacle"][0], [-0.1, 0.3, 0.2])


def test_a_detour_the_obstacle_has_left_is_replanned(paper, baseline):
    """The first plan bends round the obstacle where it stands at t = 0; the obstacle then
    leaves upwards. The first plan stays clear (Algorithm 2 alone would follow it to the
    end), yet its detour is wasted energy: the planner re-plans and spends less."""
    from planning.formulation.clearance import predicted_clearance
    from planning.formulation.obstacle import LinearObstacle
    from planning.replanning import forecast_at

    planner, scenario, free, _ = paper
    t_mid = 0.5 * scenario.duration
    tip = planner.config.geometry.flange_position(free.execution.segments[0].trajectory
                                                    .position(np.asarray([t_mid])))[0]
    leaving = LinearObstacle(start=tuple(tip), end=tuple(tip + [0.0, 0.0, 1.5]),
                             duration=scenario.duration)
    case = dataclasses.replace(scenario, obstacle=leaving)
    followed = execute(segments(planner), case, replan=False)
    first = followed.segments[0]
    assert first.penalty > 0.0  # bent round the obstacle standing still
    moving = forecast_at(leaving, leaving.sample_times[0])
    assert predicted_clearance(planner.config.geometry, first.trajectory, moving) > \
        planner.config.threshold  # no threat
    replanned = execute(segments(planner), case)
    assert len(replanned.segments) >= 2
    energy = {name: evaluate(run, case, baseline, planner.config)
              for name, run in (("followed", followed), ("replanned", replanned))}
    assert energy["replanned"].feasible, energy["replanned"].problems
    assert energy["replanned"].energy < 0.9 * energy["followed"].energy
