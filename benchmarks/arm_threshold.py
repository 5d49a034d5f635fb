"""The keep threshold of the kinematic-library identification, measured side by side.

For each arm, 10 draws at 5 % noise (generate(robot, 4000, 0.05, seed), first 75 % trains);
the identified model with |t| bounds c = 1 (the default, identification.identify.KEEP_T)
and c = sqrt(2) (Akaike), and the oracle (harness.sections.arm_identification.oracle_design),
all judged on one fresh trajectory against its clean torque. Prints per draw the number of
atoms kept, the median over joints and the worst joint of the ratio to the oracle.

    python benchmarks/arm_threshold.py ur5 panda
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import identification.identify as identification  # noqa: E402
from harness.data.generate import generate  # noqa: E402
from harness.robots.baseline import PinocchioModel  # noqa: E402
from harness.robots.registry import load_pinocchio  # noqa: E402
from harness.robots.torque_models import robot_library  # noqa: E402
from harness.sections.arm_identification import (  # noqa: E402
    FRESH_SEED,
    HOLDOUT,
    NOISE,
    SAMPLES,
    oracle_design,
)
from identification.metrics import rel_error  # noqa: E402
from identification.regression.oracle import BaseParameterRegression  # noqa: E402

BOUNDS = (1.0, float(np.sqrt(2.0)))


def main(robots: list[str]) -> None:
    default = identification.KEEP_T
    for robot in robots:
        library, baseline = robot_library(robot), PinocchioModel(load_pinocchio(robot))
        fresh = generate(robot, SAMPLES, 0.0, FRESH_SEED, "inverse")
        design_fresh = oracle_design(baseline, fresh.q, fresh.qd, fresh.qdd)
        n = int(round(SAMPLES * (1 - HOLDOUT)))
        for seed in range(1, 11):
            d = generate(robot, SAMPLES, NOISE, seed, "inverse")
            oracle = BaseParameterRegression().fit(
                oracle_design(baseline, d.q[:n], d.qd[:n], d.qdd[:n]), d.tau[:n])
            ref = rel_error(oracle.predict(design_fresh), fresh.tau_clean)
            row = []
            for c in BOUNDS:
                identification.KEEP_T = c
                model = identification.identify(d.q, d.qd, d.qdd, d.tau, library, HOLDOUT).model
                r = rel_error(model.torque(fresh.q, fresh.qd, fresh.qdd), fresh.tau_clean) / ref
                row.append(f"c={c:.2f}: {np.count_nonzero(model.coefficients)} atoms, median "
                           f"{np.median(r):.2f}, worst joint {r.max():.2f}")
            identification.KEEP_T = default
            print(f"{robot} draw {seed}: " + " | ".join(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or ["ur5", "panda"])
