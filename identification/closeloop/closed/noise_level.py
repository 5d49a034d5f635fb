"""Whether what a closed loop leaves is the sensor's noise, said in the command's line.

A loop that names nothing on a clean robot is right, and its error after is then what the
torque sensor's noise alone gives: the noise's standard deviation over the scored torque's
RMS, per joint (the relative error a perfect model would show; a sensor offset is taken out
of every score, so a bias does not count). The noise is the data's declared one where they
declare it (generate's meta 'noise': that fraction of each joint's torque std), else the one
estimated from the residual itself (its second differences, as the unexplained rule uses).
"At its level": within sqrt(1 + LEFT^2) of it on every joint, the unexplained rule's bound.
"""

from __future__ import annotations

import numpy as np

from identification.closeloop.closed.leftover import LEFT
from identification.metrics import error_figures

AT_LEVEL = float(np.sqrt(1.0 + LEFT**2))


def declared_sigma(metas, taus) -> tuple[np.ndarray, float] | None:
    """The torque noise's std per joint (N m) the runs declare, from each run's meta 'noise'
    (a fraction of each joint's torque std in that run, taus: each run's torque, clean where
    known), pooled over the runs; and the fraction. None unless every run declares one."""
    levels = [m.get("noise") for m in metas]
    if not levels or not all(isinstance(x, int | float) and not isinstance(x, bool) and x > 0
                             for x in levels):
        return None
    power = sum(len(t) * (x * np.std(t, axis=0)) ** 2 for x, t in zip(levels, taus, strict=True))
    level = levels[0] if len(set(levels)) == 1 else float("nan")
    return np.sqrt(power / sum(len(t) for t in taus)), level


def relative_floor(sigma, scored_tau) -> np.ndarray:
    """The relative error noise of std sigma (N m per joint) alone gives on scored_tau."""
    return np.asarray(sigma, float) / np.sqrt(np.mean(np.asarray(scored_tau) ** 2, axis=0))


def noise_line(error_after, floor, against: str) -> str | None:
    """'the leftover is at the sensor noise's level ...' when the relative error after is
    within AT_LEVEL of floor (what the noise alone gives) on every joint; else None."""
    error_after, floor = np.asarray(error_after, float), np.asarray(floor, float)
    if not np.all(error_after <= AT_LEVEL * floor):
        return None
    return (f"    the leftover is at the sensor noise's level: error after "
            f"{error_figures(error_after)} against {error_figures(floor)} {against}")


def runs_line(error_after, metas, taus, scored_tau, estimated_sigma) -> str | None:
    """noise_line of a loop on runs: against their declared noise, else the estimated."""
    declared = declared_sigma(metas, taus)
    sigma = estimated_sigma if declared is None else declared[0]
    return noise_line(error_after, relative_floor(sigma, scored_tau),
                      f"that {source_words(declared)} alone gives")


def source_words(declared: tuple[np.ndarray, float] | None) -> str:
    if declared is None:
        return "the noise estimated from the residual (its second differences)"
    level = declared[1]
    return ("the data's declared noise" + (f" ({level:g} of each joint's torque std)"
                                           if np.isfinite(level) else ""))
