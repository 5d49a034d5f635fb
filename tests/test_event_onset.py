"""Where an event starts (identification.closeloop.events.detect.intervals), on synthetic
observer signals whose onsets are known: a step of external torque through the observer's own
first-order lag (the closed form 1 - exp(-GAIN (t - t0))) over coloured noise of unit robust
scale, with what the real residual carries before a push (a level the persistent fit left)
and between two pushes (a calm gap)."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from identification.closeloop.events.detect import intervals
from identification.closeloop.events.observer import GAIN

DT = 0.005  # s, 200 Hz


def _noise(n: int, dof: int, seed: int) -> np.ndarray:
    """White noise through the observer's lag, rescaled to unit robust scale per joint."""
    a = np.exp(-GAIN * DT)
    x = lfilter([1 - a], [1, -a], np.random.default_rng(seed).normal(size=(n, dof)), axis=0)
    return x / (1.4826 * np.median(np.abs(x - np.median(x, axis=0)), axis=0))


def _step(t: np.ndarray, start: float, end: float) -> np.ndarray:
    """The observer's response (exact first-order lag) to a unit step over [start, end)."""
    on = np.where(t > start, 1 - np.exp(-GAIN * (t - start)), 0.0)
    off = np.where(t > end, 1 - np.exp(-GAIN * (t - end)), 0.0)
    return on - off


def test_a_step_onset_is_located_within_two_samples_after_a_level_left_before_it():
    t = np.arange(1600) * DT
    for seed, (start, size, level) in enumerate([(3.0013, 25.0, 0.0), (4.1027, 12.0, 4.0),
                                                 (2.5031, 60.0, -2.5), (5.0042, 10.0, 5.0)]):
        z = _noise(len(t), 2, seed)
        z[:, 1] += level * ((t > start - 0.6) & (t < start + 0.5))  # the persistent fit left
        z[:, 1] += size * _step(t, start, start + 0.5)
        (event,) = intervals(z, t)
        a, b, onset = event
        assert abs(onset - start) <= 2 * DT, (seed, onset, start)
        assert t[a - 1] < onset <= t[a] and abs(t[b - 1] - (start + 0.5)) < 0.1


def test_a_calm_gap_splits_two_pushes_and_each_keeps_its_onset():
    t = np.arange(1600) * DT
    z = _noise(len(t), 3, 7)
    first, second = (2.0021, 2.6), (2.8033, 3.4)  # 0.2 s between them, all joints calm
    z[:, 0] += 30.0 * _step(t, *first)
    z[:, 2] -= 6.0 * _step(t, *first)  # the first push felt below ON on joint 3 too
    z[:, 2] -= 14.0 * _step(t, *second)
    found = intervals(z, t)
    assert len(found) == 2
    for (a, b, onset), (start, end) in zip(found, (first, second), strict=True):
        assert abs(onset - start) <= 2 * DT
        assert t[a - 1] < onset <= t[a] and t[b - 1] < end + 0.1


def test_noise_alone_is_no_event():
    t = np.arange(4000) * DT
    assert intervals(_noise(len(t), 3, 11), t) == []


def test_a_column_that_moves_only_while_pushed_is_no_persistent_effect():
    from identification.closeloop.events.persistent import moving_columns

    t = np.arange(4000) * DT
    rng = np.random.default_rng(5)
    held = 1e-5 * rng.normal(size=len(t)) + 0.01 * _step(t, 7.0, 7.5)  # deflected while pushed
    moving = np.sin(2 * np.pi * 0.3 * t) + 0.01 * rng.normal(size=len(t))
    sign = np.tanh(np.cos(2 * np.pi * 0.2 * t) / 0.02)  # dry friction of a moving joint
    X = np.stack([held, moving, sign, np.ones(len(t))], axis=1)
    assert moving_columns(X).tolist() == [False, True, True, True]


class _Inertia:
    """A free rigid body on one joint: torque = I qdd (no gravity, no friction)."""

    dof = 1

    def __init__(self, inertia: float):
        self.inertia = inertia

    def torque(self, q, qd, qdd):
        return self.inertia * np.asarray(qdd, float)


def test_a_push_seen_through_a_savitzky_golay_velocity_keeps_its_onset():
    """A free body at rest pushed by a constant torque from t0 for 0.3 s, then back as long
    (it stops again: its angle's acceleration is +-push / inertia, integrated exactly at the
    samples, a parabola in each piece), its angle sampled at 2 kHz, its velocity estimated as the log's
    (harness.data.derivatives: Savitzky-Golay, 0.2 s window, order 4), sampled at 200 Hz, and
    the real observer run on it: the onset found with the log's smoothing is within two
    samples of t0; fitted through the lag alone it comes out early (the smear)."""
    from harness.data.derivatives import savgol_derivatives
    from identification.closeloop.events.detect import find_events
    from identification.closeloop.events.smoothing import StateSmoothing

    rate, window, order, inertia, push = 2000.0, 0.2, 4, 0.02, 0.3  # Hz, s, -, kg m^2, N m
    fine = np.arange(int(6.0 * rate)) / rate
    rng = np.random.default_rng(5)
    onsets = []
    for t0 in (2.0031, 3.5117):
        qdd = push / inertia * (((fine >= t0) & (fine < t0 + 0.3)).astype(float)
                                - ((fine >= t0 + 0.3) & (fine < t0 + 0.6)))
        qd = np.concatenate([[0.0], np.cumsum((qdd[1:] + qdd[:-1]) / 2) / rate])
        q = np.concatenate([[0.0], np.cumsum((qd[1:] + qd[:-1]) / 2) / rate])
        q = q + 1e-6 * rng.normal(size=len(q))  # an encoder's resolution
        q_est, qd_est, qdd_est = savgol_derivatives(q[:, None], rate, window, order, (0, 1, 2))
        pick = slice(0, len(fine), int(rate * DT))
        t = fine[pick]
        tau = 0.003 * rng.normal(size=(len(t), 1))  # the torque sensor's noise; the push is
        # external: the drive applies nothing
        smoothing = StateSmoothing(window, order, rate)
        found = [find_events(_Inertia(inertia), t, q_est[pick], qd_est[pick], qdd_est[pick],
                             tau, smoothing=s) for s in (smoothing, None)]
        (with_smoothing,), (lag_alone,) = (f.events[:1] for f in found)
        onsets.append((with_smoothing.start - t0, lag_alone.start - t0))
    for smeared, plain in onsets:
        assert abs(smeared) <= 2 * DT, onsets
        assert plain < -2 * DT, onsets
