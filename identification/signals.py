"""Analytic multi-sine joint trajectories for identification experiments and tests.

q_j(t) = centre_j + sum_k a_jk sin(w_jk t + phi_jk): positions, velocities and
accelerations are exact (no numerical differentiation), so noise-free data is
noise-free to machine precision.
"""

from __future__ import annotations

import numpy as np

from identification.torque_model import Motion


def multisine(n: int, dof: int, seed: int, centre, amplitude, duration: float = 20.0,
              harmonics: int = 5, base_hz: float = 0.1) -> Motion:
    """A random multi-sine with |q - centre| <= amplitude per joint (rad)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, duration, n)
    centre = np.broadcast_to(np.asarray(centre, float), (dof,))
    amplitude = np.broadcast_to(np.asarray(amplitude, float), (dof,))
    q = np.tile(centre, (n, 1))
    qd = np.zeros((n, dof))
    qdd = np.zeros((n, dof))
    for j in range(dof):
        w = 2 * np.pi * base_hz * rng.choice(np.arange(1, 4 * harmonics), harmonics, replace=False)
        a = rng.uniform(0.5, 1.0, harmonics)
        a *= amplitude[j] / a.sum()
        phi = rng.uniform(0, 2 * np.pi, harmonics)
        arg = np.outer(t, w) + phi
        q[:, j] += np.sin(arg) @ a
        qd[:, j] = np.cos(arg) @ (a * w)
        qdd[:, j] = -np.sin(arg) @ (a * w**2)
    return Motion(t, q, qd, qdd)
