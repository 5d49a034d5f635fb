"""Closing the loop on measured data: the rigid-body identification's residual, traced per
joint to named effects chosen by what they predict.

A real arm's residual is not white noise plus a missing effect: state estimates, gearbox
friction and unmodelled compliance all leave coloured structure, so a whiteness test or
BIC on thousands of samples would name everything. Here every decision is made on
validation blocks of the training part (the held-out part only scores):

1. Declared model: the rigid-body identification on the training part (the coupled sparse
   regression on the robot's rigid-body base atoms, identification.identify; a constant
   sensor offset per joint is part of it).
2. Candidates, per joint: `viscous`, `coulomb`, `sigmoid` (Gaz et al.'s friction),
   `armature`, `spring` (identification.closeloop.candidates.effects). The shapes of the nonlinear
   ones (Coulomb lead and width, sigmoid steepness and shift) are fitted per joint by
   variable projection: the least-squares residual of the rigid-body atoms, the offsets,
   the joint's viscous column and the candidate, minimized over the shape.
3. Forward selection by block cross-validation (identification.closeloop.selection.crossval): the
   candidate that lowers the validation error most is added while it lowers its own
   joint's validation error sum of squares by at least MIN_GAIN and its coefficient in
   the joint fit lies in its physical range (identification.closeloop.verdicts.ranges).
4. Adding: the rigid-body atoms the declared model kept, the offsets and the named effects
   refitted jointly by weighted least squares on the training part.
5. A joint is `unexplained` when its declared residual carries structure - validation
   power above its white-noise level (estimated from second differences of the residual,
   identification.closeloop.selection.residual.noise_sigma) of more than STRUCTURE noise sigmas RMS -
   and the named effects remove less than EXPLAINED of that structured power: something
   is left that no candidate accounts for, and it is said rather than forced onto a name.
   Measured on structure, not on the whole residual power: where noise dominates, the
   right effect leaves the residual at the noise and removes only part of its power (a
   UR5 plant's viscous joint: 45 % of the power, all of the structure). On a real arm
   the second-difference level also holds the residual's fast unmodelled part, so the
   structure there is a lower bound; the power the effects remove is reported beside it.

Rows of joint j are weighted by 1 / (RMS of the declared model's training residual on j),
so every joint's residual counts alike whatever its torque scale.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize

from identification.closeloop.candidates.effects import (
    COULOMB_SHAPES,
    MEASURED_EFFECTS,
    EffectTerm,
    effect_torque,
)
from identification.closeloop.closed.extended import ExtendedModel, WithOffsets
from identification.closeloop.selection.bic import EPS_RANGE, LEAD_RANGE
from identification.closeloop.selection.crossval import BlockValidation, weighted_fit
from identification.closeloop.selection.plant import check_data
from identification.closeloop.selection.residual import noise_sigma
from identification.closeloop.verdicts.agreement import best_left
from identification.closeloop.verdicts.ranges import Scales, unbounded
from identification.identify import identify
from identification.kinematic_model import KinematicModel
from identification.library.kinematic import KinematicLibrary
from identification.metrics import rel_error

VALIDATION_BLOCKS = 5
MIN_GAIN = 0.02  # an effect must cut its joint's validation error power by >= 2 %
EXPLAINED = 0.5  # effects removing less of a residual's structured power: unexplained
STRUCTURE = 0.5  # noise sigmas of structure (RMS above the white noise) worth explaining:
# 0.5 sigma is 25 % more residual power than the noise; block cross-validation alone adds a
# few per cent (a generated log of the declared Lynxmotion reached 0.26 sigma)
SIGMOID_SHAPES = tuple((s, d) for s in (2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
                       for d in (-0.05, 0.0, 0.05))  # (s/rad, rad/s): start grid
STEEPNESS_RANGE = (0.5, 500.0)  # s/rad
SHIFT_RANGE = (-0.5, 0.5)  # rad/s


@dataclass(frozen=True)
class MeasuredLoop:
    """Outcome of the loop on measured data; errors relative (1 = 100 %), vs measured tau."""

    declared: WithOffsets  # the rigid-body identification (training part)
    model: ExtendedModel  # declared atoms and offsets refitted with the named effects
    terms: tuple[EffectTerm, ...]  # named effects, coefficients of the joint refit
    error_before: np.ndarray  # (dof,) held-out
    error_after: np.ndarray
    validation_before: np.ndarray  # (dof,) block cross-validated, training part
    validation_after: np.ndarray
    structure_before: np.ndarray  # (dof,) RMS of the validation residual above the white
    structure_after: np.ndarray  # noise, in noise sigmas: declared model / with the effects
    noise: np.ndarray  # (dof,) N m, white-noise level of the declared model's residual
    path: tuple[tuple[str, float], ...]  # (label added, total validation power after)
    not_named: tuple[tuple[int, str, float, str], ...]  # per joint: best candidate left, its
    # validation gain, why it was not named
    split: int

    @property
    def power_removed(self) -> np.ndarray:
        """(dof,) fraction of the declared model's validation residual power the named effects
        remove."""
        return 1.0 - (self.validation_after / np.maximum(self.validation_before, 1e-300)) ** 2

    @property
    def explained(self) -> np.ndarray:
        """(dof,) fraction of the structured residual power (above the white noise) the named
        effects remove; 1 where there was none."""
        before = self.structure_before**2
        return np.where(before > 0, 1.0 - self.structure_after**2 / np.maximum(before, 1e-300),
                        1.0)

    @property
    def unexplained_joints(self) -> tuple[int, ...]:
        return tuple(int(j) + 1 for j in np.flatnonzero(
            (self.structure_before > STRUCTURE) & (self.explained < EXPLAINED)))

    @property
    def unexplained(self) -> bool:
        return bool(self.unexplained_joints)


def _unit(effect: str, joint: int, shape: tuple[float, float] = ()) -> EffectTerm:
    if effect in ("coulomb", "load_friction"):
        return EffectTerm(effect, joint, 1.0, lead=shape[0], eps=shape[1])
    if effect == "sigmoid":
        return EffectTerm(effect, joint, 1.0, steepness=shape[0], shift=shape[1])
    return EffectTerm(effect, joint, 1.0)


class _Projector:
    """Weighted stacked residuals after the base's least-squares fit (for shape fitting)."""

    def __init__(self, base: np.ndarray, w: np.ndarray):
        self.w = w
        self.q = np.linalg.qr((base * w[None, :, None]).reshape(-1, base.shape[2]))[0]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        v = (x * self.w[None, :] if x.ndim == 2 else x * self.w[None, :, None]).reshape(
            x.shape[0] * x.shape[1], -1)
        return v - self.q @ (self.q.T @ v)


