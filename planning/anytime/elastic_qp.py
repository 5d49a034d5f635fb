"""The QP of one anytime-SQP iteration (planning.anytime.sqp): the Sl1QP model of the elastic planning
NLP at a point, in the variables that have rows (a clearance slack whose row is free stays
0), the hard rows the point violates given elastic columns, the coefficients in a box trust
region, the slacks under a small proximal term, the power samples whose sign the step
cannot change linearized by their sign instead of their epigraph (see step); solved by DAQP
(dual active set) from a working set guessed from the last multipliers and the point
itself."""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cache

import daqp
import numpy as np

from planning.anytime import qp_kernels as kernels

QP_PRIMAL_TOLERANCE = 1e-10  # DAQP's (its default, 1e-6, let steps leave the trust region)
PROXIMAL = 1e-2  # weight of the slacks' proximal term in each QP (vanishes at a fixed point; e,
# v move by less than cost / PROXIMAL >= 10 only where the rows allow nothing less)
CURVATURE = 1e-8  # smallest eigenvalue kept in the coefficient block of the QP's Hessian
VIOLATED = 1e-9  # a hard row beyond its bound by more gets an elastic column in the QP
_INF = 1e30
SIGN_FLOOR = 1e-9  # a power sample this small (relative to the largest) keeps its slack,
# and one whose |P| is below HOLD x its largest linear change in the trust region
HOLD = 0.1
# inequality rows no step in the trust region can bring to a bound leave the QP (exact: each
# would be inactive; a smaller QP (docs/realtime.md, 'planning.anytime.elastic_qp'))
DROP_UNREACHABLE = True


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
    """An iterate with its slacks reset: x, objective f, rows g, gradient, the rows'
    Jacobian in the coefficients (the slacks' columns are constant: slack_structure), the
    Lagrangian Hessian's coefficient block, and its hard-row violation (L1)."""

    x: np.ndarray
    f: float
    g: np.ndarray
    grad: np.ndarray
    jac: np.ndarray
    hess: np.ndarray
    violation: float


class Frame:
    """What every QP of one solve shares: its rows and variables, which rows are equalities,
    the slacks' variable bounds, and where the slacks' rows and columns sit (see step)."""

    def __init__(self, rows, cols, layout: Layout, equality, lbx_slacks):
        self.rows, self.cols, self.nc = rows, cols, layout.nc
        self.lbx, self.equality = np.asarray(lbx_slacks, float), np.asarray(equality, bool)
        self.equal_rows = self.rows[self.equality]  # the equality rows' NLP indices
        # the power samples' epigraph rows (above, below: P - e, -P - e) and slacks (e), the
        # bounded clearance rows (D + v) and their slacks (v): their indices in the NLP and
        # their positions among the QP's rows and variables
        self.above, self.below, self.e = (np.arange(part.start, part.stop) for part in
                                          (layout.above, layout.below, layout.e))
        clearance = np.arange(layout.clearance.start, layout.clearance.stop)
        at = np.minimum(np.searchsorted(rows, clearance), max(len(rows) - 1, 0))
        self.clearance = clearance[rows[at] == clearance] if len(rows) else clearance[:0]
        self.v = layout.v.start + self.clearance - layout.clearance.start
        self.above_at, self.below_at, self.clearance_at = (
            np.searchsorted(rows, part) for part in (self.above, self.below, self.clearance))
        self.e_at, self.v_at = np.searchsorted(cols, self.e), np.searchsorted(cols, self.v)
        # per slack item (power samples, then clearance rows): its rows in the QP, its column
        self.rows_at = np.concatenate([self.above_at, self.clearance_at])
        self.second_at = np.concatenate([self.below_at, np.full(len(self.clearance), -1)])
        self.cols_at = np.concatenate([self.e_at, self.v_at])
        self.slack = np.concatenate([self.e, self.v])
        self.start = (self.above, self.below, self.clearance, self.v)
        self.slack_rows, self.slack_sign, self.slack_row = slack_structure(layout)


