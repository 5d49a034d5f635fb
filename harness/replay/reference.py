"""The reference a replay tracks: a validated PLAN.json, interpolated in time.

Between the plan's samples the joint reference is a quintic Hermite spline
through (q, qd, qdd) at every sample, so it is C2, exact for quintic segments,
and its acceleration is the plan's own at every sample. The obstacle centre is
interpolated linearly (it moves on a polyline of obstacle samples).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.errors import UserError

REQUIRED = ("t", "q", "qd", "qdd", "obstacle", "threshold")
LIMIT_TOLERANCE = 1e-3  # rad: a plan ending on a limit may overshoot it between its samples
MIN_STEP = 1e-9  # s: the closest distinct samples of a plan (PLAN.json's are 2 ms apart)
MAX_DURATION = 600.0  # s of simulated motion; a longer plan is a corrupt file, not a motion
MAX_SAMPLES = 1_000_000
# Magnitudes no arm's plan reaches (a file beyond them is corrupt or in other units)
MAGNITUDE = {"t": 1e6, "q": 1e3, "qd": 1e4, "qdd": 1e6, "obstacle": 1e3, "threshold": 1e3}


@dataclass(frozen=True)
class PlanReference:
    """A planned trajectory: samples t (s), q (rad), qd (rad/s), qdd (rad/s^2), obstacle (m)."""

    t: np.ndarray  # (K,)
    q: np.ndarray  # (K, dof)
    qd: np.ndarray
    qdd: np.ndarray
    obstacle: np.ndarray  # (K, 3) centre of the obstacle at each t
    threshold: float  # m, the planner's safety distance lambda
    energy: float | None = None  # J, the planner's own estimate
    min_clearance: float | None = None  # m, the planner's own estimate

    @property
    def dof(self) -> int:
        return self.q.shape[1]

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def joints_at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd) of shape (n, dof) at times (s) inside [t0, t_end]."""
        times = np.clip(np.asarray(times, dtype=float), self.t[0], self.t[-1])
        k = np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, len(self.t) - 2)
        h = (self.t[k + 1] - self.t[k])[:, None]
        s = ((times - self.t[k]) / h[:, 0])[:, None]
        ends = [(self.q[i], self.qd[i] * h, self.qdd[i] * h**2) for i in (k, k + 1)]
        return tuple(d / h**order for order, d in enumerate(_quintic(s, *ends)))

    def obstacle_at(self, times: np.ndarray) -> np.ndarray:
        """Obstacle centre (n, 3) in m at times (s), linear between samples."""
        return np.stack([np.interp(times, self.t, self.obstacle[:, j]) for j in range(3)], axis=1)


def _quintic(s, start, end):
    """Value and first two s-derivatives of the quintic Hermite segment on s in [0, 1].

    start/end are (p, v, a) with v, a already scaled to the unit interval.
    """
    (p0, v0, a0), (p1, v1, a1) = start, end
    # Coefficients of p(s) = sum c_i s^i matching p, p', p'' at s = 0 and s = 1.
    c0, c1, c2 = p0, v0, a0 / 2
    d = p1 - (c0 + c1 + c2)
    e = v1 - (c1 + 2 * c2)
    f = a1 - 2 * c2
    c3 = 10 * d - 4 * e + f / 2
    c4 = -15 * d + 7 * e - f
    c5 = 6 * d - 3 * e + f / 2
    p = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    v = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
    a = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
    return p, v, a


def _array(plan: dict, key: str, shape_tail: tuple[int, ...] | None = None) -> np.ndarray:
    value = plan[key]
    if isinstance(value, list) and len(value) > MAX_SAMPLES:
        raise UserError(f"plan field '{key}' has {len(value)} samples, more than {MAX_SAMPLES}")
    try:
        x = np.asarray(value, dtype=float)
    except (TypeError, ValueError):  # strings, nulls, ragged lists
        raise UserError(f"plan field '{key}' is not a numeric array of one shape") from None
    if not np.all(np.isfinite(x)):
        raise UserError(f"plan field '{key}' contains NaN or inf")
    if x.size and np.abs(x).max() > MAGNITUDE[key]:
        raise UserError(f"plan field '{key}' reaches {np.abs(x).max():.3g}, beyond any plan's "
                        f"{MAGNITUDE[key]:g} (SI units)")
    if shape_tail is not None and (x.ndim != 1 + len(shape_tail) or x.shape[1:] != shape_tail):
        raise UserError(f"plan field '{key}' has shape {x.shape}, expected (K, {shape_tail[0]})")
    return x


