"""`identify --refine rollout`: the consistent fit's estimate refined by rollouts, the idea of
Gautier, Janot & Vandanjon's DIDIM (IEEE TCST 2013): the inverse-dynamics (IDIM) estimate is
the start, the direct model's output error the criterion.

The start is the MJCF `export --format mjcf` writes of the model (its bodies, its friction in
MuJoCo's terms, the run's sensor offset in its motors' bias); mujoco.sysid's optimizer
(harness.identify.rollout_fit.fit_rollout: Levenberg-Marquardt on its rollout residual, q and
qd over WINDOW s windows tiling each run's fitted part, from the log's state under its torque)
moves every body's pseudo-inertia (log-Cholesky parameters: every body stays physically
consistent whatever the step), armature, damping, frictionloss and the bias within a region
around the start (rollout_model.NEAR: mass and principal stretches x [0.8, 1.25], centre of
mass +-2 cm, joint terms x [0.5, 2] plus a floor, bias +-1 N m; the toolbox's wide bounds,
the peer's, let the real Panda log's refinement reach 34.9 kg of a 16.8 kg arm and a held-out
torque error of 22.8 on joint 1, 0.118 unrefined: docs/identification.md), the start itself
not moved off them;
stopped at a wall-time budget, the best point evaluated kept. What the MJCF cannot hold (a
sigmoid's shape) stays approximated as the export approximates it; the refined model is the
MJCF, not the torque law in MODEL.json: MODEL.json's 'refined' names it (its path as written and
from MODEL.json's folder), `predict --rollout` rolls it out (harness.replay.rollout.
refined_model), `predict`'s torque stays the torque law's.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from harness.identify.rollout_fit import RolloutFit, Windows, fit_rollout
from harness.identify.rollout_model import NEAR, Region, file_spec
from harness.robots.arm import Arm
from harness.robots.export import export_model
from harness.robots.mjcf_export import full_precision

WINDOW = 0.5  # s, the rollouts compared (the window the fidelity target is judged on)
SECONDS = 60.0  # s of wall time by default (the target: within a minute on a 7-joint arm)
REFINEMENTS = ("none", "rollout")  # identify --refine


def fitted_parts(labels, n_train: int) -> list[tuple[int, int]]:
    """(start, stop) of each run's stretch of the first n_train samples (labels: each
    sample's run), so that no window spans two runs."""
    labels = np.asarray(labels)[:n_train]
    cuts = [0, *(np.flatnonzero(np.diff(labels)) + 1).tolist(), n_train]
    return [(a, b) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]


def refine_rollout(payload: dict, arm: Arm, t, q, qd, tau, parts: list[tuple[int, int]],
                   offset, seconds: float = SECONDS, out: Path | None = None,
                   rollouts: int | None = None, region: Region = NEAR
                   ) -> tuple[RolloutFit, dict]:
    """The model (MODEL.json's payload, a consistent fit) refined on the log's parts (module
    docstring), its sensor offset `offset` (dof,) in the start's bias, for `seconds` of wall
    time or `rollouts` (rollout_fit.BudgetedResidual); out: where to write the refined MJCF.
    Returns the fit and its record for MODEL.json."""
    t = np.ravel(t)
    samples = int(round(WINDOW / np.median(np.diff(t))))
    windows = [Windows(a, b, samples) for a, b in parts if b - a > samples]
    with tempfile.TemporaryDirectory() as folder:
        start = Path(folder) / "start.xml"
        export_model(payload, arm, "mjcf", start, offset=offset)
        spec, bias = file_spec(start)
    fit = fit_rollout(spec, t, q, qd, tau, windows, seconds, False, rollouts, region)
    record = {"method": "rollout", "window_s": WINDOW,
              "budget_s": float(seconds) if np.isfinite(seconds) else None,
              "budget_rollouts": rollouts,
              "start_bias": bias.tolist(), **fit.to_json()}
    if out is not None:
        Path(out).write_text(spec.to_xml())  # spec holds the fit's values (rollout_fit)
        full_precision(str(out), fit.model).write(str(out))
        record["mjcf"] = str(out)
    return fit, record


def refine_command(args, payload: dict, arm: Arm, runs, result, holdout: float) -> list[str]:
    """`identify --refine rollout` (harness.commands.identify): the refined MJCF written to
    --refine-out (default: --out's name, suffix .refined.xml), payload['refined'] added; its
    lines to print. UserError (nothing written) for a model without bodies, a run unevenly
    sampled, a budget that is not positive, or no toolbox."""
    from harness.data.runs import run_times
    from harness.errors import UserError
    from harness.identify.rollout_model import toolbox
    from harness.replay.rollout import log_step
    from harness.robots.inertials import model_standard_parameters
    from identification.closeloop.closed.offsets import held_out_offset

    if model_standard_parameters(payload) is None:
        raise UserError("--refine rollout refines bodies MuJoCo can hold: this fit has none "
                        "(a sparse or feature model); identify with --prior nominal|flat")
    if not args.refine_seconds > 0:
        raise UserError(f"--refine-seconds must be positive, got {args.refine_seconds:g}")
    try:
        toolbox()
    except ImportError as exc:
        raise UserError(f"--refine rollout: {exc}") from None
    data = runs.arrays
    t = np.concatenate([run_times(f, {"q": np.empty(n), "t": times}, meta) for f, meta, n, times
                        in zip(runs.files, runs.metas, runs.lengths,
                               runs.times or (None,) * len(runs.files), strict=True)])
    n_train = int(round(len(t) * (1 - holdout)))  # identify's split
    parts = fitted_parts(runs.labels, n_train)
    for a, b in parts:
        log_step(t[a:b])
    out = Path(args.refine_out) if args.refine_out else Path(args.out).with_suffix(".refined.xml")
    offset = held_out_offset(result.model, np.asarray(result.sensor_offsets()["new_run"], float))
    fit, record = refine_rollout(payload, arm, t, data["q"], data["qd"], data["tau"],
                                 parts, offset, args.refine_seconds, out)
    record["mjcf_from_model"] = os.path.relpath(out.resolve(), Path(args.out).resolve().parent)
    payload["refined"] = record
    return [f"refined by rollouts ({fit.windows} windows of {WINDOW:g} s, {fit.count} "
            f"parameters): cost {fit.cost_start:.4g} -> {fit.cost:.4g}, {fit.stopped} after "
            f"{fit.seconds:.1f} s; wrote {out}"]