def fit_shape(effect: str, joint: int, project: _Projector, target: np.ndarray, states,
              load: np.ndarray | None = None) -> tuple:
    """The shape of a nonlinear effect on joint minimizing the projected residual of the
    target with the joint's viscous column and the effect's (load: the joints' load torque
    of a `load_friction`)."""
    viscous = project(effect_torque((_unit("viscous", joint),), *states))

    def rss(shape) -> float:
        col = project(effect_torque((_unit(effect, joint, shape),), *states, load=load))
        X = np.concatenate([viscous, col], axis=1)
        c, *_ = np.linalg.lstsq(X, target, rcond=None)
        return float(np.sum((target - X @ c) ** 2))

    if effect in ("coulomb", "load_friction"):
        grid, lo, hi = COULOMB_SHAPES, (LEAD_RANGE[0], np.log(EPS_RANGE[0])), (LEAD_RANGE[1],
                                                                              np.log(EPS_RANGE[1]))
        to_x, from_x = (lambda s: (s[0], np.log(s[1]))), (lambda x: (x[0], np.exp(x[1])))
    else:
        grid = SIGMOID_SHAPES
        lo, hi = (np.log(STEEPNESS_RANGE[0]), SHIFT_RANGE[0]), (np.log(STEEPNESS_RANGE[1]),
                                                                 SHIFT_RANGE[1])
        to_x, from_x = (lambda s: (np.log(s[0]), s[1])), (lambda x: (np.exp(x[0]), x[1]))
    start = min(grid, key=rss)
    res = minimize(lambda x: rss(from_x(np.clip(x, lo, hi))), to_x(start), method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-9, "maxiter": 150})
    best = tuple(float(v) for v in from_x(np.clip(res.x, lo, hi)))
    return best if rss(best) <= rss(start) else start


def candidates(project: _Projector, target: np.ndarray, states, dof: int,
               effects=MEASURED_EFFECTS) -> list[EffectTerm]:
    """Unit-coefficient candidate terms on every joint, nonlinear shapes fitted."""
    out = []
    for j in range(1, dof + 1):
        for e in effects:
            shape = fit_shape(e, j, project, target, states) if e in ("coulomb", "sigmoid") else ()
            out.append(_unit(e, j, shape))
    return out


def _physical(base, target, cols, w, subset, terms, scales: Scales) -> bool:
    """Whether every coefficient of the subset's joint fit lies in its range."""
    coef = weighted_fit(base, target, cols[:, :, subset], w)[1]
    return all(scales.holds(replace(terms[i], coefficient=float(c)))
               for i, c in zip(subset, coef, strict=True))


