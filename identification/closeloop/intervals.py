"""Intervals that hold on coloured residuals: a named coefficient's 95 % interval from a
delete-one-block jackknife over contiguous time blocks of every run.

A real residual is coloured by what the model lacks, so the white-noise covariance of a
least-squares fit understates its spread several times over (issue #67: drive gains printed
+- 0.3-1.7 % moved 1-19 % between runs). Deleting one contiguous block at a time keeps the
residual's correlation inside each block: with B blocks and theta_(i) the fit without block
i, var = (B - 1) / B sum (theta_(i) - mean)^2, and the half-width is Student's t(0.975, B - 1)
times its root. The blocks are BLOCKS per run, so the runs' differences (a sensor offset, a
warm-up) enter the spread too.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import t as student

BLOCKS = 8  # contiguous blocks of each run
LEVEL = 0.95
RULE = (f"delete-one-block jackknife over {BLOCKS} contiguous time blocks of every run (the "
        "residual's correlation within a block kept), Student's t, 95 %")


def jackknife(fit: Callable[[np.ndarray], np.ndarray], runs: list[np.ndarray],
              blocks: int = BLOCKS) -> tuple[np.ndarray, np.ndarray]:
    """(the fits without each block (B, k), the 95 % half-width of each coefficient (k,)):
    fit(rows) -> (k,) coefficients on the sample indices rows; runs: each run's indices."""
    every = np.concatenate(runs)
    folds = [block for rows in runs for block in np.array_split(rows, blocks) if len(block)]
    thetas = np.array([fit(np.setdiff1d(every, block, assume_unique=True)) for block in folds])
    thetas = thetas[np.all(np.isfinite(thetas), axis=1)]  # a fold whose fit failed
    b = len(thetas)
    if b < 3:
        return thetas, np.full(thetas.shape[1], np.nan)
    spread = np.sqrt((b - 1) / b * np.sum((thetas - thetas.mean(axis=0)) ** 2, axis=0))
    return thetas, student.ppf(0.5 + LEVEL / 2, b - 1) * spread
