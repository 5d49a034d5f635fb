"""What a user of a real arm measures: encoder angles and noisy motor torques.

Joint velocities and accelerations are estimated from the measured angles by
Savitzky-Golay differentiation (harness.data.derivatives).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.data.derivatives import savgol_derivatives


@dataclass(frozen=True)
class SensorConfig:
    """Sensor model; angles in rad, rates in Hz, window in s."""

    encoder_bits: int = 16  # quantization step 2 pi / 2**bits
    angle_noise: float = 2e-5  # rad, Gaussian jitter before quantization
    sensing_rate: float = 2000.0  # Hz, the controller/sensor loop
    window: float = 0.2  # s, Savitzky-Golay window for derivative estimation
    polyorder: int = 4

    @property
    def resolution(self) -> float:
        return 2 * np.pi / 2**self.encoder_bits


def encoder(q: np.ndarray, cfg: SensorConfig, rng: np.random.Generator) -> np.ndarray:
    """Quantized, jittered angle readings (rad)."""
    noisy = q + rng.normal(scale=cfg.angle_noise, size=q.shape)
    return np.round(noisy / cfg.resolution) * cfg.resolution


def estimate_derivatives(q_meas: np.ndarray, cfg: SensorConfig) -> tuple[np.ndarray, ...]:
    """Smoothed q, estimated qd, qdd from angles sampled at cfg.sensing_rate (axis 0 = time)."""
    return savgol_derivatives(q_meas, cfg.sensing_rate, cfg.window, cfg.polyorder)


def torque_noise(
    tau_clean: np.ndarray, level: float, bias: float, rng: np.random.Generator,
    one_sensor: bool = False,
) -> np.ndarray:
    """Non-zero-mean Gaussian torque noise: std = level * std(tau_j), mean = bias * that std;
    one_sensor: the same std on every joint, the mean over joints of level * std(tau_j) (one
    sensor's noise in N m, as much on a loaded joint as on the wrist)."""
    sigma = level * tau_clean.std(axis=0)
    if one_sensor:
        sigma = np.full(tau_clean.shape[1], sigma.mean())
    return rng.normal(size=tau_clean.shape) * sigma + bias * sigma
