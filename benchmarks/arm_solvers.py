"""Solvers side by side on an arm whose planning NLP stays interpreted (not a test).

    .venv/bin/python -m benchmarks.arm_solvers [--robot ur5] [--replans 12]
        [--solvers fatrop,ipopt]

For each solver, in one run: the arm's registered motion with an obstacle crossing a moving
link at mid-time (the bench's arm_planning scenario), one cold plan, then warm re-plans one
obstacle sample apart from the start (each from the previous plan). Prints CPU time of the
planning thread per plan (ms, end to end), the iterations and status of every solve, the
plan's energy and its smallest predicted clearance.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from harness.robots.arm import bench_motion, planner_config
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from planning import solver as planning_solver
from planning.clearance import link_clearances
from planning.replanning import execute, forecast_at, plan_segment
from planning.scenarios import crossing_scenario
from planning.solver import Planner


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--replans", type=int, default=12)
    parser.add_argument("--solvers", default="fatrop,ipopt")
    args = parser.parse_args()
    baseline = PinocchioModel(load_pinocchio(args.robot))
    base, link = bench_motion(args.robot)
    config = planner_config(args.robot, compile_code=False)
    free = execute(Planner(baseline, config), base, avoid=False).segments[0].trajectory
    scenario = crossing_scenario(free, config.geometry, base=base, link=link)
    for name in args.solvers.split(","):
        run(baseline, dataclasses.replace(config, solver=name), scenario, args.replans)


def run(baseline, config, scenario, replans: int) -> None:
    planner, solves = Planner(baseline, config), []
    real = planning_solver.Planner._solve

    def recorded(self, solvers, goal, warm, segment):
        result = real(self, solvers, goal, warm, segment)
        solves.append(f"{result.iterations}:{result.status}")
        return result

    planning_solver.Planner._solve = recorded
    try:
        obstacle, goal, duration = scenario.obstacle, scenario.goal, scenario.duration
        times = obstacle.sample_times
        plan, _, cpu = plan_segment(planner, scenario.start, scenario.start_velocity, 0.0,
                                    duration, goal, forecast_at(obstacle, times[0]))
        print(f"{config.solver}: cold plan {cpu:.0f} ms CPU, solves {solves}")
        warm_cpu = []
        for t in times[:replans]:
            solves.clear()
            q, qd, _ = plan.trajectory.state(t)
            forecast = forecast_at(obstacle, t)
            new, _, cpu = plan_segment(planner, q[0], qd[0], t, duration - t, goal, forecast,
                                       warm=plan)
            warm_cpu.append(cpu)
            clearance = link_clearances(config.geometry, new.trajectory.position(forecast.times),
                                        forecast.centres).min()
            print(f"  t = {t:.2f} s: {cpu:.0f} ms CPU, success {new.success}, energy "
                  f"{new.energy:.4f} J, clearance {clearance:.4f} m, solves {solves}")
            if new.success:
                plan = new
        print(f"{config.solver}: warm re-plans CPU median {np.median(warm_cpu):.0f} ms, max "
              f"{np.max(warm_cpu):.0f} ms over {len(warm_cpu)}")
    finally:
        planning_solver.Planner._solve = real


if __name__ == "__main__":
    main()
