"""The measured loop, as its steps; each step a folder of identification/closeloop:

1. events/: the declared model's external-torque estimate on every run (a momentum observer),
   the world's transients (a push, a bump) found and left out of every later step
   (`leave_out_events`);
2. the split: training runs, and the scored runs (the --validate runs, or the last holdout of
   every run), each scored run with its sensor offset by the rule identify and predict use
   (closed/offsets.py);
3. candidates/: what the declared model may lack: joint effects (effects.py), load friction
   (load_friction.py), a payload on one of the bodies the data choose among (payload.py,
   load_body.py), the rigid-body correction (inertial.py);
4. selection/: which candidates the training data name: validated run by run
   (selection/runs.py), on one log's validation blocks (selection/one_log.py), or by BIC on a
   simulated plant (selection/plant.py, plant_identified.py);
5. verdicts/: named only in its physical range (verdicts/ranges.py) and where it holds from
   one run to the next (verdicts/agreement.py);
6. closed/: the closed model, one composition of the declared model and the named terms
   (closed/extended.py), scored before and after, and what it leaves per joint
   (closed/leftover.py, noise_level.py).

Every path of `closeloop` enters here, at its own function, and every path starts with step 1:

- runs of a robot against a fixed declared model (`--data`, `--validate`): `close_the_loop`;
- one log whose declared model is its own rigid-body identification (`--data --declared
  identified`): `close_the_log`;
- a simulated plant (`--plant`): `leave_out_events`, then `close_the_plant` for each declared
  model compared.

What a robot is (its model, its load's body, its scales, the rigid-body correction's fit) is
the caller's (harness/robots: bodies.py, scales.py; the command's files in harness/closeloop):
this module sees arrays and torque models only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from identification.closeloop.candidates.payload import REACH, LastBody
from identification.closeloop.closed.leftover import Leftover, leftover
from identification.closeloop.closed.offsets import (
    ScoredRun,
    run_tail,
    scored_error,
    scored_offsets,
    whole_run,
)
from identification.closeloop.events.detect import Events
from identification.closeloop.events.runs import run_events, without_events
from identification.closeloop.selection.one_log import MeasuredLoop, close_loop_measured
from identification.closeloop.selection.plant import CloseLoopResult, close_loop
from identification.closeloop.selection.plant_identified import close_loop_identified
from identification.closeloop.selection.runs import RunsLoop, close_loop_runs
from identification.closeloop.verdicts.ranges import Scales
from identification.library.base import Library


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


def leave_out_events(declared, runs: list[tuple], times, body: LastBody | None = None,
                     scales: Scales | None = None, detect: bool = True,
                     smoothing=None) -> tuple[list[tuple], list[Events]]:
    """Step 1 of every path: the external torques on each run (q, qd, qdd, tau, ...) with its
    times (n,) s, found with the declared torque model (identification.closeloop.events;
    body: the load's body, scales: the robot's; smoothing: each run's velocity estimate,
    events.smoothing, or None), and each run's arrays (all of them, (n, ...)) without their
    samples; detect=False: every sample kept, no event looked for."""
    found = (run_events(declared, runs, times, body, scales, smoothing) if detect
             else no_events(runs, declared.dof))
    return [without_events(r, ev) for r, ev in zip(runs, found, strict=True)], found


def close_the_log(nominal, library, run: tuple, times, holdout: float = 0.25,
                  body: LastBody | None = None,
                  scales: Callable[[list[tuple]], Scales] | None = None,
                  smoothing=None) -> tuple[MeasuredLoop, tuple, Events]:
    """One log (q, qd, qdd, tau[, tau_clean]) against its own rigid-body identification
    (library: the robot's rigid-body atoms) on its first 1 - holdout: the events found with the
    nominal model and left out, then identification.closeloop.selection.one_log on what is kept.
    smoothing: the log's velocity estimate (events.smoothing) or None. Returns the loop, the
    kept arrays and the events."""
    (kept,), (found,) = leave_out_events(nominal, [run], [times], body,
                                         None if scales is None else scales([run[:4]]),
                                         smoothing=[smoothing])
    split = int(round(len(kept[0]) * (1.0 - holdout)))
    loop = close_loop_measured(library, *kept[:4], holdout,
                               scales=None if scales is None else scales(
                                   [tuple(a[:split] for a in kept[:4])]))
    return loop, kept, found


def close_the_plant(declared, run: tuple, holdout: float = 0.25, payload=None,
                    scales: Callable[[list[tuple]], Scales] | None = None) -> CloseLoopResult:
    """A simulated plant's run (q, qd, qdd, tau, tau_clean) without its events (step 1,
    leave_out_events, is the caller's: once for every declared model it compares) against a
    fixed declared torque model, or a library (identification.library.base.Library) the
    declared model is identified with on the training part: the plant loop
    (identification.closeloop.selection.plant / .identified); payload: the unit payload torque at the
    flange (its `symbolic` form for the planner); scales(runs) -> the robot's scales."""
    split = int(round(len(run[0]) * (1.0 - holdout)))
    train_scales = None if scales is None else scales([tuple(a[:split] for a in run[:4])])
    loop = close_loop_identified if isinstance(declared, Library) else close_loop
    return loop(declared, *run[:5], holdout, payload,
                None if payload is None else payload.symbolic, scales=train_scales)


def close_the_loop(declared, runs: list[tuple], times, held: list[tuple] | None = None,
                   held_times=None, holdout: float = 0.25,
                   body: LastBody | tuple[LastBody, ...] | None = None,
                   scales: Callable[[list[tuple]], Scales] | None = None,
                   inertial: Callable[[list[tuple]], object] | None = None,
                   reach: float = REACH, detect: bool = True, smoothing=None,
                   held_smoothing=None) -> LoopOutcome:
    """The loop on runs [(q, qd, qdd, tau)] with their times [(n,)] s against the declared
    torque model; held: the scored runs (None: the last holdout of every run); body: the
    load's body, or candidates the data choose among; scales(runs) -> the robot's scales on
    those samples; inertial(train) -> the rigid-body correction candidate or None;
    detect=False: no event looked for; smoothing, held_smoothing: each run's velocity estimate
    (events.smoothing) or None."""
    carrier = body[0] if isinstance(body, tuple) else body  # the last body's, for events
    robot = None if scales is None else scales(runs)
    kept, found = leave_out_events(declared, runs, times, carrier, robot, detect, smoothing)
    if held is not None:
        held_kept, held_found = leave_out_events(declared, held, held_times, carrier, robot,
                                                 detect, held_smoothing)
        train = kept
        scored = [whole_run(r, train) for r in held_kept]
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
