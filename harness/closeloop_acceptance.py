"""Acceptance of one closed loop (issue #6), scored against the plant's true effects.

- named: the set of (effect, joint) named equals the plant's (nothing for a plant
  without undeclared effects); not checked when the plant carries an effect outside
  the dictionary. With the identified declared model, "the plant's" excludes effects its
  kept terms span exactly (`absorbed`: an armature where it kept qdd_j, a payload): the
  identified model carries those already, and no data can attribute them.
- coefficients: each within 10 % of the plant's value.
- improved: held-out error after <= 1/5 of before on every joint an effect acts on.
- near_noise_floor: error after <= 1.5 x the noise floor (oracle refit) on every joint.
Reported beside them, not required: `near_truth_error`, error after <= 1.5 x the error of
the true effects at the plant's own coefficients (harness.closeloop, `truth_error`).
- unexplained: equals "the plant carries an effect outside the dictionary".
"""

from __future__ import annotations

import numpy as np

from harness.closeloop import CloseLoopRun

COEFFICIENT_TOLERANCE = 0.10
IMPROVEMENT = 5.0
FLOOR_FACTOR = 1.5


def affected_joints(run: CloseLoopRun) -> list[int]:
    """0-based joints the plant's true effects act on (a payload acts on all)."""
    dof = run.data.q.shape[1]
    if any(t.effect == "payload" for t in run.expected):
        return list(range(dof))
    return sorted({t.joint - 1 for t in run.expected})


def coefficient_errors(run: CloseLoopRun) -> dict[str, float]:
    """Relative coefficient error of each true effect that was named."""
    named = {(t.effect, t.joint): t.coefficient for t in run.result.terms}
    return {f"{t.effect}@{t.joint}": abs(named[(t.effect, t.joint)] - t.coefficient)
            / abs(t.coefficient) for t in run.expected if (t.effect, t.joint) in named}


def checks(run: CloseLoopRun) -> dict[str, bool]:
    """Pass/fail of each acceptance criterion that applies to this plant."""
    r = run.result
    out = {"unexplained": bool(r.unexplained) == run.outside_dictionary}
    if run.outside_dictionary:
        return out
    named = {(t.effect, t.joint) for t in r.terms}
    out["named"] = named == {(t.effect, t.joint) for t in run.expected}
    errs = coefficient_errors(run)
    out["coefficients"] = len(errs) == len(run.expected) and all(
        e <= COEFFICIENT_TOLERANCE for e in errs.values())
    joints = affected_joints(run)
    if joints:
        out["improved"] = bool(np.all(r.error_after[joints] * IMPROVEMENT <= r.error_before[joints]))
    out["near_noise_floor"] = bool(np.all(r.error_after <= FLOOR_FACTOR * run.noise_floor))
    return out


def floor_criteria(run: CloseLoopRun) -> dict[str, bool]:
    """Which reference error the error after is within FLOOR_FACTOR of, on every joint:
    the oracle refit (`noise_floor`, required) and the true coefficients (`truth_error`)."""
    after = run.result.error_after
    return {name: bool(np.all(after <= FLOOR_FACTOR * ref)) for name, ref in
            (("noise_floor", run.noise_floor), ("truth_error", run.truth_error)) if ref is not None}
