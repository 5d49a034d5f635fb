"""The measured loop's rules for naming an effect (identification.closeloop.selection.runs): the gains
it needs, on every joint of every held-out run, the agreement between runs, its physical
range (identification.closeloop.verdicts.ranges), and what is said of a candidate left out."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm
from identification.closeloop.selection.crossval import weighted_fit
from identification.closeloop.verdicts.ranges import Scales
from identification.intervals import jackknife

MIN_GAIN = 0.02  # an effect must cut its joint's validation error power by >= 2 %
AGREE = 3.0  # combined standard errors within which two runs' coefficients agree
RUN_BLOCKS = 4  # blocks of a run whose coefficients' spread gives the run's uncertainty


def rows_of(term: EffectTerm, dof: int) -> list[int]:
    return list(range(dof)) if term.effect in ("inertial", "payload") else [term.joint - 1]


def per_run(base, target, cols, w, runs: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Each run's coefficients of the last column (joint fit on the run alone) and their
    standard errors: a delete-one-block jackknife over the run's time blocks
    (identification.intervals; fits of short blocks alone were noisy enough to
    call one load's two runs apart one time in three on coloured residuals)."""
    coef, std = [], []
    for rows in runs:
        coef.append(weighted_fit(base[rows], target[rows], cols[rows], w)[1][-1])
        thetas, _ = jackknife(lambda r: weighted_fit(base[r], target[r], cols[r], w)[1][-1:],
                              [rows])
        b = len(thetas)
        std.append(float(np.sqrt((b - 1) / b * np.sum((thetas - thetas.mean()) ** 2))))
    return np.array(coef), np.array(std)


def agree(coef: np.ndarray, std: np.ndarray) -> bool:
    diff = np.abs(coef[:, None] - coef[None, :])
    return bool(np.all(diff <= AGREE * np.hypot(std[:, None], std[None, :]) + 1e-12))


def verdict(term, fold_gains, coef, per_run, per_run_std, several, scales: Scales) -> str:
    """Why a candidate that improves validation is not named ('' if it is): fold_gains
    (folds, joints it acts on), the fraction of each held-out run's error power on each of
    its joints it removes."""
    if several and np.min(fold_gains) < 0:
        run, joint = np.unravel_index(int(np.argmin(fold_gains)), np.shape(fold_gains))
        joints = rows_of(term, len(scales.torque))
        return f"makes joint {joints[joint] + 1} of held-out run {run + 1} worse"
    why = scales.why_not(replace(term, coefficient=float(coef)))
    if why:
        return why
    if several and not agree(per_run, per_run_std):
        return ("coefficients differ between runs beyond their uncertainty: "
                + ", ".join(f"{c:.3g} +- {s:.2g}" for c, s in zip(per_run, per_run_std,
                                                                strict=True)))
    return ""


def best_left(terms, gains) -> list[tuple[int, int, float]]:
    """Per joint, in joint order, the candidate with the largest gain among gains [(gain,
    index into terms)]: (joint, index, gain)."""
    best: dict[int, tuple] = {}
    for gain, i in gains:
        j = terms[i].joint
        if j not in best or gain > best[j][1]:
            best[j] = (i, gain)
    return [(j, *best[j]) for j in sorted(best)]


def not_named(terms, chosen, rejected, trials) -> tuple[tuple[int, str, float, str], ...]:
    """Per joint, the best candidate left when selection stopped, its gain and why."""
    out = []
    for j, i, gain in best_left(terms, ((t[1], t[2]) for t in trials)):
        why = rejected[i][1] if i in rejected and gain >= MIN_GAIN else (
            f"cuts the validation error power by {gain:.1%} < {MIN_GAIN:.0%}")
        out.append((j, terms[i].effect, float(gain), why))
    return tuple(out)
