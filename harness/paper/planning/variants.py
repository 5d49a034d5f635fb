"""Named parametrizations of the planning NLP, compared side by side in the bench.

The paper's choice (quartic, N = 10 right Riemann sum of |P|) against a dense
energy quadrature (the planned energy is then the true one) and higher degrees
(more free coefficients per joint). Everything else is the planner's default.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from harness.paper.planning.scenario import paper_config
from planning.config import PlannerConfig


@dataclass(frozen=True)
class Parametrization:
    """Degree of the joint polynomials, energy quadrature rule and samples, |P| smoothing (W)."""

    name: str
    degree: int = 4
    quadrature: str = "paper"
    samples: int = 10
    smoothing: float = 0.0
    rest_at_goal: bool = False  # the paper's free end velocity
    replanner: str = "penalty"  # the paper's exterior penalty loop (PlannerConfig.replanner)

    def config(self, base: PlannerConfig | None = None) -> PlannerConfig:
        """`base` (default: the paper's configuration) with this parametrization."""
        return dataclasses.replace(base or paper_config(), degree=self.degree,
                                   energy_quadrature=self.quadrature,
                                   energy_samples=self.samples, power_smoothing=self.smoothing,
                                   rest_at_goal=self.rest_at_goal,
                                   replanner=self.replanner)


PAPER = Parametrization("quartic, N=10 (paper)")
PARAMETRIZATIONS = (
    PAPER,
    Parametrization("quartic, Gauss N=20", 4, "gauss", 20),
    Parametrization("quartic, Gauss N=20, smooth abs(P)", 4, "gauss", 20, 1e-3),
    Parametrization("quintic, Gauss N=20", 5, "gauss", 20),
    # exact abs(P) at degree 7 left the limits (docs/realtime.md, 'Nominal clock')
    Parametrization("degree 7, Gauss N=20, smooth abs(P)", 7, "gauss", 20, 1e-3),
)
