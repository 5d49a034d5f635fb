"""Error measures shared by identification, the close-the-loop analysis and the report."""

from __future__ import annotations

import numpy as np


def rel_error(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-column (per-joint) relative RMS error ||estimate - truth|| / ||truth||.

    Arrays of shape (n, dof) give a (dof,) array; a column whose truth is zero
    divides by 1e-300 instead (an infinite or zero error, never NaN from 0/0 alone).
    """
    return np.linalg.norm(estimate - truth, axis=0) / np.maximum(
        np.linalg.norm(truth, axis=0), 1e-300)
