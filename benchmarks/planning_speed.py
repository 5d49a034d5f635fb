"""Planner timing on the paper scenario and the crossing scenario (not a test).

    .venv/bin/python -m benchmarks.planning_speed [--model pinocchio|MODEL.json]

Prints cold-plan and warm re-plan times (wall and CPU) for every obstacle sample.
"""

from __future__ import annotations

import argparse
import json
import os

from harness.torque_models import load_torque_model
from planning.replanning import execute
from planning.scenarios import crossing_scenario, paper_scenario
from planning.solver import Planner
from planning.speed import measure


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="pinocchio")
    args = parser.parse_args()
    planner = Planner(load_torque_model(args.model))
    paper = paper_scenario()
    free = execute(planner, paper, avoid=False).segments[0].trajectory
    for name, scenario in (("paper", paper),
                           ("crossing", crossing_scenario(free, planner.config.geometry))):
        timings, _ = measure(planner, scenario)
        summary = {k: round(v, 2) for k, v in timings.summary().items()}
        print(name, json.dumps(summary))
    print("load average", os.getloadavg())


if __name__ == "__main__":
    main()
