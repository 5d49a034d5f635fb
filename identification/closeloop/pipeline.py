"""The measured loop on runs of one robot, as its steps (`closeloop --data`):

1. residual and events: the declared model's external-torque estimate on every run, the
   world's transients found and left out (identification.closeloop.events);
2. the split: training runs, and the scored runs (the --validate runs, or the last holdout of
   every run), each scored run with its sensor offset by the rule identify and predict use:
   the model's mean residual on the training runs' samples, or on its own run's trained
   part for a holdout (identification.closeloop.offsets);
3. candidates, selection and verdicts on the training runs: joint effects, the load's body,
   load friction, the rigid-body correction, each named only in its physical range and where
   it holds run to run (identification.closeloop.runs, .verdicts, .ranges);
4. the closed model (the declared model and the named terms) scored before and after, and
   what it leaves per joint (identification.closeloop.leftover).

What a robot is (its model, its load's body, its scales, the rigid-body correction's fit) is
the caller's: this module sees arrays and torque models only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from identification.closeloop.events.detect import Events
from identification.closeloop.events.runs import run_events, without_events
from identification.closeloop.leftover import Leftover, leftover
from identification.closeloop.offsets import (
    ScoredRun,
    run_tail,
    scored_error,
    scored_offsets,
    whole_run,
)
from identification.closeloop.payload import REACH, LastBody
from identification.closeloop.ranges import Scales
from identification.closeloop.runs import RunsLoop, close_loop_runs


@dataclass(frozen=True)
class LoopOutcome:
    """The loop on runs: what it named, where, and how it scores."""

    loop: RunsLoop
    found: tuple[Events, ...]  # per run, training then scored: its external torques
    scored: list[ScoredRun]  # what each scored run is scored on, its offset from where
    error_before: np.ndarray  # (dof,) the declared model on the scored runs
    error_after: np.ndarray  # (dof,) the closed model
    heldout_offsets: np.ndarray  # (scored runs, dof) N m, each under the closed model
    left: Leftover  # what the closed model leaves on the scored runs
    inertial: object | None  # the rigid-body correction candidate (a TorqueModel) or None
    train: list[tuple]  # the training runs' samples the loop fitted on


def no_events(runs: list[tuple], dof: int) -> list[Events]:
    """Runs with no event looked for (every sample kept)."""
    return [Events((), np.zeros(dof), np.zeros(dof), np.ones(len(r[0]), bool), 0) for r in runs]


def close_the_loop(declared, runs: list[tuple], times, held: list[tuple] | None = None,
                   held_times=None, holdout: float = 0.25,
                   body: LastBody | tuple[LastBody, ...] | None = None,
                   scales: Callable[[list[tuple]], Scales] | None = None,
                   inertial: Callable[[list[tuple]], object] | None = None,
                   reach: float = REACH, detect: bool = True) -> LoopOutcome:
    """The loop on runs [(q, qd, qdd, tau)] with their times [(n,)] s against the declared
    torque model; held: the scored runs (None: the last holdout of every run); body: the
    load's body, or candidates the data choose among; scales(runs) -> the robot's scales on
    those samples; inertial(train) -> the rigid-body correction candidate or None;
    detect=False: no event looked for."""
    dof = declared.dof

    def events(of, at):
        if not detect:
            return no_events(of, dof)
        carrier = body[0] if isinstance(body, tuple) else body  # the last body's, for events
        return run_events(declared, of, at, carrier, None if scales is None else scales(runs))

    found = events(runs, times)
    if held is not None:
        held_found = events(held, held_times)
        train = [without_events(r, ev) for r, ev in zip(runs, found, strict=True)]
        scored = [whole_run(without_events(r, ev), train) for r, ev in zip(held, held_found,
                                                                           strict=True)]
        found = found + held_found
    else:
        cut = [int(round(len(r[0]) * (1.0 - holdout))) for r in runs]
        train, scored = [], []
        for r, c, ev in zip(runs, cut, found, strict=True):
            first, last = ev.kept[:c], ev.kept[c:]
            train.append(tuple(a[:c][first] for a in r))
            scored.append(run_tail(train[-1], tuple(a[c:][last] for a in r)))
    correction = None if inertial is None else inertial(train)
    loop = close_loop_runs(declared, train, correction, body=body, reach=reach,
                           scales=None if scales is None else scales(train))
    return LoopOutcome(loop, tuple(found), scored, scored_error(declared, scored),
                       scored_error(loop.model, scored), scored_offsets(loop.model, scored),
                       leftover(loop.model, [s.scored for s in scored]), correction, train)
