"""The QP of one anytime-SQP iteration (planning.sqp): the Sl1QP model of the elastic planning
NLP at a point, in the variables that have rows (a clearance slack whose row is free stays
0), the hard rows the point violates given elastic columns, the coefficients in a box trust
region, the slacks under a small proximal term, the power samples whose sign the step
cannot change linearized by their sign instead of their epigraph (see step); solved by DAQP
(dual active set) from a working set guessed from the last multipliers and the point
itself."""

from __future__ import annotations

import time
from dataclasses import dataclass

import daqp
import numpy as np
from scipy.linalg.lapack import dsyevd as syevd

QP_PRIMAL_TOLERANCE = 1e-10  # DAQP's (its default, 1e-6, let steps leave the trust region)
PROXIMAL = 1e-2  # weight of the slacks' proximal term in each QP (vanishes at a fixed point; e,
# v move by less than cost / PROXIMAL >= 10 only where the rows allow nothing less)
CURVATURE = 1e-8  # smallest eigenvalue kept in the coefficient block of the QP's Hessian
_EQUALITY = 5  # DAQP sense flags: active + immutable
VIOLATED = 1e-9  # a hard row beyond its bound by more gets an elastic column in the QP
_INF = 1e30
SIGN_FLOOR = 1e-9  # a power sample this small (relative to the largest) keeps its slack,
# and one whose |P| is below HOLD x its largest linear change in the trust region
HOLD = 0.1


@dataclass(frozen=True)
class Layout:
    """Where the NLP's pieces sit: nc coefficient variables first, then the power slacks
    (slice e) and the clearance slacks (slice v); the epigraph rows (slices above, below:
    P - e, -P - e) and the clearance rows (slice clearance, D + v)."""

    nc: int
    e: slice
    v: slice
    above: slice
    below: slice
    clearance: slice


@dataclass
class Point:
    """An iterate with its slacks reset: x, objective f, rows g, gradient, Jacobian, the
    Lagrangian Hessian's coefficient block, and its hard-row violation (L1)."""

    x: np.ndarray
    f: float
    g: np.ndarray
    grad: np.ndarray
    jac: np.ndarray
    hess: np.ndarray
    violation: float


class Frame:
    """What every QP of one solve shares: its rows and variables, the Hessian buffer (the
    slacks' proximal diagonal set once), the variable bounds and DAQP's constraint types,
    and where the slacks' rows and columns sit (see step)."""

    def __init__(self, rows, cols, layout: Layout, equality, lbx_slacks):
        k, nc = len(cols), layout.nc
        self.rows, self.cols, self.nc, self.lbx = rows, cols, nc, lbx_slacks
        # the power samples' epigraph rows (above, below: P - e, -P - e) and slacks (e), the
        # bounded clearance rows (D + v) and their slacks (v): their indices in the NLP and
        # their positions among the QP's rows and variables
        self.above, self.below, self.e = (np.arange(part.start, part.stop) for part in
                                          (layout.above, layout.below, layout.e))
        clearance = np.arange(layout.clearance.start, layout.clearance.stop)
        self.clearance = clearance[np.isin(clearance, rows)]
        self.v = layout.v.start + self.clearance - layout.clearance.start
        self.above_at, self.below_at, self.clearance_at = (
            np.searchsorted(rows, part) for part in (self.above, self.below, self.clearance))
        self.e_at, self.v_at = np.searchsorted(cols, self.e), np.searchsorted(cols, self.v)
        self.hess = np.zeros((k, k))
        self.hess[np.arange(nc, k), np.arange(nc, k)] = PROXIMAL
        self.low, self.high = np.zeros(k), np.full(k, _INF)
        self.sense = np.zeros(k + len(rows), dtype=np.int32)
        self.sense[k + np.flatnonzero(equality)] = _EQUALITY


