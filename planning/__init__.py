"""Energy-optimal, obstacle-avoiding trajectory planning (paper III.B, III.G, Algorithm 2)."""

from planning.errors import PlanningError

__all__ = ["PlanningError"]
