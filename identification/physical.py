"""Physically consistent identification relative to a nominal model (convex, cvxpy).

The rigid-body torque is linear in the standard inertial parameters pi (10 per body:
m, m c, and the rotational inertia about the body frame's origin, in Pinocchio's
toDynamicParameters order), tau = Y(q, qd, qdd) pi, plus per-joint friction
phi_j: viscous qd, Coulomb qd / sqrt(qd^2 + w^2), and an offset. The fit is

    minimize  mean_k,j ((tau - Y pi - F phi) / s_j)^2 + lam * sum_b ||(pi_b - nom_b) / r_b||^2
    subject to  J_b(pi_b) >= 0 (positive semidefinite) for every body b,
                viscous >= 0, Coulomb >= 0,

where s_j is joint j's torque scale, r_b a per-parameter scale of body b's nominal values,
and J_b = [[tr(I)/2 1 - I, h], [h^T, m]] the pseudo-inertia (Wensing, Wensing & Slotine 2017:
a body's (m, h, I) is physically consistent iff J_b is positive semidefinite). lam = 0 is
least squares under the LMI; lam is chosen by validation inside the training data (its last
contiguous block), never on a scored part. Solved by Clarabel (SCS if it fails).
"""

from __future__ import annotations

from dataclasses import dataclass

import cvxpy as cp
import numpy as np

COULOMB_WIDTH = 0.01  # rad/s: the smoothed sign's linear zone
LAMBDAS = (0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)  # ridge weights tried toward the nominal


def friction_columns(qd: np.ndarray) -> np.ndarray:
    """(n, dof, 3 dof): viscous, Coulomb and offset columns, each acting on its joint."""
    n, dof = qd.shape
    eye = np.eye(dof)
    coulomb = qd / np.sqrt(qd**2 + COULOMB_WIDTH**2)
    return np.concatenate([qd[:, :, None] * eye, coulomb[:, :, None] * eye,
                           np.broadcast_to(eye, (n, dof, dof))], axis=2)


def pseudo_inertia(p) -> list:
    """The 4x4 pseudo-inertia of one body's 10 standard parameters (numbers or cvxpy)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (p[k] for k in range(10))
    half = (ixx + iyy + izz) / 2
    return [[half - ixx, -ixy, -ixz, hx], [-ixy, half - iyy, -iyz, hy],
            [-ixz, -iyz, half - izz, hz], [hx, hy, hz, m]]


def min_pseudo_eigenvalues(params: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue of each body's pseudo-inertia (>= 0: physically consistent)."""
    return np.array([np.linalg.eigvalsh(np.array(pseudo_inertia(b), float)).min()
                     for b in np.asarray(params).reshape(-1, 10)])


@dataclass(frozen=True)
class PhysicalFit:
    """Identified standard parameters (10 per body), friction (viscous, Coulomb, offset per
    joint), the ridge weight chosen, and each body's smallest pseudo-inertia eigenvalue."""

    params: np.ndarray
    friction: np.ndarray
    lam: float
    min_eigenvalues: np.ndarray

    @property
    def consistent(self) -> bool:
        return bool(np.all(self.min_eigenvalues >= -1e-8))

    def torque(self, regressor: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """(n, dof) torque from the regressor Y (n, dof, 10 nb) and the velocities."""
        return regressor @ self.params + friction_columns(qd) @ self.friction


def _solve(Y, F, tau, scale, nominal, lam: float) -> tuple[np.ndarray, np.ndarray]:
    n, dof, p = Y.shape
    pi, phi = cp.Variable(p), cp.Variable(F.shape[2])
    a = (np.concatenate([Y, F], axis=2) / scale[None, :, None]).reshape(n * dof, -1)
    b = (tau / scale).reshape(-1)
    # the least-squares term through a's QR factors (the problem's size is its columns';
    # R may be singular: parameters the data do not excite, held by the LMI and the ridge)
    q, r = np.linalg.qr(a / np.sqrt(len(b)))
    c = q.T @ (b / np.sqrt(len(b)))
    x = cp.hstack([pi, phi])
    ref = np.maximum(np.abs(nominal).reshape(-1, 10).max(axis=1), 1e-6).repeat(10)
    cost = cp.sum_squares(r @ x - c)
    if lam > 0:
        cost = cost + lam * cp.sum_squares(cp.multiply(1.0 / ref, pi - nominal))
    blocks = [cp.bmat(pseudo_inertia(pi[10 * k:10 * k + 10])) for k in range(p // 10)]
    constraints = [(j + j.T) / 2 >> 0 for j in blocks]
    constraints += [phi[:2 * dof] >= 0]
    problem = cp.Problem(cp.Minimize(cost), constraints)
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.SolverError:
        problem.solve(solver=cp.SCS)
    if pi.value is None:
        raise ValueError(f"the consistent fit did not solve ({problem.status})")
    return np.asarray(pi.value), np.asarray(phi.value)


def fit_physical(Y: np.ndarray, qd: np.ndarray, tau: np.ndarray, nominal: np.ndarray,
                 lambdas=LAMBDAS, validation: float = 0.2) -> PhysicalFit:
    """The consistent fit of tau (n, dof) on the regressor Y (n, dof, 10 nb) and friction,
    pulled toward the nominal parameters with the lam of `lambdas` that predicts the last
    `validation` fraction of these samples best when fitted on the rest; refitted on all."""
    Y, qd, tau = (np.asarray(x, float) for x in (Y, qd, tau))
    F = friction_columns(qd)
    scale = np.maximum(tau.std(axis=0), 1e-9)
    split = int(round(len(tau) * (1 - validation)))
    errors = []
    for lam in lambdas:
        pi, phi = _solve(Y[:split], F[:split], tau[:split], scale, nominal, lam)
        pred = Y[split:] @ pi + F[split:] @ phi
        errors.append(float(np.mean(((pred - tau[split:]) / scale) ** 2)))
    lam = float(lambdas[int(np.argmin(errors))])
    pi, phi = _solve(Y, F, tau, scale, nominal, lam)
    return PhysicalFit(pi, phi, lam, min_pseudo_eigenvalues(pi))
