"""Coupled sparse regression: one Lagrangian for all joints.

Every joint's torque comes from the same Lagrangian L = sum_a xi_a * atom_a, so
an atom's coefficient xi_a is shared: its Euler-Lagrange derivative fixes the
relative factors of its features on every joint. The paper regresses each joint alone
(~30 free coefficients for the Lynxmotion); here the regression is stacked over joints
(rows = samples x joints, columns = atoms: 11 candidates, 8 true; 22 without the
symmetric-link assumption), each joint's rows weighted by 1 / its noise std, with a
per-joint unpenalized offset for the sensor bias. Selection is the paper's: Lasso over a
swept alpha, the proportional filter until the validation error rises, an unbiased weighted
least-squares refit; kept atoms whose refit t-statistic is below the Bonferroni bound of a
`familywise` error over all candidates are then dropped one at a time, the weakest first
(validation error alone cannot tell a null atom from noise). Atoms whose stacked torque
signatures are linearly dependent on the data are folded into base atoms (pivoted QR).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.base import clone

from identification.library.base import Library
from identification.library.prior_knowledge import Atom, atom_torque
from identification.regression.base import Regressor, validation_mask
from identification.regression.oracle import base_columns
from identification.regression.sparse import SparseRegression
from identification.regression.weighted import WeightedGram, weighted_lstsq


@dataclass(frozen=True)
class AtomBasis:
    """Atoms and, per joint, the matrix E_j (features x atoms) of their torque factors."""

    dof: int
    atoms: tuple[Atom, ...]
    library: Library  # every feature any atom produces
    factors: np.ndarray  # (dof, n_features, n_atoms)

    @classmethod
    def from_atoms(cls, atoms, dof: int, name: str = "atoms") -> AtomBasis:
        torques = [[atom_torque(a, m) for a in atoms] for m in range(dof)]
        feats = sorted({f for per_joint in torques for t in per_joint for f in t},
                       key=lambda f: f.name)
        index = {f: k for k, f in enumerate(feats)}
        factors = np.zeros((dof, len(feats), len(atoms)))
        for m, per_joint in enumerate(torques):
            for a, t in enumerate(per_joint):
                for f, v in t.items():
                    factors[m, index[f], a] = v
        return cls(dof, tuple(atoms), Library(name, dof, tuple(feats), tuple(atoms)), factors)

    @property
    def names(self) -> list[str]:
        return [a.name for a in self.atoms]

    def evaluate(self, q, qd, qdd) -> np.ndarray:
        """Atom torque signatures (n, dof, n_atoms) at states (n, dof)."""
        theta = self.library.evaluate(q, qd, qdd)
        return np.stack([theta @ self.factors[m] for m in range(self.dof)], axis=1)

    def expand(self, coef: np.ndarray, rtol: float = 1e-12) -> list[dict[str, float]]:
        """Per joint {feature name: coefficient} of the Lagrangian sum_a coef_a atom_a."""
        out = []
        for m in range(self.dof):
            c = self.factors[m] @ coef
            big = np.abs(c) > rtol * max(np.abs(coef).max(initial=0.0), 1e-300)
            out.append({self.library.names[k]: float(c[k]) for k in np.flatnonzero(big)})
        return out


    def expand_stderr(self, cov: np.ndarray) -> list[np.ndarray]:
        """Per joint, the standard error of every library feature's coefficient."""
        return [np.sqrt(np.maximum(np.einsum("fa,ab,fb->f", e, cov, e), 0.0))
                for e in self.factors]


def shrink_factors(coef: np.ndarray, stderr: np.ndarray) -> np.ndarray:
    """Per coefficient, max(0, 1 - 1/t^2) with t = coef / stderr (1 where stderr is 0).

    For one coefficient estimated as b ~ N(beta, s^2), the factor f minimizing the expected
    squared error of f b is beta^2 / (beta^2 + s^2); t^2 - 1 estimates (beta / s)^2 without
    bias, which gives 1 - 1/t^2 (the positive-part James-Stein factor of one coordinate,
    Breiman's non-negative garrote in closed form). Its mean squared error relative to b's
    (tests/test_identification_coupled.py, Monte Carlo): 0.33 for beta = 0, 0.86 at
    beta = s, up to 1.45 for beta of 2-3 s, 1.03 at 10 s, 1.00 beyond: a trade that pays
    where most kept atoms are null or nearly so - a robot's many weak base atoms."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t2 = np.where(stderr > 0, (coef / np.where(stderr > 0, stderr, 1.0)) ** 2, np.inf)
        return np.clip(1.0 - 1.0 / t2, 0.0, 1.0)


OFFSET_RTOL = 1e-3  # an atom whose spread about its per-joint means is below this share of its
# size acts as an offset on this data (a Coulomb atom of a joint that never reverses: 3e-7)


def base_atoms(design: np.ndarray, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Independent atom columns of the stacked (n*dof, p) design by pivoted QR, and the
    folded ones (linearly dependent on the base columns on this data). An atom constant on
    every joint over the data (a Coulomb atom whose joint never reverses) is the per-joint
    offset the fit always has: folded, never fitted beside it (the two would cancel with huge
    coefficients that blow up on any motion that does reverse)."""
    base = base_columns(design, rtol)
    spread = np.linalg.norm((design - design.mean(axis=0)).reshape(-1, design.shape[-1]), axis=0)
    size = np.linalg.norm(design.reshape(-1, design.shape[-1]), axis=0)
    base = base[spread[base] > OFFSET_RTOL * size[base]]
    return base, np.setdiff1d(np.arange(design.shape[-1]), base)


