"""The arrays of one anytime-SQP point (planning.anytime.sqp.AnytimeSQP.evaluate), compiled by
numba as planning.anytime.qp_kernels: a local evaluation's column unpacked, its slacks reset,
and the L1 violation of its rows' bounds (the merit's)."""

from __future__ import annotations

from planning.anytime.qp_kernels import entry


@entry("(f8[:], f8[:], f8[:])")
def violation(g, lbg, ubg):
    """L1 distance of the rows g from [lbg, ubg]."""
    total = 0.0
    for i in range(len(g)):
        total += max(lbg[i] - g[i], 0.0) + max(g[i] - ubg[i], 0.0)
    return total


@entry("(f8[:], f8[:], f8[:], f8[:], i8, i8, i8, i8[:], i8[:], i8[:], i8[:], i8[:])")
def reset(out, x, lbg, ubg, n, rows, nc, above, below, e, clearance, v):
    """A local evaluation's column (f, grad f, g, the Jacobian in the coefficients
    row-major, their Hessian) unpacked into copies, at x with its slacks reset to the least values their
    rows allow (e = |P|, v = max(0, lambda - D)) and f, g moved with them: f, grad, g, jac,
    hess, x, and the reset rows' L1 distance from [lbg, ubg] (violation)."""
    grad, g = out[1:1 + n].copy(), out[1 + n:1 + n + rows].copy()
    start = 1 + n + rows
    jac = out[start:start + rows * nc].copy().reshape((rows, nc))
    hess = out[start + rows * nc:start + rows * nc + nc * nc].copy().reshape((nc, nc))
    x, f = x.copy(), out[0]
    for i in range(len(e)):
        power = 0.5 * (g[above[i]] - g[below[i]])
        magnitude = abs(power)
        f += grad[e[i]] * (magnitude - x[e[i]])
        x[e[i]], g[above[i]], g[below[i]] = magnitude, power - magnitude, -power - magnitude
    for i in range(len(v)):
        distance = g[clearance[i]] - x[v[i]]
        slack = max(0.0, lbg[clearance[i]] - distance)
        f += grad[v[i]] * (slack - x[v[i]])
        x[v[i]], g[clearance[i]] = slack, distance + slack
    return f, grad, g, jac, hess, x, violation(g, lbg, ubg)
