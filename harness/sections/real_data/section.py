"""Bench section "real data": the measured log of a real Franka Emika Panda.

The log shipped with the project (data/panda_gaz2019, Gaz et al. 2019, GPL-3.0) goes
through the user's path: `ingest` (resampled to its median step, qdd from qd by
Savitzky-Golay with the window chosen from the data, handed over at RATE Hz), then

- three models side by side, scored on the last HOLDOUT of the time against the measured
  torque (harness.sections.real_data.models): the nominal URDF model, the least-squares
  reference of the source README recomputed on the same data, and `identify --robot
  panda`; the identified model is judged against the README's reference figures (parsed
  from data/panda_gaz2019/README.md): median over joints of its error ratio <= 1 and no
  joint above MAX_RATIO;
- closing the loop (`closeloop --data`, harness.closeloop.measured): the rigid-body
  identification's residual traced per joint to named effects, added, errors before and
  after held out, joints nothing explains reported.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np

from data import DATA
from harness.closeloop.measured import run_measured
from harness.data.ingest import ingest
from harness.io import write_npz
from harness.sections.real_data.figures import (
    error_figure,
    residual_time_figure,
    residual_velocity_figure,
)
from harness.sections.real_data.models import score_models
from harness.sections.real_data.report import markdown
from identification.metrics import rel_error

LOG = DATA / "panda_gaz2019"
ROBOT = "panda"
RATE = 100.0  # Hz handed over (every 10th resampled sample, as the reference figures use)
HOLDOUT = 0.25
MAX_RATIO = 1.25
FRICTION = ("viscous", "coulomb", "sigmoid")


def readme_reference(name: str) -> list[float]:
    """The per-joint figures of the source README's table row starting with name."""
    for line in (LOG / "README.md").read_text().splitlines():
        if line.startswith(f"| {name}"):
            return [float(x) for x in re.findall(r"\|\s*([0-9.]+)\s*(?=\|)", line)]
    raise ValueError(f"no row '{name}' in {LOG / 'README.md'}")


def run(out_dir: Path, quick: bool = False) -> dict:
    out_dir = Path(out_dir)
    start = time.process_time()
    data = ingest(LOG / "panda_gaz2019.csv.gz", 7, ROBOT, RATE)
    npz = out_dir / "real_data" / "panda_gaz2019.npz"
    write_npz(npz, **data.npz())
    a = data.arrays
    states = (a["q"], a["qd"], a["qdd"])
    models, identification = score_models(ROBOT, *states, a["tau"], HOLDOUT)
    loop = run_measured(npz, ROBOT, HOLDOUT)
    r = loop.loop
    reference = readme_reference("least squares")
    nominal_ref = readme_reference("nominal")
    identified = models["identified"].heldout
    ratio = identified / np.array(reference)
    same_data = identified / models["least_squares"].heldout
    tau = a["tau"]
    nominal_whole = rel_error(models["nominal"].torque, tau)
    before = r.declared.torque(*states)
    after = r.model.torque(*states)
    first = r.path[1][0].split("@")[0] if len(r.path) > 1 else ""
    acceptance = {
        "identified_median_ratio_to_reference_at_most_1": bool(np.median(ratio) <= 1.0),
        f"identified_every_joint_within_{MAX_RATIO}x_reference": bool(np.all(ratio <= MAX_RATIO)),
        "closeloop_friction_named_first": first in FRICTION,
        "closeloop_never_worse_held_out": bool(np.all(r.error_after <= r.error_before)),
        "log_read_from_package_data": str(LOG).startswith(str(DATA)),
    }
    figures_dir = out_dir / "figures"
    errors = {"nominal": models["nominal"].heldout, "least_squares": models["least_squares"].heldout,
              "identified": identified, "rigid_body": r.error_before, "closed_loop": r.error_after}
    figures = [
        error_figure(errors, reference, figures_dir / "real_data_errors.png"),
        residual_time_figure(a["t"] - a["t"][0], tau, {
            "identified": models["identified"].torque, "rigid_body": before,
            "closed_loop": after}, r.split, figures_dir / "real_data_residual_time.png"),
        residual_velocity_figure(tuple(x[:r.split] for x in states), tau[:r.split],
                                 before[:r.split], after[:r.split], r.terms,
                                 figures_dir / "real_data_residual_velocity.png"),
    ]
    seconds = time.process_time() - start
    results = {
        "robot": ROBOT, "log": str(LOG.relative_to(DATA.parent)), "holdout": HOLDOUT,
        "ingest": {k: data.meta[k] for k in ("raw_samples", "samples", "raw_step_s",
                                             "resampling", "derivatives")},
        "reference_least_squares": reference, "reference_nominal_whole_log": nominal_ref,
        "models": {name: {"heldout_rel_rmse": m.heldout, "cpu_s": m.seconds}
                   for name, m in models.items()},
        "nominal_whole_log_rel_rmse": nominal_whole,
        "identified": {"ratio_to_reference": ratio, "median_ratio": float(np.median(ratio)),
                       "max_ratio": float(np.max(ratio)),
                       "ratio_to_least_squares_same_data": same_data,
                       "atoms_kept": int(np.count_nonzero(identification.model.coefficients)),
                       "atoms": len(identification.model.coefficients)},
        "closeloop": loop.to_json(),
        "cpu_s": seconds,
        "acceptance": acceptance,
    }
    results["headline"] = {
        "identified held-out rel err (real Panda)": [float(x) for x in identified],
        "identified / README least squares, median (max)": f"{np.median(ratio):.2f} ({np.max(ratio):.2f})",
        "closed loop held-out rel err before": [float(x) for x in r.error_before],
        "closed loop held-out rel err after": [float(x) for x in r.error_after],
    }
    md = markdown(data.meta, models, reference, nominal_ref, nominal_whole, ratio, same_data,
                  loop, acceptance, seconds, figures)
    return {"markdown": md, "results": results, "figures": [str(p) for p in figures]}
