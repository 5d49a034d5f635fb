"""What the robot itself adds to the observer's estimate: its persistent effects, functions of
its state (friction, a payload, a spring or tendon, a scale error of the drive gains), removed
per joint by a robust fit (Tukey's bisquare, iteratively reweighted) on the same low-pass of
state columns, so that what is left is what no function of the state explains.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

BISQUARE = 4.685  # Tukey's constant (95 % efficiency at Gaussian residuals)
FRICTION_WIDTH = 0.02  # rad/s, the dry-friction column's tanh width
REACH = 1.0  # m: a load's centre of mass within it, for its bounds
MOVING = 0.15  # a column is a persistent effect's only if at least this share of the fitted
# samples lie off its median by a tenth of its largest excursion (moving_columns); chosen on
# development draws (the pushes case's seeds 1-2 on the Lynxmotion, 1 on the UR5): a pushed
# held arm's velocity and pose columns 0.02-0.11, a moving arm's 0.2-0.99


def state_columns(model, q, qd, qdd, body=None, pose: bool = True, scales=None,
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per joint j, the (n, k) torques of the persistent effects the detection removes and the
    (k,) bound on each one's coefficient (scales: the robot's, identification.closeloop.verdicts.ranges;
    None: unbounded): an offset (+- tau_max), viscous (+- tau_max / v_max) and dry friction
    (+- tau_max), the declared torque's scale (+- 1), a spring or tendon from every joint's
    pose (+- tau_max / that joint's span), and, with body (a callable (q, qd, qdd) ->
    (n, dof, 10), the load's body's regressor), its ten parameters (a mass of at most the
    robot's, within a metre); pose=False: without the springs. Either sign: the declared model
    may have too much of an effect as well as too little. Bounded, a persistent effect cannot
    take a push's place: under a stiff position loop a push deflects the arm by milliradians,
    which only a spring thousands of times stiffer than any joint's could turn into the
    push's torque."""
    n, dof = q.shape
    declared = model.torque(q, qd, qdd)
    load = None if body is None else np.asarray(body(q, qd, qdd), float)
    if scales is None:
        tau, speed, span, mass = (np.full(dof, np.inf), np.ones(dof), np.ones(dof), np.inf)
    else:
        tau, speed, span, mass = scales.torque, scales.speed, scales.span, scales.mass
    out = []
    for j in range(dof):
        cols = [np.ones(n), qd[:, j], np.tanh(qd[:, j] / FRICTION_WIDTH), declared[:, j]]
        bound = [tau[j], tau[j] / speed[j], tau[j], 1.0]
        if pose:
            cols += list(q.T)
            bound += list(tau[j] / span)
        if load is not None:
            cols += list(load[:, j, :].T)
            bound += [mass] * 4 + [mass * REACH**2] * 6
        out.append((np.stack(cols, axis=1), np.asarray(bound, float)))
    return out


def robust_scale(x: np.ndarray) -> np.ndarray:
    med = np.median(x, axis=0)
    return np.maximum(1.4826 * np.median(np.abs(x - med), axis=0), 1e-12)


def moving_columns(X: np.ndarray) -> np.ndarray:
    """(k,) bool: the columns of X (n, k) that move over the run rather than at a few of its
    instants (module constant MOVING); a constant is the offset's, and kept. On an arm held
    still the velocity, the deflection and every function of them move only while a push
    deflects the arm: fitted, such a column is the push, nothing persistent."""
    dev = np.abs(X - np.median(X, axis=0))
    largest = np.max(dev, axis=0)
    constant = largest <= 1e-12 * np.maximum(np.max(np.abs(X), axis=0), 1e-300)
    return constant | (np.mean(dev > 0.1 * largest, axis=0) >= MOVING)


def persistent_residual(r: np.ndarray, cols: list[tuple[np.ndarray, np.ndarray]],
                        use: np.ndarray, iterations: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """r minus, per joint, its bisquare fit on that joint's columns (both low-passed alike),
    each coefficient within its bound (state_columns) and held at zero on a column not
    moving_columns, fitted on the samples use; returns that residual (n, dof) and its robust
    scale (dof,) on those samples."""
    res = np.empty_like(r)
    for j, (X, bound) in enumerate(cols):
        size = np.maximum(np.sqrt(np.mean(X[use] ** 2, axis=0)), 1e-12)
        # an unbounded coefficient (bound inf) of a column held at zero: 1e-300, not inf x 0
        X, bound = X / size, np.where(moving_columns(X[use]), np.maximum(bound * size, 1e-300),
                                      1e-300)
        y, weight = r[:, j], np.ones(len(r))
        out = y.copy()
        for _ in range(iterations):
            w = np.sqrt(weight[use])
            coef = lsq_linear(X[use] * w[:, None], y[use] * w, bounds=(-bound, bound)).x
            out = y - X @ coef
            u = out / (BISQUARE * robust_scale(out[use]))
            weight = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
        res[:, j] = out
    return res, robust_scale(res[use])
