"""What the robot itself adds to the observer's estimate: its persistent effects, functions of
its state (friction, a payload, a spring or tendon, a scale error of the drive gains), removed
per joint by a robust fit (Tukey's bisquare, iteratively reweighted) on the same low-pass of
state columns, so that what is left is what no function of the state explains.
"""

from __future__ import annotations

import numpy as np

BISQUARE = 4.685  # Tukey's constant (95 % efficiency at Gaussian residuals)
FRICTION_WIDTH = 0.02  # rad/s, the dry-friction column's tanh width
SUPPORT = 0.1  # a column's spread where the fit is made, of its spread over the run


def state_columns(model, q, qd, qdd, body=None, pose: bool = True) -> list[np.ndarray]:
    """Per joint j, the (n, k) torques of the persistent effects the detection removes: an
    offset, viscous and dry friction, the declared torque's scale, a smooth function of the
    arm's pose (every joint's q, sin q and cos q: a spring, a tendon, a gravity error), and,
    with body (a callable (q, qd, qdd) -> (n, dof, 10), the load's body's regressor), its ten
    parameters' torque on j; pose=False: without the function of the pose."""
    declared = model.torque(q, qd, qdd)
    shape = np.concatenate([q, np.sin(q), np.cos(q)], axis=1)
    load = None if body is None else np.asarray(body(q, qd, qdd), float)
    out = []
    for j in range(q.shape[1]):
        own = np.stack([np.ones(len(q)), qd[:, j], np.tanh(qd[:, j] / FRICTION_WIDTH),
                        declared[:, j]], axis=1)
        parts = [own] + ([shape] if pose else []) + ([] if load is None else [load[:, j, :]])
        out.append(np.concatenate(parts, axis=1))
    return out


def robust_scale(x: np.ndarray) -> np.ndarray:
    med = np.median(x, axis=0)
    return np.maximum(1.4826 * np.median(np.abs(x - med), axis=0), 1e-12)


def persistent_residual(r: np.ndarray, cols: list[np.ndarray], use: np.ndarray,
                        iterations: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """r minus, per joint, its bisquare fit on that joint's columns (both low-passed alike),
    fitted on the samples use; returns that residual (n, dof) and its robust scale (dof,) on
    those samples. A column whose spread over the samples use is below SUPPORT of its spread
    over the whole run is left out: a function fitted where the state hardly moves (an arm
    held still) is not extrapolated to where it does (the same arm deflected by a push)."""
    res = np.empty_like(r)
    for j, X in enumerate(cols):
        spread = np.std(X, axis=0)
        X = X[:, (np.std(X[use], axis=0) >= SUPPORT * spread) | (spread == 0)]
        X = X / np.maximum(np.sqrt(np.mean(X[use] ** 2, axis=0)), 1e-12)
        y, weight = r[:, j], np.ones(len(r))
        out = y.copy()
        for _ in range(iterations):
            w = np.sqrt(weight[use])
            coef = np.linalg.lstsq(X[use] * w[:, None], y[use] * w, rcond=None)[0]
            out = y - X @ coef
            u = out / (BISQUARE * robust_scale(out[use]))
            weight = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
        res[:, j] = out
    return res, robust_scale(res[use])
