"""The array work of one anytime-SQP QP (planning.anytime.elastic_qp.step), compiled by numba: the
slacks' branches at a point, the dense QP DAQP solves, and its solution unpacked into the
NLP's step and multipliers: in numpy, many small array calls a QP cost more than DAQP
itself (docs/realtime.md, 'planning.anytime.qp_kernels').

Conventions as planning.anytime.elastic_qp: DAQP's variables are the kept columns, then one elastic
column per violated hard row; its multipliers are < 0 where a lower bound is active. A
slack "item" is a power sample (rows above/below, slack e) or a clearance row (row D + v,
slack v), power samples first.
"""

from __future__ import annotations

import numba
import numpy as np

_JIT = {"cache": True, "nogil": True}
# the entry points are compiled when this module loads (from numba's cache after the first
# time), for these argument types only: a plan never pays for a compilation (seconds,
# (docs/realtime.md, 'planning.anytime.qp_kernels')), and a call with other types fails
# instead of compiling


def entry(signature: str):
    """A kernel compiled for this signature only (see above)."""
    return numba.njit(signature, **_JIT)


@entry("(f8[:], f8[:, :], f8[:], f8[:], f8[:], i8[:], i8[:], i8[:], i8[:], i8[:], i8, f8, f8, f8)")
def branches(g, jac, grad, x, lbg, above, below, e, clearance, v, nc, radius, hold, floor):
    """Per item: its margin (P; D - lambda), the sign it keeps on its branch, the slack's
    change per unit of the row's linear change (e: sign P; v: -1 violated, 0 clear), the
    row's gradient in the coefficients, the slack's weight, and whether the branch is held
    (margin above floor and above hold x its largest linear change in the trust region)."""
    count, items = len(above), len(above) + len(clearance)
    value, slope, weight = np.empty(items), np.empty((items, nc)), np.empty(items)
    for i in range(count):
        value[i] = 0.5 * (g[above[i]] - g[below[i]])
        for j in range(nc):
            slope[i, j] = 0.5 * (jac[above[i], j] - jac[below[i], j])
        weight[i] = grad[e[i]]
    largest = 0.0
    for i in range(count):
        largest = max(largest, abs(value[i]))
    for i in range(len(clearance)):
        r = clearance[i]
        value[count + i] = g[r] - x[v[i]] - lbg[r]
        for j in range(nc):
            slope[count + i, j] = jac[r, j]
        weight[count + i] = grad[v[i]]
    side, rate = np.sign(value), np.sign(value)
    held = np.zeros(items, np.bool_)
    for i in range(items):
        if i >= count:
            rate[i] = min(side[i], 0.0)
        reach = 0.0
        for j in range(nc):
            reach += abs(slope[i, j])
        magnitude = abs(value[i])
        held[i] = magnitude > floor * (1.0 + largest) and magnitude >= hold * radius * reach
    return value, side, rate, slope, weight, held


@entry("(b1[:], f8[:], f8[:], f8[:, :], i8[:], i8[:], i8[:], i8, i8, f8)")
def held_out(held, rate, weight, slope, rows_at, second_at, cols_at, rows, cols, proximal):
    """The QP's rows and columns kept (masks over the frame's) with the held items' out, and
    what the held moving slacks add to the coefficients' cost and Hessian: sum w rate grad,
    proximal sum grad grad'."""
    keep_rows, keep_cols = np.ones(rows, np.bool_), np.ones(cols, np.bool_)
    nc = slope.shape[1]
    cost, curvature = np.zeros(nc), np.zeros((nc, nc))
    for i in range(len(held)):
        if not held[i]:
            continue
        keep_rows[rows_at[i]] = False
        if second_at[i] >= 0:
            keep_rows[second_at[i]] = False
        keep_cols[cols_at[i]] = False
        if rate[i] == 0.0:
            continue
        for j in range(nc):
            cost[j] += weight[i] * rate[i] * slope[i, j]
            for k in range(nc):
                curvature[j, k] += proximal * slope[i, j] * slope[i, k]
    return keep_rows, keep_cols, cost, curvature


@numba.njit(**_JIT)
def _out_of_reach(g, jac, lbg, ubg, rows, nc, equality, radius, slack_row):
    """The inequality rows in only the coefficients (no slack_row) that no step in the
    trust region (|d_j| <= radius) brings to a bound: inactive in the QP whatever its
    solution, so leaving them out changes neither the step nor a multiplier (each 0)."""
    out = np.zeros(len(rows), np.bool_)
    for i in range(len(rows)):
        r = rows[i]
        if equality[i] or (r < len(slack_row) and slack_row[r]):
            continue
        reach = 0.0
        for j in range(nc):
            reach += abs(jac[r, j])
        reach *= radius * (1.0 + 1e-9)
        out[i] = lbg[r] - g[r] < -reach and ubg[r] - g[r] > reach
    return out


