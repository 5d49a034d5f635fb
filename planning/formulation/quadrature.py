"""Where the power is sampled and how the samples are weighted: E = sigma sum_i w_i |P(s_i)|.

- "paper": the right Riemann sum of eq. (18), s_i = i/N, w_i = 1/N. With N = 10 the
  optimizer can place power peaks between the samples (docs/realtime.md, 'planning.formulation.quadrature').
- "gauss": Gauss-Legendre nodes and weights on [0, 1]; exact for polynomial power of
  degree 2N - 1 (|P| has kinks where P changes sign, so convergence there is slower).
- "simpson": composite Simpson on N (odd) equally spaced points including both ends.
- "split": Gauss-Legendre on each of the intervals between breakpoints where the power
  changes sign (planning.formulation.breaks finds them on a reference motion; a solve is repeated
  until they are those of its own solution): |P| is smooth inside each interval, so the
  rule converges as fast as for a polynomial. N / (breaks + 1) nodes per interval.
Weights are dimensionless and sum to 1; s is normalized time.
"""

from __future__ import annotations

import numpy as np

RULES = ("paper", "gauss", "simpson", "split")


def energy_nodes(rule: str, n: int, breaks=None) -> tuple:
    """Normalized times s (n,) and weights w (n,) of the energy quadrature; for "split",
    lists of expressions of the breaks (ascending in [0, 1]: numbers or CasADi symbols)."""
    if n < 1:
        raise ValueError(f"energy samples must be >= 1, got {n}")
    if rule == "split":
        return split_nodes(breaks, n)
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


def splits_evenly(samples: int, breaks: int) -> bool:
    """True if the split rule can put `samples` nodes, the same number on each interval,
    between `breaks` (>= 1) breaks."""
    return breaks >= 1 and samples >= 1 and samples % (breaks + 1) == 0


def split_nodes(breaks, n: int) -> tuple[list, list]:
    """Gauss-Legendre with n / (len(breaks) + 1) nodes on each interval between 0, the
    breaks (ascending) and 1: normalized times and weights as expressions of the breaks."""
    count = breaks.shape[0] if hasattr(breaks, "shape") else len(breaks)
    if n % (count + 1):
        raise ValueError(f"the split rule puts the same number of nodes between {count} "
                         f"breaks: energy samples must be a multiple of {count + 1}, got {n}")
    x, w = energy_nodes("gauss", n // (count + 1))
    edges = [0.0, *(breaks[i] for i in range(count)), 1.0]
    nodes = [a + (b - a) * float(xi) for a, b in zip(edges[:-1], edges[1:], strict=True) for xi in x]
    weights = [(b - a) * float(wi) for a, b in zip(edges[:-1], edges[1:], strict=True) for wi in w]
    return nodes, weights
