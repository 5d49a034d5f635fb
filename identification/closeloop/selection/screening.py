"""Which selected effects the data support robustly: stable across halves, useful on validation.

BIC on thousands of samples accepts any column that lowers the residual a little, including
columns that stand in for structure outside the dictionary (a tendon coupling q2 + q3 shows
up as springs, offsets and armatures whose coefficients depend on the stretch of data they
are fitted on). A selected effect is therefore only *named* if

1. stable: its coefficients fitted on the first and the second half of the training part
   agree, |c1 - c2| <= STABILITY |c| + Z_NOISE se(c1 - c2) (se from the white-noise level),
2. physical: its coefficient lies in its physical range (identification.closeloop.verdicts.ranges),
3. useful: leaving it out raises the block cross-validated error (VALIDATION_BLOCKS
   contiguous blocks of the training part, each predicted from the others) on the joints
   it acts on.

The held-out part is never used. Effects are removed one at a time, the least stable or
least useful first, until every one left passes both; the removed ones are returned as
candidates with the reason. Finally a joint whose cross-validated error with the named
effects exceeds the declared model's falls back to the declared model (`fallback`).

The problem is one weighted least-squares regression stacked over joints (rows weighted by
1 / noise sigma of their joint): `base` columns (the identified model's kept terms, refitted
jointly; none for a fixed declared model) plus the effects' torque columns.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm, PayloadTorque, effect_torque
from identification.closeloop.verdicts.ranges import Scales, unbounded

STABILITY = 0.10  # relative disagreement of the two halves' coefficients tolerated
Z_NOISE = 4.0  # ... plus this many standard errors of the difference from sensor noise
VALIDATION_BLOCKS = 4
TIE = 1e-9  # relative: equal validation errors (a joint no named effect acts on) are a tie


@dataclass(frozen=True)
class Candidate:
    """A selected effect that is not named, and why."""

    term: EffectTerm
    reason: str

    def to_json(self) -> dict:
        return {**self.term.to_json(), "reason": self.reason}


@dataclass(frozen=True)
class Screening:
    """Named effects (refitted on the whole training part), rejected candidates, joints
    (1..dof) falling back to the declared model, and the block cross-validated relative RMS
    error per joint of the declared model and of the model with the named effects."""

    named: tuple[EffectTerm, ...]
    candidates: tuple[Candidate, ...]
    fallback: tuple[int, ...]
    validation_before: np.ndarray
    validation_after: np.ndarray


class StackedProblem:
    """target (n, dof) ~ base columns (per joint, (n, k_j)) + effect columns (n, dof, m)."""

    def __init__(self, target: np.ndarray, base: list[np.ndarray], effects: np.ndarray,
                 sigma: np.ndarray):
        n, dof = target.shape
        w = 1.0 / np.maximum(sigma, 1e-12)
        base = base or [np.zeros((n, 0))] * dof
        widths = [b.shape[1] for b in base]
        self.n_base = int(sum(widths))
        X = np.zeros((n, dof, self.n_base + effects.shape[2]))
        start = 0
        for j, k in enumerate(widths):
            X[:, j, start:start + k] = base[j] * w[j]
            start += k
        X[:, :, self.n_base:] = effects * w[None, :, None]
        self.X, self.Y = X, target * w
        self.active = np.any(effects != 0, axis=0)  # (dof, m): joints each effect acts on

    def _cols(self, effects: list[int]) -> list[int]:
        return list(range(self.n_base)) + [self.n_base + i for i in effects]

    def fit(self, rows: np.ndarray, effects: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """Coefficients (base + effects) on rows, and their covariance at unit noise."""
        if self.n_base + len(effects) == 0:
            return np.zeros(0), np.zeros((0, 0))
        X = self.X[rows][:, :, self._cols(effects)].reshape(-1, self.n_base + len(effects))
        coef, *_ = np.linalg.lstsq(X, self.Y[rows].ravel(), rcond=None)
        return coef, np.linalg.pinv(X.T @ X)

    def sse(self, rows: np.ndarray, effects: list[int], coef: np.ndarray) -> np.ndarray:
        """Per-joint weighted residual sum of squares on rows."""
        r = self.Y[rows] - self.X[rows][:, :, self._cols(effects)] @ coef
        return np.sum(r**2, axis=0)

    def validation_sse(self, effects: list[int], blocks: int = VALIDATION_BLOCKS) -> np.ndarray:
        """Per-joint SSE of each contiguous block predicted from a fit on the other blocks."""
        n = len(self.Y)
        out = np.zeros(self.Y.shape[1])
        for block in np.array_split(np.arange(n), blocks):
            held = np.zeros(n, bool)
            held[block] = True
            coef, _ = self.fit(~held, effects)
            out += self.sse(held, effects, coef)
        return out

    def instability(self, effects: list[int]) -> np.ndarray:
        """Per effect: |c1 - c2| / (STABILITY |c| + Z_NOISE se), halves 1 and 2 (> 1: unstable)."""
        n = len(self.Y)
        first = np.arange(n) < n // 2
        full, _ = self.fit(np.ones(n, bool), effects)
        (c1, v1), (c2, v2) = self.fit(first, effects), self.fit(~first, effects)
        e = slice(self.n_base, None)
        se = np.sqrt(np.maximum(np.diag(v1)[e] + np.diag(v2)[e], 0.0))
        return np.abs(c1[e] - c2[e]) / np.maximum(STABILITY * np.abs(full[e]) + Z_NOISE * se,
                                                  1e-300)


def _columns(terms, q, qd, qdd, payload) -> np.ndarray:
    unit = [EffectTerm(t.effect, t.joint, 1.0, t.lead, t.eps) for t in terms]
    cols = [effect_torque((u,), q, qd, qdd, payload) for u in unit]
    return np.stack(cols, axis=2) if cols else np.zeros((*q.shape, 0))


def _next_rejection(problem: StackedProblem, kept: list[int], terms,
                    scales: Scales) -> tuple[int, str] | None:
    """The effect to drop next and why, or None if every kept effect is robust."""
    coef, _ = problem.fit(np.ones(len(problem.Y), bool), kept)
    for i, c in zip(kept, coef[problem.n_base:], strict=True):
        why = scales.why_not(replace(terms[i], coefficient=float(c)))
        if why:
            return i, why
    ratio = problem.instability(kept)
    if np.max(ratio) > 1.0:
        k = int(np.argmax(ratio))
        return kept[k], f"unstable: halves' coefficients differ by {ratio[k]:.2g}x the tolerance"
    with_all = problem.validation_sse(kept)
    gains = []
    for k, i in enumerate(kept):
        without = problem.validation_sse(kept[:k] + kept[k + 1:])
        joints = problem.active[:, i]
        gains.append(float(np.sum(without[joints] - with_all[joints]) / np.sum(with_all[joints])))
    k = int(np.argmin(gains))
    if gains[k] <= 0.0:
        return kept[k], f"no validation gain: block cross-validated error {-gains[k]:+.2%} with it"
    return None


def _rel(sse: np.ndarray, problem: StackedProblem) -> np.ndarray:
    return np.sqrt(sse / np.maximum(np.sum(problem.Y**2, axis=0), 1e-300))


def screen(target: np.ndarray, base: list[np.ndarray], terms: tuple[EffectTerm, ...],
           sigma: np.ndarray, q, qd, qdd, payload: PayloadTorque | None = None,
           scales: Scales | None = None) -> Screening:
    """Keep the robust terms among `terms` (selected on target (n, dof), N m), refitted;
    scales: the robot's, which bound every coefficient (identification.closeloop.verdicts.ranges; None:
    the signs only)."""
    scales = scales or unbounded(q.shape[1])
    problem = StackedProblem(target, base, _columns(terms, q, qd, qdd, payload), sigma)
    kept, rejected = list(range(len(terms))), []
    while kept:
        nxt = _next_rejection(problem, kept, terms, scales)
        if nxt is None:
            break
        kept.remove(nxt[0])
        rejected.append(Candidate(terms[nxt[0]], nxt[1]))
    before, after = problem.validation_sse([]), problem.validation_sse(kept)
    worse = {int(j) + 1 for j in np.flatnonzero(after > before * (1 + TIE))}
    for i in list(kept):
        t = terms[i]
        if t.effect != "payload" and t.joint in worse:
            kept.remove(i)
            rejected.append(Candidate(t, f"joint {t.joint} is worse on validation blocks with "
                                         "the effects: it falls back to the declared model"))
    after = problem.validation_sse(kept)
    fallback = tuple(int(j) + 1 for j in np.flatnonzero(after > before * (1 + TIE)))  # payload
    coef, _ = problem.fit(np.ones(len(target), bool), kept)
    named = tuple(EffectTerm(terms[i].effect, terms[i].joint, float(c), terms[i].lead,
                             terms[i].eps) for i, c in zip(kept, coef[problem.n_base:], strict=True))
    return Screening(named, tuple(rejected), fallback, _rel(before, problem),
                     _rel(np.minimum(after, before), problem))
