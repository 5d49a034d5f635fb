"""Closing the loop on several runs of one robot, against the model the user declared.

A real effect does not change from one run of a robot to the next; the residual of
something else does. So, with the declared model D (the robot's nominal model, or a
MODEL.json) and the training runs:

1. Target: tau - D(q, qd, qdd) on every training run; the base refitted beside the effects
   is a constant sensor offset per joint and run (an offset is the run's, not the robot's;
   a held-out run in validation gets its own refitted). Rows of joint j weigh 1 / (RMS of
   its target).
2. Candidates, per joint: `viscous`, `coulomb`, `armature`, `spring` (the Coulomb shape
   fitted by variable projection, identification.closeloop.selection.one_log.candidates),
   `load_friction` (dry friction growing with the joint's load torque, its shape fitted:
   identification.closeloop.candidates.load_friction), when given, a payload on the last body
   (identification.closeloop.candidates.payload), and, when given, `inertial`: the rigid-body
   correction of the consistent fit pulled toward the declared model
   (identification.regression.consistent), one column acting on every joint, its
   coefficient a scale (1 = the consistent fit's correction).
3. Forward selection, validated run by run (leave one run out; one run alone: contiguous
   blocks of it). A candidate is named when it cuts its joint's validation error power by
   >= MIN_GAIN in total and on no held-out run makes any joint it acts on worse (one run
   alone: in total only, its blocks are too short to each decide), its coefficient lies in
   its physical range (identification.closeloop.verdicts.ranges), and its coefficient fitted on
   each run alone agrees with every other run's within AGREE combined standard errors (a
   run's error from the spread over RUN_BLOCKS blocks of it: coloured residuals make the
   white-noise formula far too small).
4. The model: D + the named effects, refitted jointly with the offsets on all training runs
   (named load friction: alternated with the load of the model fitted); an effect whose
   refitted coefficient leaves its range is dropped and the rest refitted.
   The offsets stay out of it: a sensor offset is a property of a run, not of the robot, so
   a new run is scored with its own offset refitted (identification.closeloop.closed.leftover).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm, effect_torque
from identification.closeloop.candidates.load_body import choose_body
from identification.closeloop.candidates.load_friction import (
    EFFECT,
    refit_under_load,
    spread_with_and_without,
    told_apart,
    with_payload,
)
from identification.closeloop.candidates.payload import (
    REACH,
    LastBody,
    com_spread,
    consistent_fit,
    named_payload,
    payload_column,
)
from identification.closeloop.closed.extended import ExtendedModel, closed_model
from identification.closeloop.selection.crossval import BlockValidation, weighted_fit
from identification.closeloop.selection.one_log import VALIDATION_BLOCKS, _Projector, candidates
from identification.closeloop.verdicts.agreement import (
    AGREE,
    MIN_GAIN,
    RUN_BLOCKS,
    not_named,
    per_run,
    rows_of,
    verdict,
)
from identification.closeloop.verdicts.ranges import Scales, unbounded
from identification.errors import IdentificationError
from identification.intervals import RULE, jackknife
from identification.torque_model import TorqueModel, as_states

RUNS_EFFECTS = ("viscous", "coulomb", "armature", "spring", EFFECT)  # the contract's joint
# effects (the offset is refitted as the base): one dry-friction name, so runs cannot split it
# between shapes; EFFECT: dry friction growing with the joint's load (load_friction)
FEWER = 0.05  # the rigid-body correction (10 parameters a body) is taken before the payload
# (10 in all) only if it predicts the validation runs 5 % better: a load is the likelier
MIN_RUN = 40  # samples: a run shorter than that cannot be validated on


@dataclass(frozen=True)
class Named:
    """A named effect: coefficient of the joint fit on all runs, and on each run alone."""

    term: EffectTerm
    per_run: tuple[float, ...]
    per_run_std: tuple[float, ...]  # standard error of each run's coefficient
    gain: float  # fraction of its joint's validation error power it removes
    physical: bool  # has a physical reading (see module docstring)
    detail: tuple = ()  # a payload's per-run figures (identification.closeloop.candidates.payload)
    interval: float = float("nan")  # the coefficient's 95 % half-width (intervals.jackknife)

    def to_json(self) -> dict:
        return {**self.term.to_json(), "interval_95": self.interval, "interval_rule": RULE,
                "per_run": list(self.per_run),
                "per_run_std": list(self.per_run_std), "validation_gain": self.gain,
                "physical_reading": self.physical, **dict(self.detail),
                **({"joints": "all"} if self.term.effect in ("inertial", "payload") else {})}


@dataclass(frozen=True)
class RunsLoop:
    """Outcome of the loop on training runs (scores are the caller's, on held-out runs)."""

    model: ExtendedModel  # declared + named effects (no sensor offset: that is a run's)
    named: tuple[Named, ...]
    offsets: np.ndarray  # (dof,) N m, run_offsets' mean over the training samples
    run_offsets: np.ndarray  # (runs, dof) N m, each training run's, fitted with the effects
    folds: str  # "runs" (leave one run out) or "blocks" (one run: contiguous blocks)
    path: tuple[tuple[str, float], ...]  # (label added, weighted validation power after)
    not_named: tuple[tuple[int, str, float, str], ...]  # per joint: best left, gain, why
    body_choice: dict = field(default_factory=dict)  # the load's body chosen by the data

    @property
    def terms(self) -> tuple[EffectTerm, ...]:
        return tuple(n.term for n in self.named)


def close_loop_runs(declared: TorqueModel, runs: list[tuple[np.ndarray, ...]],
                    inertial: TorqueModel | None = None,
                    effects=RUNS_EFFECTS, body: LastBody | tuple[LastBody, ...] | None = None,
                    reach: float = REACH, scales: Scales | None = None) -> RunsLoop:
    """Name the effects the declared model lacks on training runs [(q, qd, qdd, tau)] of one
    robot ((n_r, dof) each, rad, rad/s, rad/s^2, N m); inertial: the rigid-body correction
    candidate (a TorqueModel of the torque to add to declared), or None; body: the body whose
    payload (centre of mass within reach m of its joint) is a candidate, a tuple of candidate
    bodies the data choose among (identification.closeloop.candidates.load_body), or None;
    scales: the robot's, which bound every named coefficient (identification.closeloop.verdicts.ranges;
    None: the signs only)."""
    dof = declared.dof
    scales = scales or unbounded(dof)
    if not runs or any(len(r[0]) < MIN_RUN for r in runs):
        raise IdentificationError(f"every run needs at least {MIN_RUN} samples")
    q, qd, qdd, tau = (np.concatenate([r[i] for r in runs]) for i in range(4))
    q, qd, qdd = as_states(q, qd, qdd, dof)
    lengths = np.cumsum([0] + [len(r[0]) for r in runs])
    run_rows = [np.arange(a, b) for a, b in zip(lengths[:-1], lengths[1:], strict=True)]
    states = (q, qd, qdd)
    target = tau - declared.torque(*states)
    n = len(q)
    base = np.zeros((n, dof, dof * len(runs)))  # a sensor offset per joint and run
    for r, rows in enumerate(run_rows):
        base[rows, :, r * dof:(r + 1) * dof] = np.eye(dof)
    w = 1.0 / np.maximum(np.std(target, axis=0), 1e-12)
    project = _Projector(base, w)
    terms = candidates(project, project(target), states, dof, [e for e in effects if e != EFFECT])
    cols = [effect_torque((t,), *states) for t in terms]
    several = len(runs) > 1
    folds = run_rows if several else VALIDATION_BLOCKS
    choice: dict = {}
    if isinstance(body, tuple):  # candidate bodies: the data choose
        body, choice = choose_body(body, base, target, states, w, reach, folds, several)
    regressor = None if body is None else body(*states)

    def payload_fit(beside):
        if body is None:
            return None
        try:
            return payload_column(base, target, regressor, w, reach, beside)
        except ValueError:  # the conic fit failed (a held arm's calm runs): no candidate
            return None

    if EFFECT in effects:  # the load friction and the payload candidates, each knowing the other
        extra, more, payload = with_payload(project, target, declared.torque(*states), states,
                                            payload_fit)
        terms += extra
        cols += more
    else:
        payload = payload_fit(None)
    if inertial is not None:
        terms.append(EffectTerm("inertial", dof, 1.0))
        cols.append(inertial.torque(*states))
    if payload is not None:
        terms.append(EffectTerm("payload", body.joint or dof, 1.0, params=tuple(payload[1]),
                                body=body.name))
        cols.append(payload[0])
    cols = np.stack(cols, axis=2)
    cv = BlockValidation.build(base, target, cols, w, folds, refit_offset=several)
    chosen: list[int] = []
    sse = cv.sse_folds([])
    path = [("", float(np.sum(sse)))]
    found: list[tuple] = []
    rejected: dict[int, tuple] = {}
    while True:
        trials = []
        for i, t in enumerate(terms):
            if i not in chosen:
                new = cv.sse_folds(chosen + [i])
                rows = rows_of(t, dof)
                fold_gains = 1.0 - new[:, rows] / np.maximum(sse[:, rows], 1e-300)
                gain = 1.0 - np.sum(new[:, rows]) / max(np.sum(sse[:, rows]), 1e-300)
                trials.append((float(np.sum(new)), float(gain), i, new, fold_gains))
        step = None
        for total, gain, i, new, fold_gains in sorted(trials, key=lambda tr: tr[0] * (
                1.0 + FEWER * (terms[tr[2]].effect == "inertial" and payload is not None))):
            if gain < MIN_GAIN:
                continue
            subset = chosen + [i]
            coef = weighted_fit(base, target, cols[:, :, subset], w)[1][-1]
            coefs, stds = (per_run(base, target, cols[:, :, subset], w, run_rows)
                           if several else (np.array([coef]), np.array([0.0])))
            why = verdict(terms[i], fold_gains, coef, coefs, stds, several, scales)
            if why:
                rejected[i] = (gain, why)
                continue
            step = (total, gain, i, new, coefs, stds)
            break
        if step is None:
            break
        total, gain, i, sse, coefs, stds = step
        chosen.append(i)
        found.append((gain, coefs, stds))
        path.append((f"{terms[i].effect}@{terms[i].joint}", total))
    k = len(terms) - 1 if payload is not None else -1  # the payload candidate's index

    def fit(cols: np.ndarray) -> tuple:
        """The joint fit of the chosen: (base, chosen coefficients, payload parameters or
        None, the payload's per-run detail); a named payload's 10 parameters with the rest."""
        if k in chosen:
            return named_payload(base, target, cols, regressor, w, chosen, k, run_rows,
                                 RUN_BLOCKS, AGREE, reach)
        return (*weighted_fit(base, target, cols[:, :, chosen], w), None, {})

    def model_load(out: tuple) -> np.ndarray:
        """The closed model's torque without its load friction: the load it acts under."""
        rest = [replace(terms[i], coefficient=float(c), params=(
            tuple(map(float, out[2])) if i == k else terms[i].params))
            for i, c in zip(chosen, out[1], strict=True) if terms[i].effect != EFFECT]
        return closed_model(declared, np.zeros(dof), tuple(rest), inertial, body).torque(*states)

    columns = cols
    while True:  # a named coefficient refitted with the others must stay in its range
        (coef_base, coef, params, detail), cols = refit_under_load(fit, model_load, terms,
                                                                   columns, chosen, states)
        out = [(n, scales.why_not(replace(terms[i], coefficient=float(c))))
               for n, (i, c) in enumerate(zip(chosen, coef, strict=True))]
        out = [(n, why) for n, why in out if why]
        if not out:
            break
        for n, why in reversed(out):
            rejected[chosen[n]] = (found[n][0], why + ", refitted with the others")
            del chosen[n], found[n]
    others = [i for i in chosen if i != k]

    def coefficients(rows: np.ndarray) -> np.ndarray:
        """The chosen's coefficients fitted on rows (a payload's: its mass, then its centre of
        mass last), the load friction's columns as last fitted."""
        if k not in chosen:
            return weighted_fit(base[rows], target[rows], cols[rows][:, :, chosen], w)[1]
        try:
            _, c, p = consistent_fit(base[rows], target[rows], cols[rows][:, :, others],
                                     regressor[rows], w, reach)
        except ValueError:  # this fold's conic fit failed: left out of the jackknife
            return np.full(len(chosen) + 3, np.nan)
        values = {**dict(zip(others, c, strict=True)), k: p[0]}
        return np.concatenate([[values[i] for i in chosen], p[1:4] / max(p[0], 1e-12)])

    half = jackknife(coefficients, run_rows)[1] if chosen else np.zeros(0)
    if params is not None:
        detail = {**detail, "com_interval_95": half[len(chosen):].tolist()}
        terms[k] = replace(terms[k], params=tuple(map(float, params)))
        detail = spread_with_and_without(detail, lambda e: com_spread(
            base, target, cols[:, :, e], regressor, w, run_rows, RUN_BLOCKS, reach),
            [i for i in chosen if i != k], terms, AGREE)
        friction = [i for i in others if terms[i].effect == EFFECT]
        detail = told_apart(detail, params[0], half[chosen.index(k)], cols[:, :, k],
                            cols[:, :, friction], project)
    named = tuple(
        Named(replace(terms[i], coefficient=float(c)), tuple(map(float, pr)),
              tuple(map(float, ps)), g, scales.holds(replace(terms[i], coefficient=float(c))),
              tuple(detail.items()) if i == k else (), float(h))
        for i, c, (g, pr, ps), h in zip(chosen, coef, found, half[:len(chosen)], strict=True))
    model = closed_model(declared, np.zeros(dof), tuple(x.term for x in named), inertial, body)
    run_offsets = coef_base.reshape(len(runs), dof)
    mean = np.average(run_offsets, axis=0, weights=np.diff(lengths))
    return RunsLoop(model, named, mean, run_offsets, "runs" if several else "blocks",
                    tuple(path), not_named(terms, chosen, rejected, trials), choice)
