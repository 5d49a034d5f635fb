"""An anytime trust-region SQP for the elastic planning NLP (planning.formulation.nlp, elastic=True).

The NLP's slacks enter linearly: the power epigraph e (rows P - e <= 0, -P - e <= 0) and the
clearance slacks v (rows D + v >= lambda, v >= 0). After every step they are reset to the
least values the rows allow (e = |P|, v = max(0, lambda - D)), so the merit function is the
exact nonsmooth objective sigma sum w |P| + alpha sum w max(0, lambda - D) plus nu times the
L1 violation of the other (hard) rows, and each QP is the Sl1QP model of it (Fletcher). A
QP is always feasible: the slacks absorb the clearance and power rows, and the hard rows the
current point violates get an elastic column of weight nu.

The dense QP (coefficients in a box trust region, slacks with a proximal term) is solved by
DAQP, a dual active-set solver, hot-started from the last working set's multipliers. The
Hessian of the Lagrangian (exact, compiled) only has a coefficient block; its eigenvalues are
clipped to keep the QP convex. Every accepted iterate goes to a caller's check (its safety
on the whole forecast); the solve stops at convergence or at a CPU budget (thread time).
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

import casadi as ca
import numpy as np

from planning.anytime import point_kernels
from planning.anytime.budget import RECENT, Clock
from planning.anytime.elastic_qp import VIOLATED, Frame, Layout, Point, linear_change, step
from planning.formulation import compiled

CONVERGED, BUDGET, STALLED, SETTLED = "converged", "budget", "stalled", "settled"
# an accepted step that lowered the merit by less than this share of the objective ends the
# solve unconverged (SETTLED; the next re-plan goes on from it): such steps gain little for
# their CPU (docs/realtime.md, 'planning.anytime.sqp')
SETTLED_SHARE = 2e-4
# predicted decrease (relative to the objective) below which a point is taken as optimal: the
# energy is nearly flat along many motions, where steps of 1e-8 went on for 100+ iterations
STEP_TOLERANCE = 1e-6
PRIMAL_TOLERANCE = 1e-8  # L1 violation of the hard rows at a converged point
# the trust region's first radius (the box on the trajectory's coefficients) in a cold plan;
# a warm re-plan starts from AnytimeOptions.warm_radius
COLD_RADIUS = 0.5
FRAMES = 64  # Frames kept per solver (a Frame is a few kB)
HARD_WEIGHT = 1e6  # nu's floor: hard rows (goal, limits) weigh far above the clearance's L1


@dataclass(frozen=True)
class Solution:
    """What a solve returns: the chosen point, its multipliers (rows, variables), why it
    stopped, its iterations and how many iterates the check saw."""

    x: np.ndarray
    f: float
    lam_g: np.ndarray
    lam_x: np.ndarray
    status: str
    iterations: int
    violation: float  # of the hard rows at x (L1)


class AnytimeSQP:
    """The solver for one elastic NLP: local evaluations by `local` (a compiled
    planning.anytime.local_model.local_function), the QPs by DAQP."""

    def __init__(self, local: ca.Function, layout: Layout, lbx: np.ndarray, rows: int,
                 settled_share: float = SETTLED_SHARE):
        self.local, self.layout, self.lbx = compiled.Buffered(local), layout, np.asarray(lbx, float)
        self.settled_share = settled_share  # 0: never settles (solved to convergence)
        n = len(self.lbx)
        self.sizes = (n, rows)  # variables, constraint rows
        # the slacks' rows and columns (above, below, e, clearance, v), for point_kernels.reset
        self._slacks = tuple(np.arange(part.start, part.stop) for part in
                             (layout.above, layout.below, layout.e, layout.clearance, layout.v))
        self.spent_ms = 0.0  # CPU ms in the compiled evaluations and the QP solver, so far
        self.solve_ms = 0.0  # CPU ms in solve, so far
        # CPU ms of the last RECENT iterations: the next one is expected to cost their most
        # (a spike, such as a first call's loading, ages out instead of shortening every
        # later re-plan's budget)
        self._recent: deque[float] = deque(maxlen=RECENT)
        self.loop_ms = 0.0
        self._frames: dict[bytes, Frame] = {}

    @property
    def iteration_ms(self) -> float:
        """What the next iteration is expected to cost (CPU ms): the most of the recent."""
        return max(self._recent, default=0.0)

    def forget(self) -> None:
        """Drop the recent iterations' costs (after the warm-up calls of prepare)."""
        self._recent.clear()

    def evaluate(self, x, p, lam, lbg, ubg=None) -> Point:
        """The point x with its slacks reset (see the module docstring), and the L1
        violation of its rows' bounds if ubg is given (else 0)."""
        began = time.thread_time()
        (out,) = self.local(x, p, lam)
        self.spent_ms += 1e3 * (time.thread_time() - began)
        n, rows = self.sizes
        lbg = np.asarray(lbg, float)
        f, grad, g, jac, hess, x, violation = point_kernels.reset(
            out, np.asarray(x, float), lbg, lbg if ubg is None else ubg, n, rows,
            self.layout.nc, *self._slacks)
        return Point(x, f, g, grad, jac, hess, 0.0 if ubg is None else violation)

    def solve(self, x0, p, lbg, ubg, lam_g0, budget_ms: float, accept, max_iter: int = 200,
              radius: float = COLD_RADIUS, lam_x0=None, clock: Clock | None = None,
              per_point_ms: float = 0.0) -> tuple[Solution, int]:
        """Iterate from x0 (multipliers lam_g0 for the first Hessian) until the predicted
        decrease vanishes or the clock (default: CPU time from now) reaches budget_ms; no
        iteration starts that would end past it, per_point_ms kept for each point accepted
        (and the one it may add: the caller's work per iterate after the solve). accept(point)
        is called on the start and every accepted iterate (its return value is ignored: the
        caller keeps the best one); returns the last point's solution and the iteration
        count."""
        entered = time.thread_time()
        clock = Clock() if clock is None else clock
        lbg, ubg = np.asarray(lbg, float), np.asarray(ubg, float)
        frame = self._frame(lbg, ubg)
        point = self._restored(self.evaluate(x0, p, lam_g0, lbg, ubg), p, lbg, ubg, lam_g0,
                               frame)
        accept(point)
        accepted = 1
        lam_x = np.zeros(len(point.x)) if lam_x0 is None else np.asarray(lam_x0, float)
        nu, lam_g = HARD_WEIGHT, np.asarray(lam_g0, float)
        status, iterations = BUDGET, 0
        self.loop_ms = 0.0  # CPU ms of this solve's iterations (CPU clocks)
        while iterations < max_iter:
            began = clock.ms()
            if began + clock.iteration(self.iteration_ms) + per_point_ms * (accepted + 1) \
                    > budget_ms:
                if not iterations and self._recent:  # none fits: the oldest cost ages out
                    self._recent.popleft()
                break
            iterations += 1
            step = self._qp(point, lbg, ubg, frame, radius, nu, (lam_g, lam_x))
            if step is None:
                status = STALLED
                break
            d, lam_rows, lam_vars, pred_parts, (largest, step_size) = step
            nu = max(nu, 10.0 * largest)
            model, linear_violation = pred_parts
            pred = -model + nu * (point.violation - linear_violation)
            scale = 1.0 + abs(point.f)
            if -model <= STEP_TOLERANCE * scale and \
                    max(point.violation, linear_violation) <= PRIMAL_TOLERANCE:
                lam_g, lam_x, status = lam_rows, lam_vars, CONVERGED
                break
            trial = self.evaluate(point.x + d, p, lam_rows, lbg, ubg)
            actual = point.f + nu * point.violation - trial.f - nu * trial.violation
            ratio = actual / pred if pred > 0 else -1.0
            # the rows' curvature spoiled the step (Maratos): correct it, if the correction
            # (a QP and an evaluation, about what the iteration cost so far) fits the budget
            if ratio < 1e-4 and clock.correction_fits(began, budget_ms):
                corrected = self._corrected(point, trial, p, lbg, ubg, frame, radius, nu,
                                            (lam_rows, lam_vars))
                clock.tick()
                if corrected is not None:
                    better = point.f + nu * point.violation - corrected[0].f \
                        - nu * corrected[0].violation
                    if better / pred >= 1e-4:
                        trial, (lam_rows, lam_vars), ratio = corrected[0], corrected[1], \
                            better / pred
            settled = False
            if ratio >= 1e-4:  # the merit's decrease is pred x ratio (corrected or not)
                settled = pred * ratio <= self.settled_share * abs(trial.f) and \
                    trial.violation <= PRIMAL_TOLERANCE
                point, lam_g, lam_x = trial, lam_rows, lam_vars
                accept(point)
                accepted += 1
            clock.tick()
            if clock.nominal is None:
                self._recent.append(clock.ms() - began)
                self.loop_ms += self._recent[-1]
            if settled:
                status = SETTLED
                break
            if ratio < 0.25:
                radius = 0.5 * step_size
                if radius < 1e-10:
                    status = STALLED
                    break
            elif ratio > 0.5 and step_size > 0.99 * radius:
                # the energy is nearly flat along many motions (a conservative model's power
                # keeps its sign): the model's decrease is then ~linear and the step rides the
                # boundary at ratios below 0.75 (docs/realtime.md, 'planning.anytime.sqp')
                radius = min(2.0 * radius, 10.0)
        self.solve_ms += 1e3 * (time.thread_time() - entered)
        return Solution(point.x, point.f, lam_g, lam_x, status, iterations,
                        point.violation), iterations

    def _frame(self, lbg: np.ndarray, ubg: np.ndarray) -> Frame:
        """The solve's Frame (its rows with a bound, its variables: a clearance slack
        without its row stays out), kept per pattern of bounds: the rounds of a re-plan
        and the re-plans of one motion share a few."""
        lay = self.layout
        lower, upper, equal = np.isfinite(lbg), np.isfinite(ubg), lbg == ubg
        key = lower.tobytes() + upper.tobytes() + equal.tobytes()
        frame = self._frames.get(key)
        if frame is None:
            if len(self._frames) >= FRAMES:
                self._frames.clear()
            rows = np.flatnonzero(lower | upper)
            kept = np.ones(len(self.lbx), bool)
            kept[lay.v][~lower[lay.clearance]] = False  # a clearance slack without its row
            cols = np.flatnonzero(kept)
            frame = self._frames[key] = Frame(rows, cols, lay, equal[rows],
                                              self.lbx[cols[lay.nc:]])
        return frame

    def _restored(self, point: Point, p, lbg, ubg, lam, frame: Frame) -> Point:
        """The point with its equality rows restored by one least-change Newton step in the
        coefficients where it leaves them (a cold start point with bumps reaches the goal but
        not at rest, which the trust region would take the whole budget to mend,
        (docs/realtime.md, 'planning.anytime.sqp')); the point as it is otherwise."""
        equal = frame.equal_rows
        residual = point.g[equal] - lbg[equal]
        if not len(equal) or np.max(np.abs(residual)) <= VIOLATED:
            return point
        nc = self.layout.nc
        step = np.zeros(len(point.x))
        step[:nc] = -np.linalg.lstsq(point.jac[equal, :nc], residual, rcond=None)[0]
        restored = self.evaluate(point.x + step, p, lam, lbg, ubg)
        return restored if restored.violation < point.violation else point

    def _qp(self, point: Point, lbg, ubg, frame: Frame, radius: float, nu: float, last):
        """planning.anytime.elastic_qp.step but its DAQP time, counted in spent_ms."""
        result = step(point, lbg, ubg, frame, radius, nu, last, self.layout)
        if result is None:
            return None
        self.spent_ms += result[4]
        return result[:4] + result[5:]

    def _corrected(self, point: Point, trial: Point, p, lbg, ubg, frame, radius, nu, last):
        """A second-order correction (Fletcher): the QP again with the rows' values at the
        trial point less their linear change, c = g(trial) - J (trial - x), so the step
        lands on the rows' curved surfaces; the corrected trial point and its multipliers,
        or None: near a minimum-violation plan's kinks plain steps alone make slow progress
        (docs/realtime.md, 'planning.anytime.sqp')."""
        shifted = Point(point.x, point.f,
                        trial.g - linear_change(point, trial.x - point.x, self.layout),
                        point.grad, point.jac, point.hess, point.violation)
        step = self._qp(shifted, lbg, ubg, frame, radius, nu, last)
        if step is None:
            return None
        corrected = self.evaluate(point.x + step[0], p, step[1], lbg, ubg)
        return corrected, (step[1], step[2])