def forward_by_validation(cv: BlockValidation, base, target, cols, w, terms,
                          scales: Scales) -> tuple:
    """Effects added while one cuts its joint's validation error power by >= MIN_GAIN."""
    chosen: list[int] = []
    sse = cv.sse([])
    path = [("", float(np.sum(sse)))]
    while True:
        trials = []
        for i, t in enumerate(terms):
            if i in chosen:
                continue
            new = cv.sse(chosen + [i])
            gain = 1.0 - new[t.joint - 1] / max(sse[t.joint - 1], 1e-300)
            trials.append((float(np.sum(new)), gain, i, new))
        usable = [tr for tr in sorted(trials) if tr[1] >= MIN_GAIN]
        unphysical = set()
        step = None
        for tr in usable:
            if _physical(base, target, cols, w, chosen + [tr[2]], terms, scales):
                step = tr
                break
            unphysical.add(tr[2])
        if step is None:
            return chosen, tuple(path), sse, _reasons(trials, terms, unphysical)
        chosen.append(step[2])
        sse = step[3]
        t = terms[step[2]]
        path.append((f"{t.effect}@{t.joint}", step[0]))


def _reasons(trials, terms, unphysical: set[int]) -> tuple[tuple[int, str, float, str], ...]:
    """Per joint, the best candidate left when selection stopped, its gain and why it was
    not named."""
    out = []
    for j, i, gain in best_left(terms, ((t[1], t[2]) for t in trials)):
        why = ("its coefficient would leave its physical range" if i in unphysical else
               f"cuts the validation error power by {gain:.1%} < {MIN_GAIN:.0%}")
        out.append((j, f"{terms[i].effect}", float(gain), why))
    return tuple(out)


def close_loop_measured(library: KinematicLibrary, q, qd, qdd, tau, holdout: float = 0.25,
                        effects=MEASURED_EFFECTS, scales: Scales | None = None) -> MeasuredLoop:
    """Identify the rigid body (library: its atoms, no joint atoms) on the first 1 - holdout
    of the samples, trace its residual to named effects, add them, score on the rest;
    scales: the robot's, which bound every named coefficient (identification.closeloop.verdicts.ranges;
    None: the signs only)."""
    dof = library.dof
    q, qd, qdd, tau, _, split = check_data(q, qd, qdd, tau, tau, dof, holdout)
    tr, held = slice(0, split), slice(split, None)
    states = (q[tr], qd[tr], qdd[tr])
    rigid = identify(*states, tau[tr], library, holdout=0.0).model
    declared = WithOffsets(rigid, rigid.offsets)
    kept = np.flatnonzero(rigid.coefficients)
    base = np.concatenate([library.evaluate(*states)[:, :, kept],
                           np.broadcast_to(np.eye(dof), (split, dof, dof))], axis=2)
    residual = tau[tr] - declared.torque(*states)
    w = 1.0 / np.maximum(np.sqrt(np.mean(residual**2, axis=0)), 1e-12)
    project = _Projector(base, w)
    terms = candidates(project, project(tau[tr]), states, dof, effects)
    cols = np.stack([effect_torque((t,), *states) for t in terms], axis=2)
    cv = BlockValidation.build(base, tau[tr], cols, w, VALIDATION_BLOCKS)
    chosen, path, sse_after, not_named = forward_by_validation(cv, base, tau[tr], cols, w, terms,
                                                               scales or unbounded(dof))
    sse_before = cv.sse([])
    coef_base, coef = weighted_fit(base, tau[tr], cols[:, :, chosen], w)
    refit = np.zeros(len(library))
    refit[kept] = coef_base[:len(kept)]
    offsets = coef_base[len(kept):]
    named = tuple(EffectTerm(t.effect, t.joint, float(c), t.lead, t.eps, t.steepness, t.shift)
                  for t, c in zip((terms[i] for i in chosen), coef, strict=True))
    model = ExtendedModel(WithOffsets(KinematicModel(library, refit, offsets), offsets), named)
    norm = np.sum((tau[tr] * w) ** 2, axis=0)
    noise = noise_sigma(residual)
    noise_power = split * (noise * w) ** 2  # weighted, summed over the validated rows

    def structure(sse: np.ndarray) -> np.ndarray:
        return np.sqrt(np.maximum(sse - noise_power, 0.0) / np.maximum(noise_power, 1e-300))
    return MeasuredLoop(
        declared=declared, model=model, terms=named,
        error_before=rel_error(declared.torque(q[held], qd[held], qdd[held]), tau[held]),
        error_after=rel_error(model.torque(q[held], qd[held], qdd[held]), tau[held]),
        validation_before=np.sqrt(sse_before / norm), validation_after=np.sqrt(sse_after / norm),
        structure_before=structure(sse_before), structure_after=structure(sse_after),
        noise=noise,
        path=path, not_named=not_named, split=split)