def restriction_pvalue(restricted: np.ndarray, full: np.ndarray, y: np.ndarray) -> float:
    """F-test p-value of 'y lies in span(restricted)' against 'y lies in span(full)', both with
    an intercept; restricted's span must lie inside full's (atom signatures inside the library).
    Small p: the data reject the restriction (e.g. no Lagrangian of these atoms fits)."""
    from scipy.stats import f as fisher

    def rss_rank(x):
        x = np.column_stack([x, np.ones(len(y))])
        sol, _, rank, _ = np.linalg.lstsq(x, y, rcond=None)
        return float(np.sum((y - x @ sol) ** 2)), rank

    (rss_r, k_r), (rss_u, k_u) = rss_rank(restricted), rss_rank(full)
    if k_u <= k_r:
        return 1.0
    dof = len(y) - k_u
    if rss_u <= 1e-28 * float(y @ y):  # exact data: any misfit rejects
        return 1.0 if rss_r <= 1e-20 * float(y @ y) else 0.0
    stat = max(rss_r - rss_u, 0.0) / (k_u - k_r) / (rss_u / dof)
    return float(fisher.sf(stat, k_u - k_r, dof))


class CoupledRegression(Regressor):
    """Stacked, noise-weighted Lasso + proportional filter + WLS refit over shared atoms.

    selector: the SparseRegression whose settings choose alpha and pass rate (a copy is fitted;
    None: the defaults). shrink: multiply each kept coefficient by shrink_factors (prediction
    over unbiasedness; stderr_ and cov_ stay the unshrunk refit's). required: a mask (p,) of
    atoms kept out of the sparsity (always in the support, never shrunk: the terms a structure
    requires), None: none. fit(design (n, dof, p) atom
    signatures, tau (n, dof)) sets coef_ (p,),
    intercept_ (dof,) per-joint offsets (also offsets_), sigma_, support_, base_, folded_,
    alpha_, pass_rate_, candidates_, path_, and the refit's covariance cov_ (p, p) and
    stderr_ (p,).
    """

    stacked = True

    def __init__(self, familywise: float = 0.01, selector: SparseRegression | None = None,
                 t_bound: float | np.ndarray | None = None, shrink: bool = False,
                 required: np.ndarray | None = None):
        self.familywise = familywise
        self.t_bound = t_bound
        self.selector = selector
        self.shrink = shrink
        self.required = required

    @property
    def offsets_(self) -> np.ndarray:
        """Per-joint sensor offsets (dof,) N m: intercept_."""
        return self.intercept_

    def noise_sigma(self, design: np.ndarray, tau: np.ndarray, cols) -> np.ndarray:
        """Per-joint noise std (N m) from a two-step weighted fit on all base atoms."""
        sigma = np.ones(tau.shape[1])
        for _ in range(2):
            resid = weighted_lstsq(design, tau, cols, sigma)[2]
            dof_used = (len(cols) + tau.shape[1]) / tau.size
            sigma = np.maximum(resid.std(axis=0) / np.sqrt(1 - dof_used), 1e-12 * tau.std(axis=0))
        return sigma

    def _fit(self, design: np.ndarray, tau: np.ndarray) -> None:
        selector = SparseRegression() if self.selector is None else clone(self.selector)
        n, dof, p = design.shape
        self.base_, self.folded_ = base_atoms(design)
        self.sigma_ = self.noise_sigma(design, tau, self.base_)
        xw = design[:, :, self.base_] / self.sigma_[None, :, None]
        yw = tau / self.sigma_
        val = validation_mask(n, selector.block, selector.every)
        xc = xw - xw[~val].mean(axis=0)  # per-joint centring = unpenalized per-joint offset
        yc = yw - yw[~val].mean(axis=0)
        scale = xc[~val].reshape(-1, len(self.base_)).std(axis=0)
        scale[scale == 0] = 1.0
        xs = xc / scale

        def rows(mask):
            return xs[mask].reshape(-1, len(self.base_)), yc[mask].reshape(-1)

        chosen = selector.select(*rows(~val), *rows(val))
        self.alpha_, self.pass_rate_ = chosen.alpha, chosen.pass_rate
        self.candidates_ = selector.candidates_
        self.path_ = self._path(xs, yc, val)
        support = self.base_[list(chosen.support)]
        required = self._required(p)
        support = np.union1d(support, np.intersect1d(self.base_, np.flatnonzero(required)))
        support, (coef, self.intercept_, _, cov) = self._stepwise(design, tau, support)
        self.cov_ = np.zeros((p, p))
        self.cov_[np.ix_(support, support)] = cov
        self.stderr_ = np.sqrt(np.maximum(np.diag(self.cov_), 0.0))
        if self.shrink:
            factors = shrink_factors(coef, self.stderr_[support])
            coef = coef * np.where(required[support], 1.0, factors)
            # the offsets follow the shrunk atoms (they stay each joint's mean residual)
            self.intercept_ = (tau - design[:, :, support] @ coef).mean(axis=0)
        self._set_coef(p, support, coef)

    def _required(self, n_atoms: int) -> np.ndarray:
        """The atoms kept out of the sparsity (n_atoms,) bool."""
        if self.required is None:
            return np.zeros(n_atoms, bool)
        return np.broadcast_to(np.asarray(self.required, bool), (n_atoms,))

    def _bound(self, n_atoms: int) -> np.ndarray:
        """|t| each atom must reach (n_atoms,): t_bound if set (a number or one per atom),
        else the two-sided Bonferroni bound of `familywise` over n_atoms candidates."""
        from scipy.stats import norm

        if self.t_bound is not None:
            return np.broadcast_to(np.asarray(self.t_bound, dtype=float), (n_atoms,))
        return np.full(n_atoms, float(norm.isf(self.familywise / (2 * n_atoms))))

    def _stepwise(self, design: np.ndarray, tau: np.ndarray, support: np.ndarray):
        """Backward elimination (`_significant`), then while a base atom left out has |t| above
        its bound when added to the support, add the most significant one (relative to its
        bound) and eliminate again: the Lasso path can drop a weak atom whose column is
        correlated with kept ones (a wrist inertia beside the larger ones)."""
        bound = self._bound(design.shape[-1])
        support, fit = self._significant(design, tau, support)
        spread = np.linalg.norm(tau - tau.mean(axis=0))
        gram = WeightedGram(design, tau, self.sigma_)
        for _ in range(len(self.base_)):
            if np.linalg.norm(fit[2]) <= 1e-9 * spread:  # exact already: t is round-off
                break
            left_out = np.setdiff1d(self.base_, support)
            ratio = gram.added_t(support, left_out) / bound[left_out]
            if not len(left_out) or ratio.max() <= 1.0:
                break
            best = left_out[int(np.argmax(ratio))]
            support, fit = self._significant(design, tau, np.sort(np.append(support, best)))
        return support, fit

    def _significant(self, design: np.ndarray, tau: np.ndarray, support: np.ndarray):
        """Backward elimination of atoms with |t| below their bound (`_bound`), the weakest
        relative to its bound first; returns the support and its refit."""
        bound = self._bound(design.shape[-1])
        required = self._required(design.shape[-1])
        while True:
            fit = weighted_lstsq(design, tau, support, self.sigma_)
            stderr = np.sqrt(np.maximum(np.diag(fit[3]), 0.0))
            ratio = np.abs(fit[0]) / np.where(stderr > 0, stderr, np.inf) / bound[support]
            ratio[required[support]] = np.inf
            if len(support) == 1 or ratio.min() >= 1.0:
                return support, fit
            support = np.delete(support, int(np.argmin(ratio)))

    def _path(self, xs, yc, val) -> list[tuple[float, np.ndarray]]:
        """(alpha, per-joint validation MSE in units of each joint's noise variance) of the
        best pass rate at every swept alpha: the paper's Figs. 3-5 per joint."""
        best: dict[float, object] = {}
        for c in self.candidates_:
            if c.alpha not in best or c.validation_mse < best[c.alpha].validation_mse:
                best[c.alpha] = c
        x_fit = xs[~val].reshape(-1, xs.shape[-1])
        gram, rhs = x_fit.T @ x_fit, x_fit.T @ yc[~val].reshape(-1)
        out = []
        for alpha in sorted(best):
            s = list(best[alpha].support)
            coef = np.linalg.lstsq(gram[np.ix_(s, s)], rhs[s], rcond=None)[0]
            out.append((alpha, np.mean((yc[val] - xs[val][:, :, s] @ coef) ** 2, axis=0)))
        return out