def plan_reference(plan: dict) -> PlanReference:
    """Validate a PLAN.json dict (fields, shapes, finiteness, time order) into a reference."""
    if not isinstance(plan, dict):
        raise UserError("plan must be a JSON object")
    missing = [key for key in REQUIRED if key not in plan]
    if missing:
        raise UserError(f"plan is missing field(s): {', '.join(missing)}")
    t = _array(plan, "t")
    if t.ndim != 1 or len(np.unique(t)) < 2:
        raise UserError(f"plan field 't' must hold at least 2 distinct times, got {t.shape}")
    if np.any(np.diff(t) < 0):
        raise UserError("plan field 't' must be increasing")
    step = np.diff(t)[np.diff(t) > 0].min()
    if step < MIN_STEP:  # the interpolation divides by step^2: a tiny step makes inf or NaN
        raise UserError(f"plan field 't' has samples {step:.3g} s apart, fewer than "
                        f"{MIN_STEP:g} s")
    if t[-1] - t[0] > MAX_DURATION:
        raise UserError(f"plan lasts {t[-1] - t[0]:.3g} s, more than {MAX_DURATION:g} s")
    q = _array(plan, "q")
    if q.ndim != 2 or len(q) != len(t) or q.shape[1] == 0:
        raise UserError(f"plan field 'q' has shape {q.shape}, expected ({len(t)}, dof)")
    arrays = {key: _array(plan, key, (q.shape[1],)) for key in ("qd", "qdd")}
    arrays["obstacle"] = _array(plan, "obstacle", (3,))
    for key, x in arrays.items():
        if len(x) != len(t):
            raise UserError(f"plan field '{key}' has {len(x)} samples, 't' has {len(t)}")
    threshold = _array(plan, "threshold")
    if threshold.ndim != 0 or not threshold > 0:
        raise UserError(f"plan field 'threshold' must be one distance > 0 m, got {plan['threshold']!r:.40}")
    threshold = float(threshold)
    optional = {k: float(plan[k]) for k in ("energy", "min_clearance")
                if isinstance(plan.get(k), int | float) and not isinstance(plan.get(k), bool)
                and np.isfinite(plan[k])}
    keep = _distinct_times(t, q, arrays["qd"])
    arrays = {key: x[keep] for key, x in arrays.items()}
    return PlanReference(t=t[keep], q=q[keep], threshold=threshold, **arrays, **optional)


def _distinct_times(t: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Indices to keep: a sample repeated at a segment boundary (same t, q, qd) counts once,
    the later one (the new segment's acceleration) wins."""
    repeated = np.flatnonzero(np.diff(t) == 0)
    same = np.all(np.isclose(q[repeated], q[repeated + 1], atol=1e-9), axis=1) & np.all(
        np.isclose(qd[repeated], qd[repeated + 1], atol=1e-6), axis=1)
    if not np.all(same):
        k = repeated[~same][0]
        raise UserError(f"plan has two different states at t = {t[k]:.6g} s")
    return np.setdiff1d(np.arange(len(t)), repeated)


def check_joint_limits(reference: PlanReference, ranges: np.ndarray, limited: np.ndarray) -> None:
    """Raise UserError if the planned q leaves a limited joint's range (rad)."""
    for j in np.flatnonzero(limited):
        lo, hi = ranges[j]
        qj = reference.q[:, j]
        if qj.min() < lo - LIMIT_TOLERANCE or qj.max() > hi + LIMIT_TOLERANCE:
            worst = qj.min() if qj.min() < lo - LIMIT_TOLERANCE else qj.max()
            raise UserError(
                f"plan leaves the limits of joint {j + 1}: q = {worst:.4f} rad "
                f"outside [{lo:.4f}, {hi:.4f}]"
            )
