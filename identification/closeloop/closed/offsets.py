"""A scored run's sensor offset: one rule for identify, closeloop and predict, never fitted on
the samples it scores.

A torque sensor's offset is a property of a run (re-zeroed, warmed up, re-mounted), not of
the robot. The rule (held_out_offset): a scored run's offset is the model's mean residual
on the samples it was trained on,

- the run's own trained samples where the scored samples continue a run trained on (a
  --holdout tail: one sensor zero, nothing re-zeroed between);
- else every training run's samples, pooled (a run never trained on: a --validate run, or
  a log given to `predict`, which reads that figure from the model file's
  sensor_offsets.new_run; a model file without one: the model's own fitted offset, 0 for a
  model without).

Never from a rest: a run at rest reads the model's torque (gravity) plus its offset plus the
static friction that holds each joint still, anywhere in the joint's band [-Fs, Fs], so on a
joint whose torque is small against its friction a rest's reading is not the offset. Chosen
by `torquebench study offset_rule` over the first rest, none, both rests, a blend and a
per-joint choice between rest and training runs, on simulated runs with static friction and
on the real Panda log (docs/identification.md, 'A held-out run's sensor offset').
`predict --offset-from-rest` still reads a log's first rest (first_rest, residual_offset),
on request.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from identification.metrics import rel_error

REST_SPEED = 0.01  # rad/s: a joint slower than this is at rest (a log's speed noise is below)
MIN_REST = 10  # samples: a shorter stillness at a run's start is no rest to calibrate on
RULE = ("a scored run's sensor offset is the model's mean residual on the samples it was "
        "trained on: the run's own trained samples where the scored samples continue a run "
        "trained on (a --holdout tail), else every training run's, pooled (a run never "
        "trained on: a --validate run, a log given to predict, which reads it as "
        "sensor_offsets.new_run); never from the samples scored, never from a rest, whose "
        "reading holds the joints' static friction (identification.closeloop.closed.offsets; "
        "torquebench study offset_rule)")
SAME_RUN = "the run's trained samples (the same sensor zero)"
RECORDED = ("the model file's offset for a new run (sensor_offsets.new_run; else the model's "
            "fitted offset)")


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


def pooled(runs: list[tuple]) -> tuple:
    """The runs' samples (q, qd, qdd, tau) as one."""
    return tuple(np.concatenate([r[i] for r in runs]) for i in range(4))


def held_out_offset(model, trained: list[tuple] | np.ndarray) -> np.ndarray:
    """The rule (module docstring): (dof,) N m, the model's mean residual on the trained
    samples given (runs (q, qd, qdd, tau), pooled), or the offset a model file records for
    a new run (an array, taken as it is)."""
    if isinstance(trained, np.ndarray):
        return np.asarray(trained, float).reshape(model.dof)
    return residual_offset(model, pooled(trained))


@dataclass(frozen=True, eq=False)
class ScoredRun:
    """The samples (q, qd, qdd, tau) a run is scored on and the trained samples (runs) its
    offset is taken from (held_out_offset); source says which."""

    scored: tuple
    trained: list[tuple]
    source: str
    _memo: list = field(default_factory=list, repr=False)  # [(model, offset)]

    def offset(self, model) -> np.ndarray:
        for known, offset in self._memo:
            if known is model:
                return offset
        offset = held_out_offset(model, self.trained)
        self._memo.append((model, offset))
        return offset

    def to_json(self, model=None) -> dict:
        out = {"scored_samples": int(len(self.scored[0])),
               "offset_samples": int(sum(len(r[0]) for r in self.trained)),
               "offset_from": self.source,
               "offset_rule": "same run" if self.source == SAME_RUN else "training runs"}
        if model is not None:
            out["offset"] = self.offset(model).tolist()
        return out


def whole_run(run: tuple, trained: list[tuple]) -> ScoredRun:
    """A run never trained on, scored whole, its offset from the training runs' samples."""
    count = sum(len(r[0]) for r in trained)
    return ScoredRun(run, list(trained), f"the training runs' samples ({len(trained)} runs, "
                                         f"{count} samples, pooled)")


def run_tail(trained: tuple, held: tuple) -> ScoredRun:
    """The last part of a run (held), its first part trained on: its offset from that part."""
    return ScoredRun(held, [trained], SAME_RUN)


def scored_offsets(model, runs: list[ScoredRun]) -> np.ndarray:
    """(runs, dof) N m: each run's offset under model."""
    return np.array([r.offset(model) for r in runs])


def scored_torques(model, runs: list[ScoredRun]) -> tuple[np.ndarray, np.ndarray]:
    """(the model's torque plus each run's offset, the measured torque) over the runs' scored
    samples, concatenated."""
    estimate = np.concatenate([model.torque(*r.scored[:3]) + r.offset(model) for r in runs])
    return estimate, np.concatenate([r.scored[3] for r in runs])


def scored_error(model, runs: list[ScoredRun]) -> np.ndarray:
    """(dof,) relative error ||tau_hat - tau|| / ||tau|| over the runs' scored samples, tau_hat
    the model's torque plus each run's offset (held_out_offset)."""
    return rel_error(*scored_torques(model, runs))
