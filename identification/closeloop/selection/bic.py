"""Which effects explain a residual: forward selection with BIC on all joints at once.

The residual of every joint is stacked into one regression, each joint's rows
weighted by 1 / (its white-noise level), so joint-coupled candidates (the
payload) and per-joint candidates compete on the same footing. Forward
selection adds the candidate that lowers the weighted residual sum of squares
most while the Bayesian information criterion
BIC = N log(RSS / N) + k log N (N = stacked rows, k = selected terms) falls.
A selected term is then only *named* if its torque is not negligible next to
the noise on the joints it acts on (`min_size`, in units of noise sigma): with
thousands of samples BIC alone would name tiny artefacts of the
velocity/acceleration estimates.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from identification.closeloop.candidates.effects import (
    COULOMB_SHAPES,
    Effect,
    EffectDictionary,
    EffectTerm,
    joint_signal,
)

Projection = Callable[[np.ndarray], np.ndarray]  # (n, dof) -> (n, dof)
LEAD_RANGE = (0.0, 0.05)  # s, Coulomb lead searched over
EPS_RANGE = (1e-4, 2.0)  # rad/s, Coulomb linear-zone half-width searched over
MIN_SIZE = 0.25  # named effects must have an RMS torque >= 0.25 noise sigma on their joint


@dataclass(frozen=True)
class Selection:
    """Selected effects, their least-squares coefficients and the BIC path."""

    terms: tuple[EffectTerm, ...]
    bic_path: tuple[tuple[str, float], ...]  # (label added, BIC after adding); first = empty model
    sizes: dict[str, float]  # label -> RMS torque of the term / noise sigma on its joint(s)


def _weighted(residual: np.ndarray, columns: np.ndarray, sigma: np.ndarray):
    w = 1.0 / np.maximum(sigma, 1e-12)
    y = (residual * w).ravel()
    X = (columns * w[None, :, None]).reshape(-1, columns.shape[2])
    return y, X


def _lstsq(X: np.ndarray, y: np.ndarray, idx: list[int]) -> tuple[np.ndarray, float]:
    if not idx:
        return np.zeros(0), float(y @ y)
    coef, *_ = np.linalg.lstsq(X[:, idx], y, rcond=None)
    r = y - X[:, idx] @ coef
    return coef, float(r @ r)


def _bic(rss: float, n: int, k: int) -> float:
    return n * np.log(max(rss, 1e-300) / n) + k * np.log(n)


def _trial(X, y, idx, passive):
    """BIC of the fit on idx, or inf if a passive effect would come out negative."""
    coef, rss = _lstsq(X, y, idx)
    if np.any(coef[passive[idx]] < 0):
        return np.inf
    return _bic(rss, len(y), len(idx))


def forward_select(y: np.ndarray, X: np.ndarray, passive: np.ndarray | None = None,
                   max_terms: int = 8) -> tuple[list[int], list]:
    """Greedy forward selection by BIC; returns column indices and the (index, BIC) path.

    passive[i]: column i is a passive physical effect whose coefficient cannot be
    negative (damping, dry friction, rotor inertia, stiffness, mass); a step that
    would make one negative is not taken - the data contradict that explanation.
    """
    n = len(y)
    passive = np.zeros(X.shape[1], bool) if passive is None else np.asarray(passive, bool)
    norms = np.linalg.norm(X, axis=0)
    usable = [i for i in range(X.shape[1]) if norms[i] > 0]
    chosen: list[int] = []
    best = _bic(_lstsq(X, y, [])[1], n, 0)
    path: list = [(None, best)]
    while len(chosen) < max_terms:
        trials = [(_trial(X, y, chosen + [i], passive), i) for i in usable if i not in chosen]
        if not trials:
            break
        bic, i = min(trials)
        if bic >= best:
            break
        chosen.append(i)
        best = bic
        path.append((i, bic))
    return chosen, path


def term_sizes(columns: np.ndarray, idx: list[int], coef: np.ndarray,
               sigma: np.ndarray) -> np.ndarray:
    """RMS torque of each term over the joints it acts on, in units of their noise sigma."""
    out = []
    for i, c in zip(idx, coef, strict=True):
        tau = c * columns[:, :, i]
        active = np.any(columns[:, :, i] != 0, axis=0)
        out.append(float(np.max(np.sqrt(np.mean(tau[:, active] ** 2, axis=0)) / sigma[active])))
    return np.array(out)


def select_effects(residual: np.ndarray, dictionary: EffectDictionary, sigma: np.ndarray,
                   min_size: float = MIN_SIZE, max_terms: int = 8) -> Selection:
    """Select and fit the effects that explain residual (n, dof), noise sigma (dof,) in N m."""
    y, X = _weighted(residual, dictionary.columns, sigma)
    passive = np.array([e.effect != "offset" for e in dictionary.effects])
    idx, path = forward_select(y, X, passive, max_terms)
    coef, _ = _lstsq(X, y, idx)
    sizes = term_sizes(dictionary.columns, idx, coef, sigma)
    keep = [i for i, s in zip(idx, sizes, strict=True) if s >= min_size]
    coef, _ = _lstsq(X, y, keep)
    labels = dictionary.effects
    terms = tuple(EffectTerm(labels[i].effect, labels[i].joint, float(c))
                  for i, c in zip(keep, coef, strict=True))
    return Selection(
        terms=terms,
        bic_path=tuple(("" if i is None else labels[i].label, float(b)) for i, b in path),
        sizes={labels[i].label: float(s) for i, s in zip(idx, sizes, strict=True)},
    )


def refit(residual: np.ndarray, dictionary: EffectDictionary, sigma: np.ndarray,
          chosen: list) -> tuple[EffectTerm, ...]:
    """Weighted least-squares coefficients of a given set of effects (no selection)."""
    y, X = _weighted(residual, dictionary.columns, sigma)
    idx = [dictionary.index(e) for e in chosen]
    coef, _ = _lstsq(X, y, idx)
    return tuple(EffectTerm(e.effect, e.joint, float(c)) for e, c in zip(chosen, coef, strict=True))


def _shape_rss(residual, cols, sigma, k, joint, q, qd, qdd, lead, eps, project=None) -> float:
    """Weighted RSS of the refit with column k replaced by a Coulomb column of shape (lead, eps)."""
    cols[:, :, k] = 0.0
    cols[:, joint - 1, k] = joint_signal("coulomb", q, qd, qdd, lead, eps)[:, joint - 1]
    if project is not None:
        cols[:, :, k] = project(cols[:, :, k])
    y, X = _weighted(residual, cols, sigma)
    return _lstsq(X, y, list(range(cols.shape[2])))[1]


def _best_shape(rss_of) -> tuple[float, float]:
    """(lead, eps) minimizing rss_of(lead, eps): best of COULOMB_SHAPES, then Nelder-Mead in
    (lead, log eps) within LEAD_RANGE x EPS_RANGE."""
    _, lead, eps = min((rss_of(lead, eps), lead, eps) for lead, eps in COULOMB_SHAPES)

    def cost(x):
        lead, eps = float(np.clip(x[0], *LEAD_RANGE)), float(np.exp(np.clip(x[1], *np.log(EPS_RANGE))))
        return rss_of(lead, eps)

    res = minimize(cost, [lead, np.log(eps)], method="Nelder-Mead",
                   options={"xatol": 1e-4, "fatol": 1e-9, "maxiter": 200,
                            "initial_simplex": [[lead, np.log(eps)], [lead + 0.004, np.log(eps)],
                                                [lead, np.log(eps) + 0.5]]})
    return float(np.clip(res.x[0], *LEAD_RANGE)), float(np.exp(np.clip(res.x[1], *np.log(EPS_RANGE))))


def refine_coulomb(residual: np.ndarray, dictionary: EffectDictionary, sigma: np.ndarray,
                   terms: tuple[EffectTerm, ...], q: np.ndarray, qd: np.ndarray,
                   qdd: np.ndarray, project: Projection | None = None) -> tuple[EffectTerm, ...]:
    """Estimate each selected Coulomb term's shape (lead in s, eps in rad/s) by the weighted
    residual sum of squares of the whole refit (variable projection: coefficients by least
    squares at each shape), one joint at a time; returns the refitted terms.

    project: the map applied to the dictionary's columns (closeloop_identified), applied to
    every trial Coulomb column too."""
    chosen = [Effect(t.effect, t.joint) for t in terms]
    if not any(e.effect == "coulomb" for e in chosen):
        return terms
    cols = np.stack([dictionary.columns[:, :, dictionary.index(e)] for e in chosen], axis=2)
    shapes = {t.joint: (t.lead, t.eps) for t in terms if t.effect == "coulomb"}
    for k, e in enumerate(chosen):
        if e.effect != "coulomb":
            continue
        shapes[e.joint] = _best_shape(
            lambda lead, eps, k=k, j=e.joint: _shape_rss(residual, cols, sigma, k, j, q, qd, qdd,
                                                         lead, eps, project))
        _shape_rss(residual, cols, sigma, k, e.joint, q, qd, qdd, *shapes[e.joint], project)
    y, X = _weighted(residual, cols, sigma)
    coef, _ = _lstsq(X, y, list(range(len(chosen))))
    return tuple(EffectTerm(e.effect, e.joint, float(c), *shapes.get(e.joint, (t.lead, t.eps)))
                 if e.effect == "coulomb" else EffectTerm(e.effect, e.joint, float(c))
                 for e, c, t in zip(chosen, coef, terms, strict=True))