@numba.njit(**_JIT)
def _working_set(g, x, rk, ck, k, m, nc, last_rows, last_vars, start):
    """DAQP's starting working set: the last multipliers' signs for the coefficients' bounds
    and the hard rows, the active side of each power sample's epigraph pair, a clearance row
    where the point dips (else its slack's bound), the elastic columns at zero."""
    above, below, clearance, v = start
    lam_rows, lam_vars = last_rows.copy(), last_vars.copy()
    for j in range(nc):
        lam_vars[j] = np.sign(lam_vars[j])
    for i in range(len(above)):
        power = 0.5 * (g[above[i]] - g[below[i]])
        lam_rows[above[i]] = 1.0 if power > 0 else 0.0
        lam_rows[below[i]] = 1.0 if power < 0 else 0.0
    for i in range(len(clearance)):
        dips = x[v[i]] > 0
        lam_rows[clearance[i]] = -1.0 if dips else 0.0
        lam_vars[v[i]] = 0.0 if dips else -1.0
    dual = np.empty(k + m + len(rk))
    for j in range(k):
        dual[j] = lam_vars[ck[j]]
    dual[k:k + m] = -1.0
    for r in range(len(rk)):
        dual[k + m + r] = lam_rows[rk[r]]
    return dual


@entry("(f8[:], f8[:, :], f8[:], f8[:], f8[:, :], f8[:], f8[:], i8[:], i8[:], i8, f8[:], b1[:], "
        "b1[:], b1[:], f8[:], f8[:, :], f8, f8, f8[:], f8[:], UniTuple(i8[:], 4), i8[:, :], "
        "f8[:], b1[:], f8, f8, f8, b1)")
def assemble(g, jac, grad, x, convexified, lbg, ubg, rows, cols, nc, col_lbx, equality,
             keep_rows, keep_cols, extra_cost, extra_curvature, radius, nu, last_rows,
             last_vars, start, slack_rows, slack_sign, slack_row, proximal, violated_tol, inf,
             drop):
    """DAQP's QP (H, f, A, bupper, blower, sense, dual start) over the kept rows and
    columns, with an elastic column for each hard row the point violates, without the rows
    no step in the trust region can reach (if drop); and the kept rows' and columns' NLP
    indices. jac: the rows' Jacobian in the coefficients; the slacks' columns are
    slack_sign at slack_rows (elastic_qp.slack_structure). start: (above, below, clearance,
    v) of the layout, whose multipliers the working set takes from the point (see
    _working_set)."""
    ck = cols[keep_cols]
    if drop:
        keep_rows = keep_rows & ~_out_of_reach(g, jac, lbg, ubg, rows, nc, equality, radius,
                                               slack_row)
    rk, eq = rows[keep_rows], equality[keep_rows]
    lr, k = len(rk), len(ck)
    low, high = lbg[rk] - g[rk], ubg[rk] - g[rk]
    m = 0
    for i in range(lr):
        if low[i] > violated_tol or high[i] < -violated_tol:
            m += 1
    size = k + m
    h = np.zeros((size, size))
    f = np.zeros(size)
    a = np.zeros((lr, size))
    upper, lower = np.empty(size + lr), np.empty(size + lr)
    sense = np.zeros(size + lr, np.int32)
    for i in range(nc):
        for j in range(nc):
            h[i, j] = convexified[i, j] + extra_curvature[i, j]
        f[i] = grad[ck[i]] + extra_cost[i]
        lower[i], upper[i] = -radius, radius
    slack_lbx = col_lbx[keep_cols[nc:]]
    for i in range(nc, k):
        h[i, i] = proximal
        f[i] = grad[ck[i]]
        lower[i], upper[i] = max(slack_lbx[i - nc] - x[ck[i]], -inf), inf
    at = np.full(len(g), -1)  # each NLP row's position among the kept
    for r in range(lr):
        at[rk[r]] = r
        for j in range(nc):
            a[r, j] = jac[rk[r], j]
    for j in range(nc, k):
        for row in slack_rows[ck[j] - nc]:
            if row >= 0 and at[row] >= 0:
                a[at[row], j] = slack_sign[ck[j] - nc]
    column = k
    for r in range(lr):
        if low[r] > violated_tol or high[r] < -violated_tol:
            a[r, column] = 1.0 if low[r] > violated_tol else -1.0
            h[column, column], f[column] = proximal, nu
            lower[column], upper[column] = 0.0, inf
            column += 1
        lower[size + r], upper[size + r] = max(low[r], -inf), min(high[r], inf)
        if eq[r]:
            sense[size + r] = 5  # DAQP: active + immutable
    dual = _working_set(g, x, rk, ck, k, m, nc, last_rows, last_vars, start)
    return h, f, a, upper, lower, sense, dual, rk, ck


@entry("(f8[:, :], f8)")
def convex(hessian, curvature):
    """The symmetric part of hessian with its eigenvalues clipped below at curvature x
    max(1, its largest |eigenvalue|)."""
    w, vectors = np.linalg.eigh(0.5 * (hessian + hessian.T))  # ascending w
    floor = curvature * max(1.0, abs(w[0]), abs(w[-1]))
    return (vectors * np.maximum(w, floor)) @ vectors.T


