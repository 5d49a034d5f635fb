"""The coupled fit on a prior-knowledge library held to the robot's rigid-body structure.

A library derived from simple structures (identification.library.prior_knowledge) spans the
truth, but also directions no rigid body of the robot's kinematics takes: a link's potential
atom (g times its first moment) and the kinetic atom that first moment makes with the link
before it (times that link's length) get free coefficients where the kinematics tie them.
Only the noise fills such a direction. Held to the coefficient directions whose torque the
robot's base atoms (identification.library.kinematic) also give on the training samples, the
fit keeps the truth, which both models contain, and least squares on their intersection is
at least as good in expectation as on either (Gauss-Markov on nested models). An F-test of
the restriction guards a library or a kinematics the data do not bear out: rejected at
PVALUE, the fit is left as selected.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import f as fisher

from identification.regression.coupled import CoupledRegression
from identification.regression.weighted import weighted_lstsq

PVALUE = 0.01  # the restriction is kept unless the data reject it at this level
RTOL = 1e-8  # a singular value below RTOL x the largest is a shared direction


def shared_directions(atoms: np.ndarray, structure: np.ndarray, rtol: float = RTOL) -> np.ndarray:
    """Orthonormal basis (p, k) of the coefficient vectors a whose torque atoms @ a (atoms:
    (n, dof, p)) lies in the span of structure's columns (n, dof, r) on these samples."""
    p = atoms.shape[-1]
    both = np.concatenate([atoms.reshape(-1, p), -structure.reshape(-1, structure.shape[-1])],
                          axis=1)
    scale = np.linalg.norm(both, axis=0)
    scale[scale == 0] = 1.0
    _, sv, vt = np.linalg.svd(both / scale, full_matrices=False)
    null = (vt[sv <= rtol * sv[0]] / scale).T[:p]  # the atoms' part of each shared pair
    if null.size == 0:
        return np.zeros((p, 0))
    u, s, _ = np.linalg.svd(null, full_matrices=False)
    return u[:, s > rtol * s[0]]


def restriction_pvalue(rss_held: float, rss_free: float, df_held: int, rows: int,
                       params: int, total: float) -> float:
    """F-test p-value of the held fit (df_held fewer parameters) against the free one, both
    weighted residual sums of squares over `rows` rows with `params` free parameters; total:
    the weighted torque's sum of squares (exact data: any misfit rejects)."""
    if rss_free <= 1e-28 * total:
        return 1.0 if rss_held <= 1e-20 * total else 0.0
    stat = max(rss_held - rss_free, 0.0) / df_held / (rss_free / (rows - params))
    return float(fisher.sf(stat, df_held, rows - params))


def hold_to_structure(reg: CoupledRegression, design: np.ndarray, tau: np.ndarray,
                      structure: np.ndarray) -> dict:
    """Refit reg's kept atoms (design (n, dof, p), tau (n, dof)) within shared_directions of
    the structure's design (n, dof, r), each joint weighed by reg.sigma_, unless the F-test
    rejects it; updates reg's coef_, intercept_, cov_ and stderr_ when held. Returns what was
    done: held or not, the directions kept of the atoms kept, the p-value."""
    support = np.flatnonzero(reg.support_)
    shared = shared_directions(design[:, :, support], structure)
    out = {"held": False, "directions": int(shared.shape[1]), "atoms": len(support)}
    if shared.shape[1] in (0, len(support)):
        return out
    held = design[:, :, support] @ shared
    coef, offsets, resid, cov = weighted_lstsq(held, tau, range(shared.shape[1]), reg.sigma_)
    free = weighted_lstsq(design, tau, support, reg.sigma_)[2]
    rss_held, rss_free = (float(np.sum((r / reg.sigma_) ** 2)) for r in (resid, free))
    out["pvalue"] = restriction_pvalue(rss_held, rss_free, len(support) - shared.shape[1],
                                       tau.size, len(support) + tau.shape[1],
                                       float(np.sum((tau / reg.sigma_) ** 2)))
    if out["pvalue"] < PVALUE:
        return out
    reg.coef_[support] = shared @ coef
    reg.intercept_ = offsets
    reg.cov_[np.ix_(support, support)] = shared @ cov @ shared.T
    reg.stderr_ = np.sqrt(np.maximum(np.diag(reg.cov_), 0.0))
    out["held"] = True
    return out
