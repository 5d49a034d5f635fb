"""A scored run's sensor offset, never fitted on the samples it scores.

A torque sensor's offset is a property of a run (re-zeroed, warmed up, re-mounted), not of
the robot. The error a model makes on a run it was not fitted on is scored with the run's
offset taken from samples the score does not count:

- the run's first rest: the samples at its start before any joint moves faster than
  REST_SPEED (at least MIN_REST of them), where the sensor reads the model's torque (gravity)
  plus its offset; those samples are then left out of the score;
- the part of the run the fit was trained on, where the scored samples are its last part
  (a --holdout) and it has no rest at its start;
- none, where a run scored whole has no rest at its start: the offset is taken as 0 and
  the score says so.

The same rule gives `predict --offset-from-rest` its offset, so that a model written by the
loop reproduces the loop's scores (harness.commands.predict).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.metrics import rel_error

REST_SPEED = 0.01  # rad/s: a joint slower than this is at rest (a log's speed noise is below)
MIN_REST = 10  # samples: a shorter stillness at a run's start is no rest to calibrate on


def first_rest(qd: np.ndarray) -> int:
    """The samples at the run's start before any joint moves faster than REST_SPEED; 0 if
    there are fewer than MIN_REST of them."""
    moving = np.flatnonzero(np.any(np.abs(np.asarray(qd)) > REST_SPEED, axis=1))
    count = len(qd) if moving.size == 0 else int(moving[0])
    return count if count >= MIN_REST else 0


def residual_offset(model, samples: tuple) -> np.ndarray:
    """(dof,) the mean of tau - model over samples (q, qd, qdd, tau)."""
    q, qd, qdd, tau = samples[:4]
    return np.mean(tau - model.torque(q, qd, qdd), axis=0)


@dataclass(frozen=True)
class ScoredRun:
    """The samples (q, qd, qdd, tau) a run is scored on, the samples its offset is taken
    from (None: no offset known, 0) and what those are."""

    scored: tuple
    calibration: tuple | None
    source: str

    def offset(self, model) -> np.ndarray:
        if self.calibration is None:
            return np.zeros(self.scored[0].shape[1])
        return residual_offset(model, self.calibration)

    def to_json(self) -> dict:
        return {"scored_samples": int(len(self.scored[0])),
                "offset_samples": 0 if self.calibration is None else
                int(len(self.calibration[0])), "offset_from": self.source}


def _cut(run: tuple, start: int, stop: int | None = None) -> tuple:
    return tuple(a[start:stop] for a in run)


def whole_run(run: tuple) -> ScoredRun:
    """A run scored whole (a --validate log): its offset from its first rest, which is not
    scored; none known without one (nor for a run that never moves: its rest is all of it)."""
    rest = first_rest(run[1])
    if rest and len(run[1]) - rest >= MIN_REST:
        return ScoredRun(_cut(run, rest), _cut(run, 0, rest),
                         f"its first rest ({rest} samples before the motion, not scored)")
    return ScoredRun(run, None, "none known (no rest before the motion): 0 N m")


def run_tail(trained: tuple, held: tuple) -> ScoredRun:
    """The last part of a run (held), its first part trained on: the offset from the run's
    first rest, else from the trained part."""
    rest = first_rest(trained[1])
    if rest:
        return ScoredRun(held, _cut(trained, 0, rest),
                         f"the run's first rest ({rest} samples before the motion)")
    return ScoredRun(held, trained, "the run's trained samples (no rest before the motion)")


def scored_offsets(model, runs: list[ScoredRun]) -> np.ndarray:
    """(runs, dof) N m: each run's offset under model."""
    return np.array([r.offset(model) for r in runs])


def scored_error(model, runs: list[ScoredRun]) -> np.ndarray:
    """(dof,) relative error ||tau_hat - tau|| / ||tau|| over the runs' scored samples, tau_hat
    the model's torque plus each run's offset (taken where ScoredRun says)."""
    estimate = np.concatenate([model.torque(*r.scored[:3]) + r.offset(model) for r in runs])
    return rel_error(estimate, np.concatenate([r.scored[3] for r in runs]))
