"""What a log's velocity estimate does to a push's onset.

A velocity estimated from the positions by a Savitzky-Golay derivative (zero phase: each
sample a fit over a window centred on it) shows a change before it happens: a step in the true
velocity rises in the estimate from about a third of the window before it. The observer's
momentum is built on that velocity, so its estimate of a push begins early by the same amount
(a push on the Lynxmotion's third link: its residual 10 robust scales up 28 ms before the push).
The change point (events.detect.change_point) fits a step through this response, the window's
and the observer's together, so the onset it gives is the step's, not the smear's.

A log whose velocity was logged (a drive's own estimate), or whose estimate is not known,
has no smoothing: the step is seen through the observer's lag alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.signal import lfilter, savgol_filter

from identification.closeloop.events.observer import GAIN

SPAN = 10.0 / GAIN  # s of the response kept after the step (ten of the observer's time constants)
START = 1e-3  # of the step: where the smeared response is said to begin


@dataclass(frozen=True)
class StateSmoothing:
    """The velocity estimated as the Savitzky-Golay derivative of the positions over window_s s
    (polynomial order polyorder) at rate Hz."""

    window_s: float
    polyorder: int
    rate: float

    @cached_property
    def _response(self) -> tuple[np.ndarray, np.ndarray]:
        window = int(round(self.window_s * self.rate)) | 1
        before = window  # samples before the step: the window's reach and more
        after = window + int(np.ceil(SPAN * self.rate))
        tau = np.arange(-before, after) / self.rate
        estimate = savgol_filter(np.maximum(tau, 0.0), window, min(self.polyorder, window - 1),
                                 deriv=1, delta=1.0 / self.rate, mode="interp")
        a = np.exp(-GAIN / self.rate)  # the observer's lag at the estimate's own rate
        return tau, lfilter([1.0 - a], [1.0, -a], estimate)

    def response(self, tau: np.ndarray) -> np.ndarray:
        """The observer's estimate of a unit step of external torque at 0, at times tau (s)."""
        grid, h = self._response
        return np.interp(tau, grid, h, left=0.0, right=h[-1])

    @property
    def lead(self) -> float:
        """s before the step where its response begins (START of the step)."""
        grid, h = self._response
        return float(-grid[np.argmax(h > START)])

    def to_json(self) -> dict:
        return {"method": "savitzky-golay", "window_s": self.window_s,
                "polyorder": self.polyorder, "rate": self.rate, "lead_s": self.lead}


def lag_response(tau: np.ndarray) -> np.ndarray:
    """The observer's estimate of a unit step at 0 when the velocity is not smoothed: its
    first-order lag."""
    return np.clip(1.0 - np.exp(-GAIN * tau), 0.0, None)
