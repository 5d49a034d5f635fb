"""Real time and true optimum over random scenarios: the planning bench's study, alone.

    .venv/bin/python -m harness.studies.realtime.ways [--scenarios 20] [--seed 2026]
        [--ways all|fast] [--free-end] [--out study.json]

`--ways fast` compares only the two re-planners (the penalty loop with fatrop and the
anytime elastic SQP; no other compiled variants: each costs one C compilation on first use).
Prints the study's markdown (as in the bench report) and the load average.
"""

from __future__ import annotations

import json
import os

from harness.io import write_json
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from harness.studies.realtime import measure as realtime
from harness.studies.realtime import options as random_scenarios
from harness.studies.realtime import tables


def main() -> None:
    parser = random_scenarios.parser(__doc__)
    parser.add_argument("--ways", choices=("all", "fast"), default="all")
    parser.add_argument("--out", default=None)
    parser.add_argument("--free-end", action="store_true",
                        help="plan with the paper's free end velocity (default: at rest)")
    args = parser.parse_args()
    changes = {"rest_at_goal": False} if args.free_end else {}
    baseline = Arm.of(DEFAULT_ROBOT).nominal
    setup = random_scenarios.setup(args)
    ways = None
    if args.ways == "fast":
        ways = realtime.fast_ways(realtime.study_config(True, **changes))
    study = realtime.run(baseline, Arm.of(DEFAULT_ROBOT).scene, False, setup, ways,
                         **changes)
    print("\n".join(tables.markdown_lines(study)))
    print(json.dumps(tables.acceptance(study)))
    print("load average", os.getloadavg())
    if args.out:
        write_json(args.out, study)


if __name__ == "__main__":
    main()
