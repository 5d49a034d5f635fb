"""Savitzky-Golay derivative estimation against the closed-form derivatives of a sine."""

import numpy as np
import pytest

from harness.data.derivatives import odd_window, savgol_derivatives


@pytest.mark.parametrize("rate", [200.0, 1000.0])
def test_derivatives_of_a_sine_match_the_closed_form(rate):
    t = np.arange(0.0, 4.0, 1.0 / rate)
    w = 2 * np.pi * 0.7
    x = np.stack([np.sin(w * t), 0.3 * np.cos(w * t)], axis=1)
    s, v, a = savgol_derivatives(x, rate, window_s=0.1, polyorder=4)
    inner = slice(len(t) // 10, -len(t) // 10)  # interior: the polynomial fits exactly there
    np.testing.assert_allclose(s[inner], x[inner], atol=1e-6)
    np.testing.assert_allclose(v[inner, 0], w * np.cos(w * t[inner]), atol=1e-4 * w)
    np.testing.assert_allclose(a[inner, 1], -0.3 * w**2 * np.cos(w * t[inner]), atol=1e-3 * w**2)


def test_window_is_odd_and_fits_the_signal():
    assert odd_window(0.2, 2000.0, 10_000) == 401
    assert odd_window(0.2, 2000.0, 100) == 99
    assert odd_window(0.2, 2000.0, 98) == 97


@pytest.mark.parametrize("window, deriv", [(11, 1), (101, 2), (51, 0)])
def test_the_filter_response_equals_the_direct_transform(window, deriv):
    """response() (an FFT of the coefficients on the Welch grid) against the direct sum
    H(f) = sum_k c_k exp(-i 2 pi f k / rate), and the derivative's low-frequency limit."""
    from scipy.signal import savgol_coeffs

    from harness.data.derivatives import response

    rate, nfft = 500.0, 1024
    f = np.arange(nfft // 2 + 1) * rate / nfft
    c = savgol_coeffs(window, 4, deriv=deriv, delta=1 / rate, use="conv")
    k = np.arange(window) - window // 2
    direct = np.exp(-2j * np.pi * np.outer(f, k) / rate) @ c
    h = response(window, 4, deriv, rate, nfft)
    np.testing.assert_allclose(h, direct, atol=1e-9 * np.max(np.abs(direct)))
    low = f[1:4]
    np.testing.assert_allclose(h[1:4], (2j * np.pi * low) ** deriv, rtol=1e-3)

