"""Planner timing on the paper, crossing and swaying scenarios (not a test).

    .venv/bin/python -m benchmarks.planning_speed [--model pinocchio|MODEL.json]
        [--degree 4] [--energy-quadrature paper|gauss|simpson] [--energy-samples 10]
        [--solver fatrop|sqpmethod|ipopt] [--compile]

Prints cold-plan and warm re-plan times (wall and CPU) for every obstacle sample, and
the re-plans Algorithm 2 makes against the swaying obstacle.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os

import numpy as np

from harness.robots.torque_models import load_torque_model
from planning.backends import SOLVERS
from planning.config import PlannerConfig
from planning.quadrature import RULES
from planning.replanning import execute
from planning.scenarios import crossing_scenario, paper_scenario, swaying_scenario
from planning.solver import Planner
from planning.speed import measure
from planning.variants import Parametrization


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="pinocchio")
    parser.add_argument("--degree", type=int, default=4)
    parser.add_argument("--energy-quadrature", choices=RULES, default="paper")
    parser.add_argument("--energy-samples", type=int, default=10)
    parser.add_argument("--solver", choices=SOLVERS, default=PlannerConfig.solver)
    parser.add_argument("--compile", action="store_true", help="compiled NLP functions")
    args = parser.parse_args()
    variant = Parametrization("cli", args.degree, args.energy_quadrature, args.energy_samples)
    base = dataclasses.replace(PlannerConfig(), solver=args.solver, compile_code=args.compile)
    planner = Planner(load_torque_model(args.model), variant.config(base))
    paper = paper_scenario()
    free = execute(planner, paper, avoid=False).segments[0].trajectory
    geometry = planner.config.geometry
    for name, scenario in (("paper", paper), ("crossing", crossing_scenario(free, geometry))):
        timings, _ = measure(planner, scenario)
        summary = {k: round(v, 2) for k, v in timings.summary().items()}
        print(name, json.dumps(summary))
    sway = execute(planner, swaying_scenario(free, geometry))
    replan_ms = np.asarray(sway.solve_ms[1:])
    print("swaying", json.dumps({"replans": len(sway.segments) - 1,
                                 "failures": len(sway.replan_failures),
                                 "replan_median_ms": round(float(np.median(replan_ms)), 2),
                                 "replan_p95_ms": round(float(np.percentile(replan_ms, 95)), 2)}))
    print("load average", os.getloadavg())


if __name__ == "__main__":
    main()
