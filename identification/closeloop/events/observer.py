"""The generalized-momentum observer (De Luca & Mattone, ICRA 2005; Haddadin, De Luca &
Albu-Schaeffer, T-RO 2017): an external torque's estimate from the declared torque model, the
joint positions and velocities and the measured torque, no acceleration needed.

With p = M(q) qd the robot obeys dp/dt = tau + tau_ext - beta(q, qd), beta = n(q, qd) -
dM/dt qd, n the torque at zero acceleration, so r = K (p - p(0) - int (tau - beta + r))
follows tau_ext through a first-order lag of time constant 1 / K. Every quantity comes from
the declared torque model alone: M(q) v = torque(q, 0, v) - torque(q, 0, 0), n = torque(q, qd,
0), and dM/dt qd by a central difference of M(q) qd along qd. Discretely, between samples
k-1 and k,

    e_k = (p_k - p_{k-1}) / dt_k - ((tau - beta)_k + (tau - beta)_{k-1}) / 2,
    r_k = a r_{k-1} + (1 - a) e_k,   a = exp(-K dt),

the exact first-order low-pass of e, stable for every sample time.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

GAIN = 50.0  # 1/s: the observer follows an external torque with a 20 ms time constant
STEP = 1e-4  # rad per (rad/s): the central difference of M(q) qd along qd


def momentum_terms(model, q, qd) -> tuple[np.ndarray, np.ndarray]:
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
    p, beta = momentum_terms(model, q, qd)
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
