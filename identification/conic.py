"""One convex solve for every LMI fit (the consistent fit, a payload, a bounding ellipsoid):
Clarabel's interior point, else SCS, never silently (SCS is first order, looser)."""

from __future__ import annotations

import warnings

import cvxpy as cp


def solve_conic(problem: cp.Problem, what: str, stacklevel: int = 3) -> str:
    """Solve problem by Clarabel, else by SCS with a warning naming what was solved; the name
    of the solver used."""
    try:
        problem.solve(solver=cp.CLARABEL)
        return "CLARABEL"
    except cp.SolverError as exc:
        warnings.warn(f"{what}'s Clarabel solve failed ({' '.join(str(exc).split())[:80]}); "
                      "solved by SCS instead (first order, looser tolerances)", RuntimeWarning,
                      stacklevel=stacklevel)
        problem.solve(solver=cp.SCS)
        return "SCS"
