"""Derivative estimation from uniformly sampled signals: the one place it is done.

Savitzky-Golay differentiation (scipy.signal.savgol_filter): a zero-phase
local-polynomial fit, the standard offline choice for identification. Used for
the simulated encoder angles of `generate --mode measured` and for measured logs
that lack velocities or accelerations (`ingest`).

For a measured log the window is chosen from the data (`choose_window`): the
signal's power spectrum (Welch) is split into the signal's band and the noise (what
lies above the band, and its level carried into the band), and the window is the one
minimizing the predicted error of the derivatives: the filter's bias on the signal,
|H(f) - (i 2 pi f)^d|^2 S(f), plus the noise it lets through, |H(f)|^2 N(f), summed
over frequencies. A narrow window passes noise, a wide one bends the signal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_coeffs, savgol_filter, welch

from identification.closeloop.events.smoothing import StateSmoothing

BAND_POWER = 1e-3  # the band holds all but this fraction of the signal's power above the floor
NOISE_BAND = 3.0  # the noise level within the band is read over this many band widths above it
TAIL = 10.0  # above the band, a bin counts as noise up to this many times the noise level
MIN_WINDOW = 5


def odd_window(window_s: float, rate: float, n: int) -> int:
    """The odd window length (samples) closest above window_s seconds at rate Hz, at most n."""
    window = int(round(window_s * rate)) | 1
    if window > n:
        window = n if n % 2 else n - 1
    return window


def savgol_window_derivatives(x: np.ndarray, rate: float, window: int, polyorder: int,
                              orders=(0, 1, 2)) -> tuple[np.ndarray, ...]:
    """The smoothed signal and its derivatives of the given orders, x sampled at rate Hz
    along axis 0, window an odd number of samples. Units: those of x per s**order."""
    kw = dict(window_length=window, polyorder=min(polyorder, window - 1), axis=0, mode="interp")
    return tuple(savgol_filter(x, deriv=k, delta=1.0 / rate, **kw) if k else
                 savgol_filter(x, deriv=0, **kw) for k in orders)


def savgol_derivatives(x: np.ndarray, rate: float, window_s: float, polyorder: int,
                       orders=(0, 1, 2)) -> tuple[np.ndarray, ...]:
    """As savgol_window_derivatives with the window given in seconds (window_s)."""
    return savgol_window_derivatives(x, rate, odd_window(window_s, rate, len(x)), polyorder,
                                     orders)


def spectrum(x: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Power spectral density of the columns of x (n, k) sampled at rate Hz: the frequencies
    (F,) in Hz and the densities (F, k), units of x^2 / Hz (0 at f = 0).

    Welch's estimate with a Blackman-Harris window (sidelobes -92 dB), on the first
    difference of x divided back by the difference's gain |2 sin(pi f / rate) rate|^2: a
    smooth signal's spectrum spans many decades, and the difference flattens it so the
    window's leakage from the signal's lines stays below the noise."""
    x = np.asarray(x, dtype=float).reshape(len(x), -1)
    nperseg = min(len(x) - 1, 1 << int(np.log2(max(len(x) // 2, 8))))
    f, p = welch(np.diff(x, axis=0) * rate, fs=rate, window="blackmanharris", nperseg=nperseg,
                 axis=0, detrend="linear")
    gain = (2 * np.sin(np.pi * f / rate) * rate) ** 2
    p = np.divide(p, gain[:, None], out=np.zeros_like(p), where=gain[:, None] > 0)
    return f, p


def band_edge(f: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Per column of the spectrum p (F, k): the frequency (Hz) below which the signal holds
    all but BAND_POWER of its power above the noise floor (the spectrum's median: a smooth
    signal occupies few of its bins). The upper edge of the bin, so the band is never
    underestimated by the resolution."""
    above = np.maximum(p - np.median(p, axis=0), 0.0)
    total = np.maximum(above.sum(axis=0), 1e-300)
    k = np.array([np.searchsorted(c, 1.0 - BAND_POWER) for c in (np.cumsum(above, 0) / total).T])
    return f[np.minimum(k, len(f) - 1)] + 0.5 * (f[1] - f[0])


def response(window: int, polyorder: int, deriv: int, rate: float, nfft: int) -> np.ndarray:
    """Frequency response H(f) of the Savitzky-Golay filter of order deriv (window odd,
    samples) at the nfft // 2 + 1 frequencies j rate / nfft, j = 0.. (the Welch bins)."""
    c = savgol_coeffs(window, polyorder, deriv=deriv, delta=1.0 / rate, use="conv")
    h = np.zeros(nfft)
    h[(np.arange(window) - window // 2) % nfft] = c
    return np.fft.rfft(h)


@dataclass(frozen=True)
class WindowChoice:
    """A Savitzky-Golay window chosen from a signal: samples, seconds, and why."""

    window: int  # samples (odd)
    rate: float  # Hz
    polyorder: int
    band_hz: list[float]  # each column's band edge
    predicted: dict[int, list[float]]  # derivative order -> predicted relative RMS error per column

    @property
    def seconds(self) -> float:
        return self.window / self.rate

    def to_json(self) -> dict:
        return {"method": "savitzky-golay", "window_samples": self.window,
                "window_s": self.seconds, "polyorder": self.polyorder,
                "band_edge_hz": self.band_hz,
                "predicted_rel_error": {str(d): e for d, e in self.predicted.items()},
                "rule": "window minimizing the predicted error of the derivatives (bias on the "
                        "signal's band + noise passed), from the Welch spectrum"}


def _error_spectra(f: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, ...]:
    """Band edges, signal and noise spectra (F, k). The noise level is the median of the
    spectrum over the NOISE_BAND band widths above the band; the noise is that level within
    the band and the spectrum above it, capped at TAIL times the level (a bin far above the
    level just past the edge is the signal's last trace, which no window should be credited
    for removing); the signal is what the band holds above the level."""
    edge = band_edge(f, p)
    signal, noise = np.zeros_like(p), p.copy()
    for j in range(p.shape[1]):
        inside = f <= edge[j]
        near = (f > edge[j]) & (f <= (1 + NOISE_BAND) * edge[j])
        level = float(np.median(p[near, j])) if near.any() else float(np.median(p[:, j]))
        signal[inside, j] = np.maximum(p[inside, j] - level, 0.0)
        noise[inside, j] = level
        noise[~inside, j] = np.minimum(p[~inside, j], TAIL * level)
    return edge, signal, noise


def choose_window(x: np.ndarray, rate: float, polyorder: int, orders=(1, 2)) -> WindowChoice:
    """The odd window (at most a quarter of the samples and one Welch segment) minimizing
    the predicted error of the derivatives of the given orders of x (n, k), summed over
    orders and columns, each relative to its derivative's power. Predicted from the Welch
    spectrum P = S + N: error power sum_f |H(f) - (i 2 pi f)^d|^2 S(f) + |H(f)|^2 N(f)."""
    f, p = spectrum(x, rate)
    nfft = 2 * (len(f) - 1)
    edge, signal, noise = _error_spectra(f, p)
    exact = {d: (2j * np.pi * f) ** d for d in orders}
    power = {d: np.maximum(np.sum(np.abs(exact[d][:, None]) ** 2 * signal, 0), 1e-300)
             for d in orders}
    low = max(MIN_WINDOW, (polyorder + 2) | 1)
    high = max(low, min(len(x) // 4, nfft) - 1 | 1)  # odd, <= the limit unless below low
    candidates = sorted({int(w) | 1 for w in np.geomspace(low, high, 60)} & set(range(low, high + 1)))

    def predicted(window: int) -> dict[int, np.ndarray]:
        out = {}
        for d in orders:
            h = response(window, polyorder, d, rate, nfft)
            err = (np.abs(h - exact[d])[:, None] ** 2 * signal + np.abs(h)[:, None] ** 2 * noise)
            out[d] = np.sqrt(np.sum(err, 0) / power[d])
        return out

    scores = [(sum(float(np.sum(e ** 2)) for e in predicted(w).values()), w) for w in candidates]
    best = min(scores)[1]
    return WindowChoice(best, rate, polyorder, edge.tolist(),
                        {d: e.tolist() for d, e in predicted(best).items()})


def state_smoothing(meta: dict) -> StateSmoothing | None:
    """How a dataset's velocity was estimated, from its meta: the Savitzky-Golay derivative of
    the angles `generate --mode measured` simulates (meta `sensors`) or of the positions
    `ingest` resampled (meta `derivatives`, when qd was estimated from q); None when the
    velocity was logged, simulated exactly or the meta does not say."""
    sensors = meta.get("sensors")
    if isinstance(sensors, dict) and {"window", "polyorder", "sensing_rate"} <= sensors.keys():
        return StateSmoothing(float(sensors["window"]), int(sensors["polyorder"]),
                              float(sensors["sensing_rate"]))
    described = meta.get("derivatives")
    if (isinstance(described, dict) and described.get("method") == "savitzky-golay"
            and described.get("source") == "q" and "qd" in described.get("estimated", ())):
        return StateSmoothing(float(described["window_s"]), int(described["polyorder"]),
                              described["window_samples"] / described["window_s"])
    return None
