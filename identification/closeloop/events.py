"""The world in a log: intervals where an external torque acts (a push, a bump, a part caught),
found with the declared model and left out of every fit and score of the loop.

A generalized-momentum observer (De Luca & Mattone, ICRA 2005; Haddadin, De Luca &
Albu-Schaeffer, T-RO 2017) needs no acceleration: with p = M(q) qd the robot obeys
dp/dt = tau + tau_ext - beta(q, qd), beta = n(q, qd) - dM/dt qd, n the torque at zero
acceleration, so r = K (p - p(0) - int (tau - beta + r)) follows tau_ext through a first-order
lag of time constant 1 / K. Every quantity comes from the declared torque model alone:
M(q) v = torque(q, 0, v) - torque(q, 0, 0), n = torque(q, qd, 0), and dM/dt qd by a central
difference of M(q) qd along qd. Discretely, between samples k-1 and k,

    e_k = (p_k - p_{k-1}) / dt_k - ((tau - beta)_k + (tau - beta)_{k-1}) / 2,
    r_k = a r_{k-1} + (1 - a) e_k,   a = exp(-K dt),

the exact first-order low-pass of e, stable for every sample time.

On a real log r also carries what the model lacks (friction, a payload, a spring or tendon,
a scale error of the drive gains): persistent effects, functions of the robot's state. Those
are removed before detection by a robust fit per joint (Tukey's bisquare, iteratively
reweighted) of r on the same low-pass of state columns (an offset, viscous and dry friction,
the declared torque's scale, every joint's q, sin q and cos q, the load's body's ten
parameters), so an event is what no smooth function of the state explains. The threshold is
the robust scale of what is left (1.4826 x its median absolute deviation per joint): an
event starts where a joint exceeds ON scales, reaches back while that joint exceeds OFF
(hysteresis) and lasts while a joint that exceeded ON in it exceeds OFF, at least
MIN_DURATION long. Its
samples and MARGIN on each side are left out, the persistent fit is made again without
them, and detection repeats until the events stop changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

GAIN = 50.0  # 1/s: the observer follows an external torque with a 20 ms time constant
ON = 8.0  # robust scales of the residual: an event starts where a joint exceeds it
OFF = 3.0  # ... and lasts while a joint exceeds this (hysteresis)
MIN_DURATION = 0.15  # s: shorter excursions are the robot's own (see module docstring)
MARGIN = 0.1  # s left out on each side of an event (the observer's lag is 1 / GAIN = 20 ms)
ROUNDS = 4  # persistent fit and detection, again without the events, at most
BISQUARE = 4.685  # Tukey's constant (95 % efficiency at Gaussian residuals)
FRICTION_WIDTH = 0.02  # rad/s, the dry-friction column's tanh width
RISE = 0.05  # s after an event crosses ON over which its rise is measured (onset)
RISE_SHARE = 0.25  # the share of that rise which marks the onset
STEP = 1e-4  # rad per (rad/s): the central difference of M(q) qd along qd


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


def _momentum_terms(model, q, qd) -> tuple[np.ndarray, np.ndarray]:
    """p = M(q) qd and beta = n(q, qd) - dM/dt qd, (n, dof) each, from the torque model."""
    zero = np.zeros_like(q)

    def mass_times(at, v):
        return model.torque(at, zero, v) - model.torque(at, zero, zero)

    p = mass_times(q, qd)
    h = STEP
    m_dot_qd = (mass_times(q + h * qd, qd) - mass_times(q - h * qd, qd)) / (2 * h)
    return p, model.torque(q, qd, zero) - m_dot_qd


def _lag(dt: float) -> float:
    return float(np.exp(-GAIN * dt))


def low_pass(x: np.ndarray, dt: float) -> np.ndarray:
    """The observer's filter on a signal of the state (n, ...): its trapezoid average between
    samples through a r_k = a r_{k-1} + (1 - a) x_k lag, from rest at the first sample."""
    x = np.asarray(x, float)
    mid = np.concatenate([np.zeros_like(x[:1]), (x[1:] + x[:-1]) / 2])
    a = _lag(dt)
    return lfilter([1.0 - a], [1.0, -a], mid, axis=0)


def observer(model, t, q, qd, tau) -> np.ndarray:
    """The momentum observer's external-torque estimate r (n, dof) in N m."""
    p, beta = _momentum_terms(model, q, qd)
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ValueError("time stamps must increase")
    drive = tau - beta
    e = np.zeros_like(p)
    e[1:] = np.diff(p, axis=0) / dt[:, None] - (drive[1:] + drive[:-1]) / 2
    a = np.exp(-GAIN * dt)
    if np.ptp(dt) <= 1e-6 * np.mean(dt):  # evenly sampled: one filter call
        return lfilter([1.0 - a[0]], [1.0, -a[0]], e, axis=0)
    r = np.zeros_like(e)
    for k in range(1, len(e)):
        r[k] = a[k - 1] * r[k - 1] + (1 - a[k - 1]) * e[k]
    return r