@entry("(f8[:], f8[:, :], f8[:], f8[:], f8[:, :], f8[:], f8[:], i8[:], i8[:], i8[:], i8[:], "
        "i8[:], i8[:], i8[:], i8[:], i8[:], i8[:], i8, f8[:], b1[:], f8, f8, f8[:], f8[:], "
        "UniTuple(i8[:], 4), i8[:, :], f8[:], b1[:], f8, f8, f8, f8, f8, f8, b1)")
def model(g, jac, grad, x, hessian, lbg, ubg, above, below, e, clearance, v, rows_at, second_at,
          cols_at, rows, cols, nc, col_lbx, equality, radius, nu, last_rows, last_vars, start,
          slack_rows, slack_sign, slack_row, hold, floor, curvature, proximal, violated_tol,
          inf, drop):
    """One call for a QP's first build: branches, the Hessian convexified (convex), the
    held items out (held_out) and DAQP's arrays (assemble); returns assemble's tuple, the
    branches' tuple and the convexified Hessian (for a rebuild when a held branch flips)."""
    branch = branches(g, jac, grad, x, lbg, above, below, e, clearance, v, nc, radius, hold,
                      floor)
    _, _, rate, slope, weight, held = branch
    convexified = convex(hessian, curvature)
    keep_rows, keep_cols, extra_cost, extra_curvature = held_out(
        held, rate, weight, slope, rows_at, second_at, cols_at, len(rows), len(cols), proximal)
    qp = assemble(g, jac, grad, x, convexified, lbg, ubg, rows, cols, nc, col_lbx, equality,
                  keep_rows, keep_cols, extra_cost, extra_curvature, radius, nu, last_rows,
                  last_vars, start, slack_rows, slack_sign, slack_row, proximal, violated_tol,
                  inf, drop)
    return qp, branch, convexified


@entry("(f8[:], f8[:], f8[:, :], f8[:], i8, i8[:], i8[:], i8, i8, f8[:], f8[:], f8[:], "
        "f8[:, :], f8[:], b1[:], i8[:], i8[:, :], f8)")
def unpack(solution, lam, h, f, k, rk, ck, n, rows_total, value, side, rate, slope, weight,
           held, slack, slack_rows, proximal):
    """The NLP's step and multipliers from DAQP's solution, the model's value and the
    linearized hard violation, which held items' branches the step flips (then nothing
    else is meaningful: the QP is solved again without them), the largest |row multiplier|
    and the step's largest coefficient change (max |d_j|, j < nc). slack: each item's slack
    (an NLP column); slack_rows: each slack's rows (elastic_qp.slack_structure)."""
    nc = slope.shape[1]
    d, lam_rows, lam_vars = np.zeros(n), np.zeros(rows_total), np.zeros(n)
    for j in range(k):
        d[ck[j]] = solution[j]
        lam_vars[ck[j]] = lam[j]
    size = len(solution)
    for r in range(len(rk)):
        lam_rows[rk[r]] = lam[size + r]
    model = 0.0
    for i in range(size):
        model += (f[i] if i < k else 0.0) * solution[i]
        for j in range(size):
            model += 0.5 * solution[i] * h[i, j] * solution[j]
    linear = 0.0
    for i in range(k, size):
        linear += solution[i]
    flipped = np.zeros(len(value), np.bool_)
    change = np.zeros(len(value))  # of P and of D along the step (linearized)
    for i in range(len(value)):
        for j in range(nc):
            change[i] += slope[i, j] * d[j]
    for i in range(len(value)):
        flipped[i] = held[i] and side[i] * (value[i] + change[i]) <= 0.0
    if flipped.any():
        return d, lam_rows, lam_vars, model, linear, flipped, 0.0, 0.0
    for i in range(len(value)):
        if not held[i]:
            continue
        moved = rate[i] * change[i]
        d[slack[i]] = moved
        multiplier = weight[i] + proximal * moved  # of the row holding a moving slack
        first, second = slack_rows[slack[i] - nc, 0], slack_rows[slack[i] - nc, 1]
        if second >= 0:  # a power sample: the row of its sign's side
            lam_rows[first] = multiplier if side[i] > 0 else 0.0
            lam_rows[second] = multiplier if side[i] < 0 else 0.0
        elif side[i] < 0:  # a violated clearance row: its lower bound
            lam_rows[first] = -multiplier
        else:  # a clear row: the slack's bound v >= 0
            lam_rows[first], lam_vars[slack[i]] = 0.0, -multiplier
    largest, reach = 0.0, 0.0
    for r in range(rows_total):
        largest = max(largest, abs(lam_rows[r]))
    for j in range(nc):
        reach = max(reach, abs(d[j]))
    return d, lam_rows, lam_vars, model, linear, flipped, largest, reach
