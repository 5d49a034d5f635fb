"""SLSQP's descent of the excitation design (identification.excitation.design): restarted
where it stopped while it improves, each run's best safe iterate kept, an unsafe end point
walked back towards the last safe one."""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

HALVINGS = 12  # bisection steps walking a colliding optimum back towards its start


def descend(objective, start: np.ndarray, constraints: list[dict], budget: int,
             safe, progress=None) -> tuple[np.ndarray, int, object]:
    """SLSQP on objective from start, again from where it stopped (its linearization may
    fail) while it improves, within budget iterations. Each run's best safe point among its
    iterates and its end point (walked back towards the last safe one if unsafe: SLSQP's
    iterates need not meet the constraints, and may touch between the design grid's points);
    that point (start itself if none improved on it), the iterations used and SLSQP's last
    result (None if it never ran)."""
    # scaled to a unit gradient at the start: SLSQP's first step, along its identity Hessian,
    # is then about 1 rad of coefficients, not a jump far outside the limits that it may
    # never walk back from (docs/identification.md, 'identification.excitation.criteria')
    scale = 1.0 / max(float(np.linalg.norm(objective(start)[1])), 1e-300)
    raw = objective

    def objective(x):
        value, grad = raw(x)
        return scale * value, scale * grad

    best, value, used, result = start, objective(start)[0], 0, None
    while used < budget:
        found = {"x": best, "value": value, "iterations": used}

        def keep(x, found=found):  # the best safe iterate so far
            v = objective(x)[0]
            if v < found["value"] - 1e-6 and safe(x):
                found.update(x=x.copy(), value=v)

        def iterated(x, found=found):  # SLSQP's callback, once an iteration
            found["iterations"] += 1
            if progress is not None:
                progress(min(found["iterations"], budget), budget)
            keep(x)

        result = minimize(objective, best, jac=True, method="SLSQP", constraints=constraints,
                          callback=iterated, options={"maxiter": budget - used, "ftol": 1e-6})
        used += max(int(result.nit), 1)
        keep(result.x if safe(result.x) else walk_back(best, result.x, safe))
        if found["value"] >= value - 1e-6:
            break
        best, value = found["x"], found["value"]
        if result.success:
            break
    return best, used, result


def walk_back(safe_x: np.ndarray, x: np.ndarray, safe) -> np.ndarray:
    """The farthest point from safe_x towards x found safe by bisection (the linear limits
    hold on the whole segment; collisions need not)."""
    good, bad = 0.0, 1.0
    for _ in range(HALVINGS):
        mid = 0.5 * (good + bad)
        good, bad = (mid, bad) if safe(safe_x + mid * (x - safe_x)) else (good, mid)
    return safe_x + good * (x - safe_x)