def state_columns(model, q, qd, qdd, body=None) -> list[np.ndarray]:
    """Per joint j, the (n, k) torques of the persistent effects the detection removes: an
    offset, viscous and dry friction, the declared torque's scale, a smooth function of the
    arm's pose (every joint's q, sin q and cos q: a spring, a tendon, a gravity error), and,
    with body (a callable (q, qd, qdd) -> (n, dof, 10), the load's body's regressor), its ten
    parameters' torque on j."""
    declared = model.torque(q, qd, qdd)
    pose = np.concatenate([q, np.sin(q), np.cos(q)], axis=1)
    load = None if body is None else np.asarray(body(q, qd, qdd), float)
    out = []
    for j in range(q.shape[1]):
        own = np.stack([np.ones(len(q)), qd[:, j], np.tanh(qd[:, j] / FRICTION_WIDTH),
                        declared[:, j]], axis=1)
        parts = [own, pose] + ([] if load is None else [load[:, j, :]])
        out.append(np.concatenate(parts, axis=1))
    return out


def _robust_scale(x: np.ndarray) -> np.ndarray:
    med = np.median(x, axis=0)
    return np.maximum(1.4826 * np.median(np.abs(x - med), axis=0), 1e-12)


def persistent_residual(r: np.ndarray, cols: list[np.ndarray], use: np.ndarray,
                        iterations: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """r minus, per joint, its bisquare fit on that joint's columns (both low-passed alike),
    fitted on the samples use; returns that residual (n, dof) and its robust scale (dof,) on
    those samples."""
    res = np.empty_like(r)
    for j, X in enumerate(cols):
        X = X / np.maximum(np.sqrt(np.mean(X[use] ** 2, axis=0)), 1e-12)
        y, weight = r[:, j], np.ones(len(r))
        out = y.copy()
        for _ in range(iterations):
            w = np.sqrt(weight[use])
            coef = np.linalg.lstsq(X[use] * w[:, None], y[use] * w, rcond=None)[0]
            out = y - X @ coef
            u = out / (BISQUARE * _robust_scale(out[use]))
            weight = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
        res[:, j] = out
    return res, _robust_scale(res[use])


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
    draws); a share of the rise does not depend on the size. Chosen on development draws
    (seeds 101-103 on the three arms of the pushes study), never on the study's."""
    k = a + int(np.argmax(np.max(z[a:b], axis=1) > ON))
    j = int(np.argmax(z[k]))
    stop = min(b, int(np.searchsorted(t, t[k] + RISE)) + 1)
    half = RISE_SHARE * float(np.max(z[k:stop, j]))
    first = a + int(np.argmax(z[a:stop, j] >= half))
    return float(max(t[a], t[first] + np.log(1.0 - RISE_SHARE) / GAIN))


def find_events(model, t, q, qd, qdd, tau, body=None) -> Events:
    """External-torque events of a log (t (n,) s; q, qd, qdd, tau (n, dof)) against the
    declared torque model; body: the load's body's regressor (state_columns), or None."""
    t = np.asarray(t, float)
    r = observer(model, t, q, qd, tau)
    dt = float(np.median(np.diff(t)))
    cols = [low_pass(c, dt) for c in state_columns(model, q, qd, qdd, body)]
    kept = np.ones(len(t), bool)
    kept[: int(np.ceil(3.0 / (GAIN * dt)))] = False  # the observer's start-up transient
    settle = kept.copy()
    found: list[tuple[int, int]] = []
    rounds = 0
    while rounds < ROUNDS:
        rounds += 1
        res, scale = persistent_residual(r, cols, kept)
        z = np.abs(res - np.median(res[kept], axis=0)) / scale
        z[~settle] = 0.0
        spans = _intervals(z, t)
        new = settle.copy()
        for a, b in spans:
            new &= ~((t >= t[a] - MARGIN) & (t <= t[b - 1] + MARGIN))
        if spans == found:
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


def run_events(model, runs, times, body=None) -> list[Events]:
    """find_events on each run (q, qd, qdd, tau, ...) with its times (n,) s."""
    return [find_events(model, t, *run[:4], body) for run, t in zip(runs, times, strict=True)]


def without_events(run: tuple, events: Events) -> tuple:
    """The run's arrays (each (n, ...)) on the samples outside its events and their margins."""
    return tuple(a[events.kept] for a in run)


def events_json(files, found: list[Events]) -> dict:
    """closeloop.json's `events` (each with the file of its run) and `event_detection`."""
    events = [{**e.to_json(), "file": str(f)} for f, ev in zip(files, found, strict=True)
              for e in ev.events]
    runs = [{"file": str(f), **{k: v for k, v in ev.to_json().items()
                                if k not in ("events", "rule", "observer_gain")}}
            for f, ev in zip(files, found, strict=True)]
    rule = found[0].to_json()["rule"] if found else ""
    return {"events": events, "event_detection": {"observer_gain": GAIN, "rule": rule,
                                                  "runs": runs}}


def events_line(files, found: list[Events]) -> str:
    """One line for all the runs (a run's file named where there are several)."""
    if len(found) == 1:
        return found[0].line()
    with_events = [(f, ev) for f, ev in zip(files, found, strict=True) if ev.events]
    if not with_events:
        return f"external torque: no event in {len(found)} runs"
    return "; ".join(f"{f}: {ev.line()}" for f, ev in with_events)
