"""Derivative estimation from uniformly sampled signals: the one place it is done.

Savitzky-Golay differentiation (scipy.signal.savgol_filter): a zero-phase
local-polynomial fit, the standard offline choice for identification. Used for
the simulated encoder angles of `generate --mode measured` and for measured logs
that lack velocities or accelerations.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter


def odd_window(window_s: float, rate: float, n: int) -> int:
    """The odd window length (samples) closest above window_s seconds at rate Hz, at most n."""
    window = int(round(window_s * rate)) | 1
    if window > n:
        window = n if n % 2 else n - 1
    return window


def savgol_derivatives(x: np.ndarray, rate: float, window_s: float, polyorder: int,
                       orders=(0, 1, 2)) -> tuple[np.ndarray, ...]:
    """The smoothed signal and its derivatives of the given orders, x sampled at rate Hz
    along axis 0; window_s in s. Units: those of x per s**order."""
    window = odd_window(window_s, rate, len(x))
    kw = dict(window_length=window, polyorder=min(polyorder, window - 1), axis=0, mode="interp")
    return tuple(savgol_filter(x, deriv=k, delta=1.0 / rate, **kw) if k else
                 savgol_filter(x, deriv=0, **kw) for k in orders)
