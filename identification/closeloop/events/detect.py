"""The world in a log: intervals where an external torque acts (a push, a bump, a part caught),
found with the declared model and left out of every fit and score of the loop.

1. The observer's external-torque estimate r (events.observer: a generalized-momentum
   observer on the declared model, no acceleration needed).
2. Less the robot's own persistent effects (events.persistent: a robust fit per joint on
   functions of the state), so an event is what no function of the state explains. A function
   of the pose is fitted only outside the events the other columns find first: under a stiff
   position loop a push deflects the arm, so during a push the torque is a function of the
   (deflected) pose, and a fit that sees the push would explain it so; fitted elsewhere, the
   function must predict the event's samples, which a tendon's or a spring's does and a
   push's does not. A function that moves only at a few instants of the run (an arm held
   still moves only while pushed) is no persistent effect (persistent.moving_columns).
3. The threshold: the robust scale of what is left (1.4826 x its median absolute deviation per
   joint). An event is found where a joint exceeds ON scales, reaches back while that joint
   exceeds OFF (hysteresis, never into the event before) and lasts while a joint that
   exceeded ON in it exceeds OFF, at least MIN_DURATION long (shorter excursions are the
   robot's own: the shipped Panda log's joint 7 at its velocity reversals, 70-145 ms;
   docs/closeloop.md). Its onset is the change point of that joint's rise: the step through
   the observer's lag that fits it best (change_point), not where it crossed a threshold,
   which comes late by the time the rise takes to reach it and early by any level left
   before it. Where the log's velocity was smoothed (a Savitzky-Golay derivative of the
   positions, as `ingest` and `generate --mode measured` estimate it), the step is fitted
   through that smoothing too (events.smoothing): the smear shows a push up to a third of
   the window early, and a fit of the lag alone put those onsets before the push.
4. Its samples and MARGIN on each side are left out, the persistent fit is made again
   without them, and detection repeats until the events stop changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.closeloop.events.observer import GAIN, low_pass, observer
from identification.closeloop.events.persistent import (
    persistent_residual,
    state_columns,
)
from identification.closeloop.events.smoothing import StateSmoothing, lag_response
from identification.errors import IdentificationError

ON = 8.0  # robust scales of the residual: an event starts where a joint exceeds it
OFF = 3.0  # ... and lasts while a joint exceeds this (hysteresis)
LOOKBACK = 0.2  # s before an event's rise above OFF searched for its change point
RISE = 3.0 / GAIN  # s after the crossing the change point's fit sees (three time constants)
# LOOKBACK and RISE were set on development draws (the push case's seeds 1-2, Lynxmotion) and
# synthetic steps (tests/test_event_onset.py), never on the study's or the bench's
MIN_DURATION = 0.15  # s: shorter excursions are the robot's own (module docstring, 3.)
MARGIN = 0.1  # s left out on each side of an event (the observer's lag is 1 / GAIN = 20 ms)
ROUNDS = 4  # persistent fit and detection, again without the events, at most


@dataclass(frozen=True)
class Event:
    """An interval (s, in the dataset's own time) of external torque; peak: the observer's
    estimate per joint (N m) where it is largest; joints: those (1-based) above ON."""

    start: float
    end: float
    peak: tuple[float, ...]
    joints: tuple[int, ...]

    def to_json(self) -> dict:
        return {"start": self.start, "end": self.end, "peak": list(self.peak),
                "joints": list(self.joints)}


@dataclass(frozen=True)
class Events:
    """The events of a log and how they were found; kept (n,) bool: the samples outside every
    event and its margin (what the loop fits and scores on)."""

    events: tuple[Event, ...]
    threshold: np.ndarray  # (dof,) N m: ON x scale
    scale: np.ndarray  # (dof,) N m: the robust scale of the observer's residual
    kept: np.ndarray
    rounds: int
    t: np.ndarray | None = None  # (n,) s: the run's times
    residual: np.ndarray | None = None  # (n, dof) N m: the observer's estimate less the
    # persistent effects, about its median (what the threshold is compared with)
    smoothing: StateSmoothing | None = None  # the log's velocity estimate, the onsets fit it

    def to_json(self) -> dict:
        return {"events": [e.to_json() for e in self.events],
                "threshold": self.threshold.tolist(), "scale": self.scale.tolist(),
                "observer_gain": GAIN, "samples_left_out": int(np.sum(~self.kept)),
                "rule": (f"generalized-momentum observer on the declared model (gain {GAIN:g} "
                         "1/s); persistent effects (offset, viscous and dry friction, the "
                         "declared torque's scale, the load's body) removed by a bisquare fit; "
                         f"an event is found above {ON:g} robust scales (1.4826 x the median "
                         f"absolute deviation per joint) and lasts while above {OFF:g}, at least "
                         f"{MIN_DURATION * 1e3:.0f} ms; its onset the likelihood-ratio change "
                         "point of a step through the observer's lag"
                         + (" and the log's velocity smoothing" if self.smoothing else "")
                         + f"; its samples and {MARGIN:g} s each side are left out of every fit "
                         "and score"),
                "state_smoothing": None if self.smoothing is None else self.smoothing.to_json()}

    def line(self) -> str:
        """One line for the command's output."""
        if not self.events:
            return "external torque: no event (threshold " + ", ".join(
                f"{v:.3g}" for v in self.threshold) + " N m)"
        spans = ", ".join(f"{e.start:.1f}-{e.end:.1f} s" for e in self.events[:6])
        spans += ", ..." if len(self.events) > 6 else ""
        peaks = np.array([np.abs(e.peak) for e in self.events])
        k, j = np.unravel_index(np.argmax(peaks), peaks.shape)
        return (f"external torque: {len(self.events)} event{'s' * (len(self.events) > 1)} "
                f"({spans}; peak {peaks[k, j]:.3g} N m on joint {j + 1}), left out of the "
                "effects")


def change_point(v: np.ndarray, t: np.ndarray, lo: int, k: int,
                 smoothing: StateSmoothing | None = None) -> float:
    """When a rise of v (n,), robust scales, crossing ON at sample k began (s): the
    likelihood-ratio change point of a step through the observer's own lag (a matched
    filter): over onsets t0 from t[lo] to t[k] a quarter sample apart,
    the one whose response level + A (1 - exp(-GAIN (t - t0))), A > 0, fits v[lo:k + RISE]
    best in least squares. A level before the event (what the persistent fit left) is the
    fit's constant rather than part of the event; a noise sample does not move the onset as
    the edge of a band would. smoothing: the log's velocity estimate, whose response to the
    step replaces the lag's (events.smoothing), onsets then searched up to its lead after
    t[k] (the smear crosses before the step)."""
    stop = min(len(v), k + int(np.ceil(RISE / max(t[k] - t[k - 1], 1e-12))) + 1)
    seg, at = v[lo:stop], t[lo:stop]
    last = t[k] + (0.0 if smoothing is None else smoothing.lead)
    starts = np.arange(t[lo], last, (t[k] - t[k - 1]) / 4)
    if len(starts) == 0:
        return float(t[k])
    response = lag_response if smoothing is None else smoothing.response
    h = response(at[None, :] - starts[:, None])
    h -= h.mean(axis=1, keepdims=True)
    fit = h @ (seg - seg.mean())
    score = np.where(fit > 0, fit**2 / np.maximum(np.sum(h**2, axis=1), 1e-300), -np.inf)
    return float(starts[int(np.argmax(score))])


def intervals(z: np.ndarray, t: np.ndarray,
              smoothing: StateSmoothing | None = None) -> list[tuple[int, int, float]]:
    """Events in z (n, dof), the signed residual in robust scales: [start, end) sample ranges
    and each one's onset (s). An event is found where a joint first exceeds ON in size, from
    where that joint, signed as its crossing, last rose above OFF, and lasts while any joint
    that exceeded ON in it exceeds OFF, at least MIN_DURATION long (never reaching into the
    event before: events a calm gap separates stay apart). Its onset is that joint's change
    point (change_point, searched from LOOKBACK s before its rise above OFF; smoothing: the
    log's velocity estimate, whose side lobe before a large step is passed over for the
    step's own crossing), its samples from there (or from the lobe's crossing, if earlier)."""
    n, size = len(z), np.abs(z)
    if not np.all(np.isfinite(z)):  # a NaN is never above ON nor below OFF: no event ends
        raise IdentificationError("the external-torque residual is not finite")
    out: list[tuple[int, int, float]] = []
    k = floor = 0
    while k < n:
        if np.max(size[k]) <= ON:
            k += 1
            continue
        j = int(np.argmax(size[k]))
        v = np.sign(z[k, j]) * z[:, j]
        cross = k
        if smoothing is not None:  # a large step's smear dips the other way before it rises
            # (the window's side lobe): the joint and sign are the largest excursion's within
            # half a window, its onset from where it crosses ON
            ahead = min(n, k + int(np.ceil(smoothing.window_s / 2 / (t[k] - t[k - 1]))) + 1)
            m, j = np.unravel_index(np.argmax(size[k:ahead]), size[k:ahead].shape)
            v = np.sign(z[k + m, j]) * z[:, j]
            cross = k + int(np.argmax(v[k:] > ON))
        rise = cross  # back while that joint exceeds OFF with the crossing's sign (hysteresis)
        while rise > floor and v[rise - 1] > OFF:
            rise -= 1
        active = size[k] > ON
        b = k
        while b < n and np.any(size[b, active] > OFF):
            active |= size[b] > ON
            b += 1
        if t[b - 1] - t[rise] >= MIN_DURATION:
            lo = max(floor, int(np.searchsorted(t, t[rise] - LOOKBACK)))
            when = change_point(v, t, lo, cross, smoothing) if cross > lo else float(t[cross])
            out.append((min(int(np.searchsorted(t, when)), k), b, when))
            floor = b
        k = b
    return out


def find_events(model, t, q, qd, qdd, tau, body=None, scales=None,
                smoothing: StateSmoothing | None = None) -> Events:
    """External-torque events of a log (t (n,) s; q, qd, qdd, tau (n, dof)) against the
    declared torque model; body: the load's body's regressor (state_columns), or None; scales:
    the robot's (identification.closeloop.verdicts.ranges), which bound the persistent effects (None:
    unbounded); smoothing: how the log's velocity was estimated (None: logged or unknown)."""
    t = np.asarray(t, float)
    r = observer(model, t, q, qd, tau)
    dt = float(np.median(np.diff(t)))
    plain = [(low_pass(c, dt), b) for c, b in state_columns(model, q, qd, qdd, body, False,
                                                            scales)]
    full = [(low_pass(c, dt), b) for c, b in state_columns(model, q, qd, qdd, body, True,
                                                           scales)]
    kept = np.ones(len(t), bool)
    kept[: int(np.ceil(3.0 / (GAIN * dt)))] = False  # the observer's start-up transient
    settle = kept.copy()
    found: list[tuple[int, int, float]] = []
    rounds = 0
    while rounds < ROUNDS:
        rounds += 1
        res, scale = persistent_residual(r, plain if rounds == 1 else full, kept)
        z = (res - np.median(res[kept], axis=0)) / scale
        z[~settle] = 0.0
        spans = intervals(z, t, smoothing)
        new = settle.copy()
        for a, b, _ in spans:
            new &= ~((t >= t[a] - MARGIN) & (t <= t[b - 1] + MARGIN))
        if spans == found and rounds > 1:
            break
        found, kept = spans, new
    events = []
    for a, b, when in found:
        seg = res[a:b] - np.median(res[kept], axis=0)
        peak = seg[np.argmax(np.abs(seg), axis=0), np.arange(seg.shape[1])]
        joints = tuple(int(j) + 1 for j in np.flatnonzero(np.max(np.abs(z[a:b]), axis=0) > ON))
        events.append(Event(when, float(t[b - 1]), tuple(map(float, peak)), joints))
    kept_out = np.ones(len(t), bool)
    for a, b, _ in found:
        kept_out &= ~((t >= t[a] - MARGIN) & (t <= t[b - 1] + MARGIN))
    return Events(tuple(events), ON * scale, scale, kept_out, rounds, t,
                  res - np.median(res[kept], axis=0), smoothing)
