"""Intervals that hold on coloured residuals: a coefficient's 95 % interval from a
delete-one-block jackknife over contiguous time blocks of every run.

A real residual is coloured by what the model lacks, so the white-noise covariance of a
least-squares fit understates its spread several times over (drive gains printed
+- 0.3-1.7 % moved 1-19 % between runs). Deleting one contiguous block at a time keeps the
residual's correlation inside each block: with B blocks and theta_(i) the fit without block
i, var = (B - 1) / B sum (theta_(i) - mean)^2, and the half-width is Student's t(0.975, B - 1)
times its root. The blocks are BLOCKS per run, so the runs' differences (a sensor offset, a
warm-up) enter the spread too. Used by the measured loop's named effects and payload
(identification.closeloop) and by the drive gains (identification.drive_gains).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import t as student

BLOCKS = 8  # contiguous blocks of each run
LEVEL = 0.95


def rule(blocks: int = BLOCKS) -> str:
    """How the intervals were computed, for a report."""
    return (f"delete-one-block jackknife over {blocks} contiguous time blocks of every run (the "
            "residual's correlation within a block kept), Student's t, 95 %")


RULE = rule()


def time_blocks(runs: list[np.ndarray], blocks: int = BLOCKS) -> list[np.ndarray]:
    """The contiguous blocks (sample indices) the jackknife deletes one at a time: `blocks`
    per run; runs: each run's sample indices in time order."""
    return [block for rows in runs for block in np.array_split(rows, blocks) if len(block)]


def half_width(thetas: np.ndarray) -> np.ndarray:
    """(k,) the 95 % half-width of each coefficient from its delete-one-block fits
    thetas (B, k); folds whose fit failed (a non-finite row) are dropped; NaN under 3 folds."""
    thetas = thetas[np.all(np.isfinite(thetas), axis=1)]
    b = len(thetas)
    if b < 3:
        return np.full(thetas.shape[1], np.nan)
    spread = np.sqrt((b - 1) / b * np.sum((thetas - thetas.mean(axis=0)) ** 2, axis=0))
    return student.ppf(0.5 + LEVEL / 2, b - 1) * spread


def jackknife(fit: Callable[[np.ndarray], np.ndarray], runs: list[np.ndarray],
              blocks: int = BLOCKS) -> tuple[np.ndarray, np.ndarray]:
    """(the fits without each block (B', k), the 95 % half-width of each coefficient (k,)):
    fit(rows) -> (k,) coefficients on the sample indices rows; runs: each run's indices.
    Folds whose fit failed (non-finite) are dropped from both."""
    every = np.concatenate(runs)
    thetas = np.array([fit(np.setdiff1d(every, block, assume_unique=True))
                       for block in time_blocks(runs, blocks)])
    return thetas[np.all(np.isfinite(thetas), axis=1)], half_width(thetas)