def step(point: Point, lbg, ubg, frame: Frame, radius: float, nu: float, last,
         layout: Layout):
    """The step d (all variables), its multipliers (rows of g, variables) and the model's
    decrease parts: (its value grad'd + d'Hd/2, the linearized hard violation), and the
    CPU ms DAQP took; None if DAQP fails. frame:
    the rows with a bound and the variables the QP has (a clearance slack whose row is
    free stays 0), with the arrays every QP of the solve shares. last: the multipliers
    (rows, variables) of the last QP or of the warm start, DAQP's hot start.

    A slack whose branch the step cannot change leaves the QP with its rows: a power
    sample's e = |P| is linearized with the sign of P (w sign(P) grad P in the cost, the
    slack's proximal term rho (grad P d)^2 / 2 in the Hessian), a clearance row's v =
    max(0, lambda - D) is 0 where the row stays clear (nothing in the QP) and linearized,
    -grad D d, where it stays violated. It is the same QP wherever the branch holds along
    the step. A slack keeps its rows when its margin (|P|, |D - lambda|) is below HOLD
    times its largest linear change in the trust region (|grad|_1 radius); one whose
    linearized margin changes sign at the step all the same goes back, and the QP is
    solved again. Measured on 8 random crossings' re-plans (Lynxmotion), with the power
    samples held: DAQP 250 -> 160 us a step, 1 % of the steps solved twice (fixing every
    sign: 40 %), re-plan CPU median 2.40 -> 1.99 ms."""
    nc, spent, g, jac = layout.nc, 0.0, point.g, point.jac
    power = 0.5 * (g[frame.above] - g[frame.below])
    margin = g[frame.clearance] - point.x[frame.v] - lbg[frame.clearance]  # D - lambda
    slope = np.concatenate([0.5 * (jac[frame.above, :nc] - jac[frame.below, :nc]),
                            jac[frame.clearance, :nc]])
    weight = np.concatenate([point.grad[frame.e], point.grad[frame.v]])
    value = np.concatenate([power, margin])
    side = np.sign(value)  # the branch: the margin keeps this sign
    # the slack's change per unit of the row's linear change (e: sign P; v: -1 or 0)
    rate = np.concatenate([side[: len(power)], np.minimum(side[len(power):], 0.0)])
    floor = SIGN_FLOOR * (1.0 + np.max(np.abs(power), initial=0.0))
    held = (np.abs(value) > floor) & (np.abs(value) >= HOLD * radius * np.abs(slope).sum(axis=1))
    rows_at = np.concatenate([frame.above_at, frame.clearance_at])
    cols_at = np.concatenate([frame.e_at, frame.v_at])
    count = len(power)
    for _ in range(len(value) + 1):
        keep_rows, keep_cols = np.ones(len(frame.rows), bool), np.ones(len(frame.cols), bool)
        keep_rows[rows_at[held]] = keep_rows[frame.below_at[held[:count]]] = False
        keep_cols[cols_at[held]] = False
        moving = held & (rate != 0)
        linear = slope[moving]
        result = _solve(point, lbg, ubg, frame, radius, nu, last, layout, keep_rows,
                        keep_cols, (weight[moving] * rate[moving]) @ linear,
                        PROXIMAL * linear.T @ linear)
        if result is None:
            return None
        d, lam_rows, lam_vars, parts, ms = result
        spent += ms
        change = slope @ d[:nc]  # of P and of D along the step (linearized)
        flipped = held & (side * (value + change) <= 0.0)
        if not np.any(flipped):
            moved = rate[held] * change[held]  # of the held slacks
            slack = np.concatenate([frame.e, frame.v])[held]
            d[slack] = moved
            lam = weight[held] + PROXIMAL * moved  # of the row holding a moving slack
            power_held, clear_held = held[:count], held[count:]
            sign, lam_power = side[:count][power_held], lam[: np.count_nonzero(power_held)]
            lam_rows[frame.above[power_held]] = np.where(sign > 0, lam_power, 0.0)
            lam_rows[frame.below[power_held]] = np.where(sign < 0, lam_power, 0.0)
            violated = side[count:][clear_held] < 0  # lower bounds: DAQP's multipliers < 0
            lam_clear = lam[np.count_nonzero(power_held):]
            lam_rows[frame.clearance[clear_held]] = np.where(violated, -lam_clear, 0.0)
            lam_vars[frame.v[clear_held]] = np.where(violated, 0.0, -lam_clear)
            return d, lam_rows, lam_vars, parts, spent
        held &= ~flipped
    raise AssertionError("unreachable: with every slack back in the QP none can flip")


