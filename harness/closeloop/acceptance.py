"""Acceptance of one closed loop, scored against the plant's true effects.

- named: the set of (effect, joint) named equals the plant's (nothing for a plant
  without undeclared effects); not checked when the plant carries an effect outside
  the dictionary. With the identified declared model, "the plant's" excludes effects its
  kept terms span exactly (`absorbed`: an armature where it kept qdd_j, a payload): the
  identified model carries those already, and no data can attribute them.
- coefficients: each within 10 % of the plant's value.
- improved: held-out error after <= 1/5 of before (against the clean torque) on every
  joint a named-able effect acts on.
- absorbed_not_worse: on the joints only absorbed effects act on (nothing to name, so
  nothing to improve by 5x), the error after is not above the error before; these joints
  are listed in the report (`absorbed_joints`), never dropped silently.
- noise_bar: what the noise allows on the same data, judged against the clean torque (the
  truth is known here). On every joint, the extended model's held-out error against the
  clean torque (`error_after`) is within 1.5x of the noise floor (`noise_floor`: the
  declared model plus the plant's true effect set, refitted on the same training part and
  scored on the same held-out samples). A missing or wrong effect leaves its torque in that
  error and fails it. (Against the measured torque both errors are dominated by the noise,
  and the bar would hold for nearly any model.)
- not_worse (a plant with an effect outside the dictionary): error after <= before on
  every joint.
- unexplained: equals "the plant carries an effect outside the dictionary".

Reported beside them (`reference_ratios`): error after / noise floor (the bar's ratio: 1
when the names are right), error after / truth error (true coefficients, clean torque: any
fitted coefficient costs about sqrt(k / n) noise sigmas there) and the same against the
measured torque.
"""

from __future__ import annotations

import numpy as np

from harness.closeloop.plant import CloseLoopRun

COEFFICIENT_TOLERANCE = 0.10
IMPROVEMENT = 5.0
FLOOR_FACTOR = 1.5
NOISE_BAR = "error_after <= 1.5 x noise_floor, both against the clean torque"


def _joints(terms, dof: int) -> set[int]:
    if any(t.effect == "payload" for t in terms):
        return set(range(dof))
    return {t.joint - 1 for t in terms}


def affected_joints(run: CloseLoopRun) -> list[int]:
    """0-based joints the nameable true effects act on (a payload acts on all)."""
    return sorted(_joints(run.expected, run.data.q.shape[1]))


def absorbed_joints(run: CloseLoopRun) -> list[int]:
    """0-based joints only absorbed true effects act on."""
    dof = run.data.q.shape[1]
    return sorted(_joints(run.truth, dof) - _joints(run.expected, dof))


def coefficient_errors(run: CloseLoopRun) -> dict[str, float]:
    """Relative coefficient error of each true effect that was named."""
    named = {(t.effect, t.joint): t.coefficient for t in run.result.terms}
    return {f"{t.effect}@{t.joint}": abs(named[(t.effect, t.joint)] - t.coefficient)
            / abs(t.coefficient) for t in run.expected if (t.effect, t.joint) in named}


def meets_noise_bar(error: np.ndarray, floor: np.ndarray) -> bool:
    """Every joint's error against the clean torque within FLOOR_FACTOR of the noise floor."""
    return bool(np.all(np.asarray(error) <= FLOOR_FACTOR * np.asarray(floor)))


def checks(run: CloseLoopRun) -> dict[str, bool]:
    """Pass/fail of each acceptance criterion that applies to this plant."""
    r = run.result
    out = {"unexplained": bool(r.unexplained) == run.outside_dictionary}
    if run.outside_dictionary:
        out["not_worse"] = bool(np.all(r.error_after <= r.error_before))
        return out
    named = {(t.effect, t.joint) for t in r.terms}
    out["named"] = named == {(t.effect, t.joint) for t in run.expected}
    errs = coefficient_errors(run)
    out["coefficients"] = len(errs) == len(run.expected) and all(
        e <= COEFFICIENT_TOLERANCE for e in errs.values())
    joints = affected_joints(run)
    if joints:
        out["improved"] = bool(np.all(r.error_after[joints] * IMPROVEMENT <= r.error_before[joints]))
    absorbed = absorbed_joints(run)
    if absorbed:
        out["absorbed_not_worse"] = bool(np.all(r.error_after[absorbed] <= r.error_before[absorbed]))
    out["noise_bar"] = meets_noise_bar(r.error_after, run.noise_floor)
    return out


def reference_ratios(run: CloseLoopRun) -> dict[str, list[float]]:
    """Per joint: error after / each reference (the noise bar's ratio is the required one)."""
    r = run.result
    pairs = (("truth_error_measured", r.error_after_measured, run.truth_error_measured),
             ("noise_floor", r.error_after, run.noise_floor),
             ("truth_error", r.error_after, run.truth_error))
    return {name: (after / np.maximum(ref, 1e-300)).tolist() for name, after, ref in pairs
            if ref is not None}
