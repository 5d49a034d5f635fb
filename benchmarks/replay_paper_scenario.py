"""Plan the paper's scenario once with the closed-form model, then replay it in MuJoCo.

    python benchmarks/replay_paper_scenario.py [--plant MJCF] [--out PLAN.json]

A stand-alone check of the replay acceptance (tracking RMS <= 1 mrad, energy
within 2 % of planned, clearance >= lambda - 5 mm) on a real IPOPT plan: one
cold solve with the whole obstacle path known (no re-planning), sampled at the
200 obstacle sample times plus t = 0. Prints the plan's and the replay's numbers.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict

import numpy as np

from harness.io import write_json
from harness.replay.reference import plan_reference
from harness.replay.simulate import replay
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, load_mujoco, load_pinocchio
from planning.clearance import link_clearances
from planning.config import PlannerConfig, Scenario
from planning.solver import ObstacleForecast, Planner


def paper_plan(model, config: PlannerConfig | None = None, scenario: Scenario | None = None):
    """PLAN.json-shaped dict of one cold solve of the paper's scenario."""
    config, scenario = config or PlannerConfig(), scenario or Scenario()
    obstacle = scenario.obstacle
    forecast = ObstacleForecast(obstacle.sample_times, obstacle.position(obstacle.sample_times))
    segment = Planner(model, config).solve(
        np.array(scenario.start), np.array(scenario.start_velocity), scenario.duration,
        np.array(scenario.goal), forecast)
    t = np.concatenate([[0.0], obstacle.sample_times])
    q, qd, qdd = segment.trajectory.state(t)
    centres = obstacle.position(t)
    clearance = link_clearances(config.geometry, q, centres)
    return {
        "coefficients": segment.trajectory.coefficients, "t": t, "q": q, "qd": qd, "qdd": qdd,
        "obstacle": centres, "threshold": config.threshold, "energy": segment.energy,
        "min_clearance": float(np.min(clearance)), "replans": 0,
        "solve_ms": [segment.solve_ms], "status": segment.status, "penalty": segment.penalty,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plant", default=DEFAULT_ROBOT)
    parser.add_argument("--out", default=None, help="also write the plan here")
    args = parser.parse_args()
    closed_form = PinocchioModel(load_pinocchio(DEFAULT_ROBOT))
    plan = paper_plan(closed_form)
    if args.out:
        write_json(args.out, plan)
    result, _ = replay(load_mujoco(args.plant, scene=True), plan_reference(plan), closed_form)
    summary = {k: plan[k] for k in ("energy", "min_clearance", "solve_ms", "status", "penalty")}
    print(json.dumps({"plan": summary, "replay": {**asdict(result),
                                                   "energy_error": result.energy_error}},
                     indent=2, default=float))


if __name__ == "__main__":
    main()
