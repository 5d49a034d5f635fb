"""What an excitation's design optimizes: criteria of the identification's regressor at the
states of a motion, each with its gradient with respect to the states (through the
regressor's vector-Jacobian product)."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class Regressor(Protocol):
    def evaluate(self, q, qd, qdd) -> np.ndarray: ...  # (n, dof, p)

    def vjp(self, q, qd, qdd, adjoint) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def log_condition(regressor: Regressor, q, qd, qdd, gradient: bool = False):
    """log of the condition number of the column-normalized regressor at the states; with
    gradient, also its gradient with respect to q, qd and qdd (each (n, dof))."""
    A = regressor.evaluate(q, qd, qdd)
    Y = A.reshape(-1, A.shape[-1])
    norms = np.maximum(np.linalg.norm(Y, axis=0), 1e-300)
    Yn = Y / norms
    eig, v = np.linalg.eigh(Yn.T @ Yn)  # the Gram's eigenpairs: singular values squared
    s = np.sqrt(np.maximum(eig[[-1, 0]], 1e-300))
    value = float(np.log(s[0]) - np.log(s[1]))
    if not gradient:
        return value
    u_max, u_min = Yn @ v[:, -1] / s[0], Yn @ v[:, 0] / s[1]
    dYn = np.outer(u_max, v[:, -1]) / s[0] - np.outer(u_min, v[:, 0]) / s[1]
    dY = dYn / norms - Y * (np.sum(dYn * Y, axis=0) / norms**3)  # through the normalization
    return value, regressor.vjp(q, qd, qdd, dY.reshape(A.shape))


def log_information(regressor: Regressor, q, qd, qdd, gradient: bool = False):
    """-(1/p) log det(Y^T Y / n) of the regressor Y (n rows, p columns) at the states: D-
    optimality, the log volume of the parameters' confidence ellipsoid under a sensor noise of
    fixed size (per column, so large motions count, unlike the normalized condition number);
    with gradient, also its gradient with respect to q, qd and qdd (each (n, dof))."""
    A = regressor.evaluate(q, qd, qdd)
    Y = A.reshape(-1, A.shape[-1])
    n, p = Y.shape
    gram = Y.T @ Y / n
    sign, logdet = np.linalg.slogdet(gram)
    value = float(-logdet / p) if sign > 0 else float("inf")
    if not gradient:
        return value
    dY = -2.0 / (n * p) * Y @ np.linalg.pinv(gram)
    return value, regressor.vjp(q, qd, qdd, dY.reshape(A.shape))


CRITERIA = {"condition": log_condition, "information": log_information}


