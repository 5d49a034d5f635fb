"""One convex solve for every LMI fit (the consistent fit, a payload, a bounding ellipsoid):
Clarabel's interior point, else SCS, never silently (SCS is first order, looser)."""

from __future__ import annotations

import warnings

import cvxpy as cp

_SAID: set[str] = set()  # the fits whose inaccurate solve was said


def solve_conic(problem: cp.Problem, what: str, stacklevel: int = 3) -> str:
    """Solve problem by Clarabel, else by SCS with a warning naming what was solved; the name
    of the solver used."""
    try:
        with warnings.catch_warnings():  # said below, naming what was solved
            warnings.filterwarnings("ignore", "Solution may be inaccurate")
            problem.solve(solver=cp.CLARABEL)
        if problem.status in (cp.OPTIMAL_INACCURATE, cp.USER_LIMIT) and what not in _SAID:
            _SAID.add(what)  # once a fit a process: the weight's choice solves it many times
            warnings.warn(f"{what}: Clarabel stopped short of its tolerances ({problem.status}); "
                          "its solution is used", RuntimeWarning, stacklevel=stacklevel)
        return "CLARABEL"
    except cp.SolverError as exc:
        warnings.warn(f"{what}'s Clarabel solve failed ({' '.join(str(exc).split())[:80]}); "
                      "solved by SCS instead (first order, looser tolerances)", RuntimeWarning,
                      stacklevel=stacklevel)
        problem.solve(solver=cp.SCS)
        return "SCS"