def _solve(point: Point, lbg, ubg, frame: Frame, radius: float, nu: float, last,
           layout: Layout, keep_rows, keep_cols, extra_cost, extra_curvature):
    """The QP of step with the frame's rows and variables where keep_rows, keep_cols, the
    coefficients' cost and Hessian block plus extra_cost, extra_curvature."""
    rows, cols, nc, n = frame.rows[keep_rows], frame.cols[keep_cols], frame.nc, len(point.x)
    k = len(cols)
    g = point.g[rows]
    low, high = lbg[rows] - g, ubg[rows] - g
    # hard rows the point violates (beyond rounding): elastic columns of weight nu
    below, above = low > VIOLATED, high < -VIOLATED
    violated = np.flatnonzero(below | above)
    m = len(violated)
    a = point.jac[rows][:, cols]
    hess = frame.hess[keep_cols][:, keep_cols]
    cost = point.grad[cols]
    cost[:nc] += extra_cost
    hess[:nc, :nc] = convex(point.hess) + extra_curvature
    var_low, var_high = frame.low[keep_cols], frame.high[keep_cols]
    var_low[:nc], var_high[:nc] = -radius, radius
    var_low[nc:] = np.maximum(frame.lbx[keep_cols[nc:]] - point.x[cols[nc:]], -_INF)
    sense = np.concatenate([frame.sense[: len(frame.cols)][keep_cols],
                            frame.sense[len(frame.cols):][keep_rows]])
    if m:  # elastic columns: the QP grows for this step
        elastic = np.zeros((len(rows), m))
        elastic[violated, np.arange(m)] = np.where(below[violated], 1.0, -1.0)
        a = np.hstack([a, elastic])
        grown = np.zeros((k + m, k + m))
        grown[:k, :k], grown[np.arange(k, k + m), np.arange(k, k + m)] = hess, PROXIMAL
        hess, cost = grown, np.concatenate([cost, np.full(m, nu)])
        var_low = np.concatenate([var_low, np.zeros(m)])
        var_high = np.concatenate([var_high, np.full(m, _INF)])
        sense = np.concatenate([sense[:k], np.zeros(m, np.int32), sense[k:]])
    blower = np.concatenate([var_low, np.maximum(low, -_INF)])
    bupper = np.concatenate([var_high, np.minimum(high, _INF)])
    dual = working_set(point, rows, cols, m, last, layout)
    began = time.thread_time()
    x, _, flag, info = daqp.solve(hess, cost, a, bupper, blower, sense, dual_start=dual,
                                  primal_tol=QP_PRIMAL_TOLERANCE)
    if flag < 0:  # the guessed working set can mislead it (cycling): again, cold
        x, _, flag, info = daqp.solve(hess, cost, a, bupper, blower, sense,
                                      primal_tol=QP_PRIMAL_TOLERANCE)
    spent = 1e3 * (time.thread_time() - began)
    if flag < 0:
        return None
    lam = info["lam"]
    lam_rows, lam_vars, d = np.zeros(len(point.g)), np.zeros(n), np.zeros(n)
    lam_rows[rows], lam_vars[cols], d[cols] = lam[k + m:], lam[:k], x[:k]
    model = float(cost[:k] @ x[:k] + 0.5 * x @ hess @ x)
    return d, lam_rows, lam_vars, (model, float(np.sum(x[k:]))), spent


def working_set(point: Point, rows, cols, m: int, last, layout: Layout) -> np.ndarray:
    """DAQP's starting working set (signs of multipliers: which bounds are active): the
    last multipliers, with the slacks' rows and bounds set from the point itself (the
    active side of each |P| epigraph pair, a clearance row where the point dips, else
    its slack's bound), the elastic columns at zero."""
    lay = layout
    lam_rows, lam_vars = (np.array(v, float) for v in last)
    lam_vars[: lay.nc] = np.sign(lam_vars[: lay.nc])
    if lay.e.stop > lay.e.start:
        power = 0.5 * (point.g[lay.above] - point.g[lay.below])
        lam_rows[lay.above], lam_rows[lay.below] = power > 0, power < 0
    if lay.v.stop > lay.v.start:
        dips = point.x[lay.v] > 0
        lam_rows[lay.clearance], lam_vars[lay.v] = -1.0 * dips, -1.0 * ~dips
    return np.concatenate([lam_vars[cols], np.full(m, -1.0), lam_rows[rows]])


def convex(hessian: np.ndarray) -> np.ndarray:
    """The symmetric matrix with its eigenvalues clipped below at CURVATURE (relative); LAPACK's
    syevd called directly (numpy's eigh wrapper cost as much again on the 9 x 9 block)."""
    w, vectors, info = syevd(0.5 * (hessian + hessian.T), lower=1)  # LAPACK: ascending w
    if info != 0:
        raise np.linalg.LinAlgError(f"the QP's Hessian has no eigendecomposition (info {info})")
    floor = CURVATURE * max(1.0, abs(float(w[0])), abs(float(w[-1])))
    return (vectors * np.maximum(w, floor)) @ vectors.T
