"""The NLP solvers the planner can use, each with a cold and a warm option set.

- "fatrop": CasADi's fatrop plugin (interior point, its dense problem type: the
  planning NLP is one stage, not an optimal-control chain, so structure detection
  is "none"; "auto" needs a stage structure). Primal warm start; its interface does
  not take initial multipliers.
- "sqpmethod": CasADi's SQP with exact Hessians (eigenvalues clipped to keep each QP
  convex) and qpOASES on the dense QPs; warm-started in primal and dual variables.
- "ipopt": the paper's interior point (MUMPS); warm-started in primal and dual
  variables with a tiny barrier.
- "feasiblesqp": CasADi's feasible SQP (feasiblesqpmethod: a trust-region SQP whose every
  iterate satisfies the constraints, given a start that does), qpOASES on the QPs. It
  needs a feasible start, so it only serves warm solves: the planner's real-time
  iterations (PenaltyOptions.replan_iterations), whose capped iterate the arm can follow.
Their cost per iteration: docs/realtime.md, 'planning.penalty.backends'.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass

import casadi as ca
import numpy as np

from planning.formulation import compiled

SOLVERS = ("fatrop", "sqpmethod", "ipopt")  # cold and warm solves; feasiblesqp: warm only
_QUIET = {"print_time": False}


@dataclass(frozen=True)
class Stats:
    """How one solve went, in the same words for every solver."""

    success: bool
    status: str
    iterations: int


def _ipopt(max_iter: int, warm: bool, hessian: str, equality) -> dict:
    options = {"ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-8,
               "ipopt.constr_viol_tol": 1e-9, "ipopt.max_iter": max_iter,
               "ipopt.hessian_approximation": hessian}
    # a primal-dual warm start with a tiny barrier and bound pushes; a re-plan stops at tol
    # 1e-6 (tests/test_planning_scenario.py) (docs/realtime.md, 'planning.penalty.backends')
    if warm:
        options.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-7,
                        "ipopt.warm_start_bound_push": 1e-7,
                        "ipopt.warm_start_mult_bound_push": 1e-7, "ipopt.tol": 1e-6})
    return options


def _fatrop(max_iter: int, warm: bool, hessian: str, equality) -> dict:
    # mu_init and tol chosen on warm re-plans and the paper scenario
    # (docs/realtime.md, 'planning.penalty.backends')
    return {"structure_detection": "none", "equality": [bool(e) for e in equality],
            "fatrop.print_level": 0, "fatrop.mu_init": 1e-4, "fatrop.max_iter": max_iter,
            "fatrop.tol": 1e-6 if warm else 1e-7}


def _sqpmethod(max_iter: int, warm: bool, hessian: str, equality) -> dict:
    return {"qpsol": "qpoases", "convexify_strategy": "eigen-clip", "max_iter": max_iter,
            "hessian_approximation": hessian, "tol_pr": 1e-9, "tol_du": 1e-6 if warm else 1e-8,
            "print_header": False, "print_iteration": False, "print_status": False,
            "qpsol_options": {"printLevel": "none", "sparse": False, "error_on_fail": False},
            "error_on_fail": False}


# feasiblesqp's feasibility tolerance, and the one its capped iterate is followed within: the
# start must be feasible within the first, and a capped iterate may leave the constraints by a
# little more than it, so an iterate followed, the next start, is held to the second; a
# tighter first one refuses fatrop's converged plans as starts
# (docs/realtime.md, 'planning.penalty.backends').
FEASIBLE_START, FEASIBLE_ITERATE = 1e-6, 5e-7


def _feasiblesqp(max_iter: int, warm: bool, hessian: str, equality) -> dict:
    return {"max_iter": max_iter, "hessian_approximation": hessian, "feas_tol": FEASIBLE_START,
            "print_header": False, "print_iteration": False, "print_status": False,
            "qpsol": "qpoases", "qpsol_options": {"printLevel": "none", "sparse": False,
                                                  "error_on_fail": False},
            "error_on_fail": False}


_OPTIONS = {"ipopt": _ipopt, "fatrop": _fatrop, "sqpmethod": _sqpmethod,
            "feasiblesqp": _feasiblesqp}
_PLUGINS = {"feasiblesqp": "feasiblesqpmethod"}  # CasADi's name of the plugin


def solver(name: str, plugin: str, problem: dict, equality: np.ndarray, *, warm: bool,
           max_iter: int, hessian: str, compile_code: bool, quick: bool = False
           ) -> ca.Function:
    """An nlpsol instance of `plugin` on problem (x, p, f, g); equality: which rows of g are
    equalities (fatrop needs it); compile_code: NLP functions as compiled C (cached; quick:
    planning.formulation.compiled's quick build)."""
    if plugin not in _OPTIONS:
        raise ValueError(f"solver must be one of {SOLVERS} (or feasiblesqp, for warm solves "
                         f"from a feasible start), got '{plugin}'")
    options = dict(_QUIET, **_OPTIONS[plugin](max_iter, warm, hessian, equality))
    casadi_name = _PLUGINS.get(plugin, plugin)
    with _silenced() if plugin in ("sqpmethod", "feasiblesqp") else contextlib.nullcontext():
        # both build qpOASES, which prints its licence banner for each instance (8 times in
        # the bench's log before)
        if compile_code and compiled.available():
            function = compiled.nlpsol(name, casadi_name, problem, options, quick)
        else:
            function = ca.nlpsol(name, casadi_name, problem, options)
    return Silenced(function) if plugin in ("sqpmethod", "feasiblesqp") else function


def _silenced():
    """Standard output swallowed (CasADi writes its plugins' output to Python's sys.stdout):
    CasADi 3.8's feasiblesqpmethod prints its set-up and trust-region trace whatever its
    print options."""
    return contextlib.redirect_stdout(io.StringIO())


class Silenced:
    """A feasiblesqp or sqpmethod instance (a ca.Function in every other respect) whose calls
    print nothing: qpOASES reports every QP it fails on (449 lines in the bench's log; the
    planner judges the solve by its own status or KKT check)."""

    def __init__(self, function: ca.Function):
        self.function = function

    def __call__(self, **kwargs):
        with _silenced():
            return self.function(**kwargs)

    def __getattr__(self, name):
        return getattr(self.function, name)


# a point whose returned KKT residuals are this small is converged (planning.penalty.backends.stats):
# sqpmethod's own test is tol_pr 1e-9 and tol_du 1e-6 warm, 1e-8 cold; the check takes 1e-8
# (room for the rounding of g) and 1e-6 for both, so a cold solve capped within 1e-6 passes
KKT_PRIMAL, KKT_DUAL = 1e-8, 1e-6


def stats(function: ca.Function, args: dict | None = None, result: dict | None = None) -> Stats:
    """Success, status and iteration count of the last call of an nlpsol instance. For
    sqpmethod, whose status CasADi 3.8 does not keep (see _kkt), and any solver that leaves
    none, the KKT conditions of the point it returned decide (args: the call's p, lbg, ubg;
    result: its output); its iteration count is kept where stats() gives one (-1 otherwise)."""
    try:
        info = function.stats()
    except RuntimeError:
        info = None
    iterations = -1 if info is None else int(info.get("iter_count", -1))
    if (info is None or function.class_name() == "Sqpmethod") and args is not None \
            and result is not None:
        return _kkt(function, args, result, iterations)
    if info is None:
        return Stats(False, "no status (the solver left none)", -1)
    status = info.get("return_status", info.get("unified_return_status", ""))
    return Stats(bool(info["success"]), str(status), iterations)


def violation(result: dict, args: dict) -> float:
    """How far the returned point's constraints g leave [lbg, ubg] (0 within them)."""
    g = np.asarray(result["g"]).ravel()
    return float(max(np.max(np.asarray(args["lbg"], float) - g, initial=0.0),
                     np.max(g - np.asarray(args["ubg"], float), initial=0.0)))


def _kkt(function: ca.Function, args: dict, result: dict, iterations: int) -> Stats:
    """Converged or not by the KKT conditions at the returned point: primal feasibility,
    stationarity of the Lagrangian (the problem has no variable bounds, so lam_x is 0 at a
    KKT point and enters the residual as it is), and complementarity (|multiplier| times the
    distance to the bound its sign points to: > 0 for the upper one; inf on a free row).
    CasADi 3.8's sqpmethod does not set its status when it converges or a QP fails:
    Function.stats() raises, or reports an earlier call's status
    (docs/realtime.md, 'planning.penalty.backends').
    Reading that as a failure had sent converged solves to the IPOPT rescue. The check is
    part of the solve's time (the planner needs it to decide on the rescue)."""
    lam_g = np.asarray(result["lam_g"]).ravel()
    grad = function.get_function("nlp_grad")(x=result["x"], p=args["p"], lam_f=1.0,
                                              lam_g=result["lam_g"])
    stationarity = np.max(np.abs(np.asarray(grad["grad_gamma_x"] + result["lam_x"])),
                          initial=0.0)
    g = np.asarray(result["g"]).ravel()
    lbg, ubg = np.asarray(args["lbg"], float), np.asarray(args["ubg"], float)
    primal = violation(result, args)
    slack = np.where(lam_g > 0, ubg - g, g - lbg)
    weighty = np.abs(lam_g) > KKT_DUAL
    complementarity = np.max(np.abs(lam_g[weighty]) * slack[weighty], initial=0.0)
    converged = primal <= KKT_PRIMAL and stationarity <= KKT_DUAL and \
        complementarity <= KKT_DUAL
    status = (f"KKT at the returned point: primal {primal:.1e}, stationarity "
              f"{stationarity:.1e}, complementarity {complementarity:.1e}")
    return Stats(bool(converged), ("converged" if converged else "not converged") + " (" +
                 status + ")", iterations)
