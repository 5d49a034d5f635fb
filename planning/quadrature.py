"""Where the power is sampled and how the samples are weighted: E = sigma sum_i w_i |P(s_i)|.

- "paper": the right Riemann sum of eq. (18), s_i = i/N, w_i = 1/N. With N = 10 the
  optimizer can place power peaks between the samples (measured: the N = 10 optimum
  spends more true energy than the N = 40 one).
- "gauss": Gauss-Legendre nodes and weights on [0, 1]; exact for polynomial power of
  degree 2N - 1 (|P| has kinks where P changes sign, so convergence there is slower).
- "simpson": composite Simpson on N (odd) equally spaced points including both ends.
Weights are dimensionless and sum to 1; s is normalized time.
"""

from __future__ import annotations

import numpy as np

RULES = ("paper", "gauss", "simpson")


def energy_nodes(rule: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Normalized times s (n,) and weights w (n,) of the energy quadrature."""
    if n < 1:
        raise ValueError(f"energy samples must be >= 1, got {n}")
    if rule == "paper":
        return np.arange(1, n + 1) / n, np.full(n, 1.0 / n)
    if rule == "gauss":
        x, w = np.polynomial.legendre.leggauss(n)
        return 0.5 * (x + 1.0), 0.5 * w
    if rule == "simpson":
        if n < 3 or n % 2 == 0:
            raise ValueError(f"Simpson's rule needs an odd number >= 3 of samples, got {n}")
        w = np.ones(n)
        w[1:-1:2], w[2:-1:2] = 4.0, 2.0
        return np.linspace(0.0, 1.0, n), w / (3.0 * (n - 1))
    raise ValueError(f"energy quadrature must be one of {RULES}, got '{rule}'")
