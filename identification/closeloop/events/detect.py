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
   push's does not.
3. The threshold: the robust scale of what is left (1.4826 x its median absolute deviation per
   joint). An event starts where a joint exceeds ON scales, reaches back while that joint
   exceeds OFF (hysteresis) and lasts while a joint that exceeded ON in it exceeds OFF, at
   least MIN_DURATION long (shorter excursions are the robot's own: the shipped Panda log's
   joint 7 at its velocity reversals, 70-145 ms; docs/closeloop.md).
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

ON = 8.0  # robust scales of the residual: an event starts where a joint exceeds it
OFF = 3.0  # ... and lasts while a joint exceeds this (hysteresis)
MIN_DURATION = 0.15  # s: shorter excursions are the robot's own (module docstring, 3.)
MARGIN = 0.1  # s left out on each side of an event (the observer's lag is 1 / GAIN = 20 ms)
ROUNDS = 4  # persistent fit and detection, again without the events, at most
RISE = 0.1  # s after an event crosses ON over which its rise is measured (onset)
RISE_SHARE = 0.25  # the share of that rise which marks the onset


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

    def to_json(self) -> dict:
        return {"events": [e.to_json() for e in self.events],
                "threshold": self.threshold.tolist(), "scale": self.scale.tolist(),
                "observer_gain": GAIN, "samples_left_out": int(np.sum(~self.kept)),
                "rule": (f"generalized-momentum observer on the declared model (gain {GAIN:g} "
                         "1/s); persistent effects (offset, viscous and dry friction, the "
                         "declared torque's scale, the load's body) removed by a bisquare fit; "
                         f"an event starts above {ON:g} robust scales (1.4826 x the median "
                         f"absolute deviation per joint) and lasts while above {OFF:g}, at least "
                         f"{MIN_DURATION * 1e3:.0f} ms; its samples and {MARGIN:g} s each side "
                         "are left out of every fit and score")}

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


def _intervals(z: np.ndarray, t: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) sample ranges of events in z (n, dof), robust scales: from where a joint
    first exceeds ON, back while that joint exceeds OFF and on while any joint that exceeded
    ON in it exceeds OFF; at least MIN_DURATION long."""
    n = len(z)
    out: list[tuple[int, int]] = []
    k = 0
    while k < n:
        if np.max(z[k]) <= ON:
            k += 1
            continue
        first = int(np.argmax(z[k]))
        a = k
        while a > 0 and z[a - 1, first] > OFF:
            a -= 1
        active = z[k] > ON
        b = k
        while b < n and np.any(z[b, active] > OFF):
            active |= z[b] > ON
            b += 1
        if t[b - 1] - t[a] >= MIN_DURATION:
            out.append((a, b))
        k = b
    return out


def onset(z: np.ndarray, t: np.ndarray, a: int, b: int) -> float:
    """When the external torque of the event at samples [a, b) began (s): where the first
    joint to cross ON first reaches RISE_SHARE of its rise over RISE s from that crossing,
    less the observer's own lag to that share of a step (-ln(1 - RISE_SHARE) / GAIN). A
    threshold crossing comes early or late with the push's size and the states' smoothing (a
    Savitzky-Golay derivative spreads a push's start both ways, 20-30 ms early on development
    draws; 60-75 ms early on an arm held still, whose noise is small); a share of the rise over
    RISE does not depend on the size. RISE and RISE_SHARE were chosen on development draws
    (seeds 101-103 and 1-2 on the three arms of the pushes study, moving and held), never on
    the study's or the bench's."""
    k = a + int(np.argmax(np.max(z[a:b], axis=1) > ON))
    j = int(np.argmax(z[k]))
    stop = min(b, int(np.searchsorted(t, t[k] + RISE)) + 1)
    half = RISE_SHARE * float(np.max(z[k:stop, j]))
    first = a + int(np.argmax(z[a:stop, j] >= half))
    return float(max(t[a], t[first] + np.log(1.0 - RISE_SHARE) / GAIN))


def find_events(model, t, q, qd, qdd, tau, body=None, scales=None) -> Events:
    """External-torque events of a log (t (n,) s; q, qd, qdd, tau (n, dof)) against the
    declared torque model; body: the load's body's regressor (state_columns), or None; scales:
    the robot's (identification.closeloop.verdicts.ranges), which bound the persistent effects (None:
    unbounded)."""
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
    found: list[tuple[int, int]] = []
    rounds = 0
    while rounds < ROUNDS:
        rounds += 1
        res, scale = persistent_residual(r, plain if rounds == 1 else full, kept)
        z = np.abs(res - np.median(res[kept], axis=0)) / scale
        z[~settle] = 0.0
        spans = _intervals(z, t)
        new = settle.copy()
        for a, b in spans:
            new &= ~((t >= t[a] - MARGIN) & (t <= t[b - 1] + MARGIN))
        if spans == found and rounds > 1:
            break
        found, kept = spans, new
    events = []
    for a, b in found:
        seg = res[a:b] - np.median(res[kept], axis=0)
        peak = seg[np.argmax(np.abs(seg), axis=0), np.arange(seg.shape[1])]
        joints = tuple(int(j) + 1 for j in np.flatnonzero(np.max(z[a:b], axis=0) > ON))
        events.append(Event(onset(z, t, a, b), float(t[b - 1]), tuple(map(float, peak)), joints))
    kept_out = np.ones(len(t), bool)
    for a, b in found:
        kept_out &= ~((t >= t[a] - MARGIN) & (t <= t[b - 1] + MARGIN))
    return Events(tuple(events), ON * scale, scale, kept_out, rounds, t,
                  res - np.median(res[kept], axis=0))