def slack_structure(layout: Layout) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The slacks' constant columns of the rows' Jacobian (a Point's jac has the coefficients'
    only): per slack (e, then v), its rows (a power sample's above and below, a clearance
    row and -1) and its coefficient in them (e: -1, v: +1); and which rows (up to the last
    with a slack) have one. Built once per layout: shared, never written."""
    return _slack_structure(*((part.start, part.stop) for part in
                              (layout.e, layout.v, layout.above, layout.below, layout.clearance)))


@cache
def _slack_structure(e, v, above, below, clearance) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    count, total = e[1] - e[0], e[1] - e[0] + v[1] - v[0]
    rows = np.full((total, 2), -1)
    rows[:count, 0], rows[:count, 1] = np.arange(*above), np.arange(*below)
    rows[count:, 0] = np.arange(*clearance)
    sign = np.concatenate([np.full(count, -1.0), np.full(total - count, 1.0)])
    has = np.zeros(max(above[1], below[1], clearance[1]), bool)
    has[rows[rows >= 0]] = True
    return rows, sign, has


def linear_change(point: Point, dx: np.ndarray, layout: Layout) -> np.ndarray:
    """The rows' linear change J dx along a step dx of all variables."""
    change = point.jac @ dx[: layout.nc]
    rows, sign, _ = slack_structure(layout)
    for column in rows.T:
        there = column >= 0
        change[column[there]] += sign[there] * dx[layout.nc:][there]
    return change


def step(point: Point, lbg, ubg, frame: Frame, radius: float, nu: float, last,
         layout: Layout):
    """The step d (all variables), its multipliers (rows of g, variables) and the model's
    decrease parts: (its value grad'd + d'Hd/2, the linearized hard violation), the
    CPU ms DAQP took, and (the largest |row multiplier|, max |d| over the coefficients);
    None if DAQP fails. frame:
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
    solved again (fewer rows, rarely a second solve: (docs/realtime.md, 'planning.anytime.elastic_qp')).
    The array work is compiled
    (planning.anytime.qp_kernels)."""
    nc, spent, g, jac, x = layout.nc, 0.0, point.g, point.jac, point.x
    lam_rows_last, lam_vars_last = np.asarray(last[0], float), np.asarray(last[1], float)
    (h, f, a, upper, lower, sense, dual, rk, ck), branch, convexified = kernels.model(
        g, jac, point.grad, x, point.hess, lbg, ubg, frame.above, frame.below, frame.e,
        frame.clearance, frame.v, frame.rows_at, frame.second_at, frame.cols_at, frame.rows,
        frame.cols, nc, frame.lbx, frame.equality, radius, nu, lam_rows_last, lam_vars_last,
        frame.start, frame.slack_rows, frame.slack_sign, frame.slack_row, HOLD, SIGN_FLOOR,
        CURVATURE, PROXIMAL, VIOLATED, _INF, DROP_UNREACHABLE)
    value, side, rate, slope, weight, held = branch
    for _ in range(len(value) + 1):
        began = time.thread_time()
        solution, _, flag, info = daqp.solve(h, f, a, upper, lower, sense, dual_start=dual,
                                             primal_tol=QP_PRIMAL_TOLERANCE)
        if flag < 0:  # the guessed working set can mislead it (cycling): again, cold
            solution, _, flag, info = daqp.solve(h, f, a, upper, lower, sense,
                                                 primal_tol=QP_PRIMAL_TOLERANCE)
        spent += 1e3 * (time.thread_time() - began)
        if flag < 0:
            return None
        d, lam_rows, lam_vars, model, violation, flipped, largest, reach = kernels.unpack(
            solution, info["lam"], h, f, len(ck), rk, ck, len(x), len(g), value, side, rate,
            slope, weight, held, frame.slack, frame.slack_rows, PROXIMAL)
        if not flipped.any():
            return d, lam_rows, lam_vars, (model, violation), spent, (largest, reach)
        held &= ~flipped  # those items back in the QP, built again
        keep_rows, keep_cols, extra_cost, extra_curvature = kernels.held_out(
            held, rate, weight, slope, frame.rows_at, frame.second_at, frame.cols_at,
            len(frame.rows), len(frame.cols), PROXIMAL)
        h, f, a, upper, lower, sense, dual, rk, ck = kernels.assemble(
            g, jac, point.grad, x, convexified, lbg, ubg, frame.rows, frame.cols, nc,
            frame.lbx, frame.equality, keep_rows, keep_cols, extra_cost, extra_curvature,
            radius, nu, lam_rows_last, lam_vars_last, frame.start, frame.slack_rows,
            frame.slack_sign, frame.slack_row, PROXIMAL, VIOLATED, _INF,
            DROP_UNREACHABLE)
    raise AssertionError("unreachable: with every slack back in the QP none can flip")

