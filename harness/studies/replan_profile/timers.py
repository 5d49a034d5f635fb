"""Timers around the anytime SQP's parts while `plan` runs (the replan_profile study).

Each part's function is replaced, for the duration of `installed()`, by one that reads the
planning thread's CPU clock (time.thread_time_ns) before and after it:

- leaves, timed inside an SQP iteration: the compiled CasADi call (the C itself) and the
  copies into its buffers, the QP's numba kernels, DAQP, the merit's violation, the point's
  reset (the PARTS table);
- windows, timed per re-plan: the bank's re-plan (planning.bank.planner.BankPlanner.plan
  with a warm plan), each round of a plan (planning.anytime.solver.Anytime.solve), each SQP
  solve, the choice among its iterates (their safety checks), and the global search, whose
  CPU is left out of the re-plan's as PLAN.json's timing leaves it out.

An iteration runs from the start of its QP to the start of the next one (or the end of its
solve); what its leaves do not account for is the Python around them. The timers' own cost
is measured (overhead_ns) and taken out of each iteration's Python share.
"""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import ExitStack, contextmanager

import daqp

from planning.anytime import elastic_qp, point_kernels, solver, sqp
from planning.anytime import qp_kernels as kernels
from planning.bank.planner import BankPlanner
from planning.formulation import compiled
from planning.globalsearch.multistart import MultiStart

now = time.thread_time_ns
# the parts of an iteration: (name in the table, what is timed)
PARTS = {
    "evaluation": "the compiled CasADi local model (its C: f, gradient, rows, Jacobian, "
                  "Hessian)",
    "evaluation call": "the Python call of it (copies into its buffers)",
    "reset and merit": "the point's slacks reset and its rows' L1 violation (numba)",
    "QP build": "the slacks' branches, the Hessian's eigenvalues clipped (LAPACK eigh), "
                "rows and columns held out, DAQP's arrays (numba)",
    "DAQP setup": "DAQP's setup (its own clock: its workspace, the LDP transformation)",
    "DAQP solve": "DAQP's active-set iterations (its own clock)",
    "DAQP call": "daqp.solve but its setup and iterations (its Python wrapper)",
    "unpack": "the step and multipliers unpacked (numba)",
}
# each kernel's part (the fused `model` calls branches, convex, held_out and assemble inside)
_KERNELS = {"model": "QP build", "branches": "QP build", "convex": "QP build",
            "held_out": "QP build", "assemble": "QP build", "unpack": "unpack",
            "reset": "reset and merit", "violation": "reset and merit"}
_MODULES = (kernels, point_kernels)  # where the kernels are (either, by the code's age)
_CHECKS = ("clearance_check", "motion_check", "dense_energy")


class Recorder:
    """Per-iteration parts (ns) and per-re-plan windows (ns) of the re-plans timed."""

    def __init__(self):
        self.iterations: list[dict[str, int]] = []
        self.replans: list[dict[str, int]] = []
        self.calls = 0  # timed calls inside iterations (each costs overhead_ns)
        self._replan: dict[str, int] | None = None
        self._iteration: dict[str, int] | None = None
        self._began = 0
        self._searching = 0
        self._correcting = 0

    # leaves --------------------------------------------------------------------------------
    def leaf(self, part: str, function):
        def timed(*args, **kwargs):
            began = now()
            try:
                return function(*args, **kwargs)
            finally:
                self._add(part, now() - began)
        return timed

    def _add(self, part: str, ns: int) -> None:
        if self._searching or self._replan is None:
            return
        if self._iteration is not None:
            self._iteration[part] += ns
            self.calls += 1
        elif part == "checks":
            self._replan["checks"] += ns

    # windows -------------------------------------------------------------------------------
    def window(self, name: str, function, when=lambda *args, **kwargs: True):
        def timed(*args, **kwargs):
            if self._searching or not when(*args, **kwargs) or \
                    (name != "replan" and self._replan is None):
                return function(*args, **kwargs)
            opened = name == "replan"
            if opened:
                self._replan = defaultdict(int)
            replan, began = self._replan, now()
            try:
                return function(*args, **kwargs)
            finally:
                spent = now() - began
                if name == "sqp":
                    self._close()
                replan[name] += spent
                if opened:
                    self.replans.append(dict(replan))
                    self._replan = None
        return timed

    def search(self, function):
        def timed(*args, **kwargs):
            self._searching += 1
            began = now()
            try:
                return function(*args, **kwargs)
            finally:
                self._searching -= 1
                if self._replan is not None and not self._searching:
                    self._replan["search"] += now() - began
        return timed

    # iterations ----------------------------------------------------------------------------
    def qp(self, function):
        """AnytimeSQP._qp: an iteration begins at its QP (not a correction's)."""
        def timed(solver_self, *args, **kwargs):
            if not self._correcting and not self._searching and self._replan is not None:
                self._close()
                self._iteration, self._began = defaultdict(int), now()
            return function(solver_self, *args, **kwargs)
        return timed

    def corrected(self, function):
        def timed(*args, **kwargs):
            self._correcting += 1
            try:
                return function(*args, **kwargs)
            finally:
                self._correcting -= 1
                if self._iteration is not None:
                    self._iteration["corrections"] += 1
        return timed

    def _close(self) -> None:
        if self._iteration is not None:
            self._iteration["total"] = now() - self._began
            self._replan["iterations"] += self._iteration["total"]
            self.iterations.append(dict(self._iteration))
            self._iteration = None


def _daqp(recorder: Recorder, solve):
    """daqp.solve timed, its CPU split as the wall clock of the call splits between the
    setup and iterations it reports (wall clock inside its C) and the rest (its wrapper):
    on a loaded machine the thread loses the core inside the call too."""
    def timed(*args, **kwargs):
        began, wall = now(), time.perf_counter_ns()
        result = solve(*args, **kwargs)
        spent, wall, info = now() - began, time.perf_counter_ns() - wall, result[3]
        share = spent / max(wall, 1)
        setup, iterations = (int(share * 1e9 * info[key]) for key in ("setup_time",
                                                                       "solve_time"))
        recorder._add("DAQP setup", setup)
        recorder._add("DAQP solve", iterations)
        recorder._add("DAQP call", spent - setup - iterations)
        return result
    return timed


def _buffered_call(recorder: Recorder, call):
    """compiled.Buffered.__call__ timed: the local model's call (its copies) apart from its
    C, the safety checks' whole calls as checks."""
    def timed(buffered, *args):
        name = buffered.function.name()
        if name == "elastic_local":
            began = now()
            out = call(buffered, *args)
            recorder._add("evaluation call", now() - began - buffered.c_ns)
            return out
        if name in _CHECKS:
            return recorder.leaf("checks", call)(buffered, *args)
        return call(buffered, *args)
    return timed


def _buffered_init(recorder: Recorder, init):
    """compiled.Buffered.__init__, its C call (the local model's) timed apart."""
    def timed(buffered, function):
        init(buffered, function)
        buffered.c_ns = 0
        if function.name() == "elastic_local":
            evaluate = buffered._evaluate

            def c_call():
                began = now()
                evaluate()
                buffered.c_ns = now() - began
                recorder._add("evaluation", buffered.c_ns)
            buffered._evaluate = c_call
    return timed


@contextmanager
def installed(recorder: Recorder):
    """The timers in place (module attributes patched, put back on exit)."""
    patches = [(module, name, recorder.leaf(part, getattr(module, name)))
               for module in _MODULES for name, part in _KERNELS.items()
               if name in vars(module)]
    patches += [(daqp, "solve", _daqp(recorder, daqp.solve)),
                (compiled.Buffered, "__call__", _buffered_call(recorder,
                                                               compiled.Buffered.__call__)),
                (compiled.Buffered, "__init__", _buffered_init(recorder,
                                                               compiled.Buffered.__init__)),
                (sqp.AnytimeSQP, "_qp", recorder.qp(sqp.AnytimeSQP._qp)),
                (sqp.AnytimeSQP, "_corrected", recorder.corrected(sqp.AnytimeSQP._corrected)),
                (sqp.AnytimeSQP, "solve", recorder.window("sqp", sqp.AnytimeSQP.solve)),
                (solver.Anytime, "solve", recorder.window("round", solver.Anytime.solve)),
                (solver, "choose", recorder.window("choice", solver.choose)),
                (BankPlanner, "plan", recorder.window(
                    "replan", BankPlanner.plan,
                    lambda planner, problem, warm=None: warm is not None)),
                (MultiStart, "search", recorder.search(MultiStart.search))]
    with ExitStack() as stack:
        for owner, name, replacement in patches:
            original = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
            stack.callback(setattr, owner, name, original)
            setattr(owner, name, replacement)
        yield recorder
    assert elastic_qp.daqp is daqp  # the module the QP calls through


def overhead_ns(repeats: int = 20000) -> float:
    """CPU ns a timed leaf adds to its caller (the timer's own calls), median of 5 runs."""
    recorder = Recorder()
    recorder._replan, recorder._iteration = defaultdict(int), defaultdict(int)
    timed = recorder.leaf("x", _nothing)
    costs = []
    for _ in range(5):
        began = now()
        for _ in range(repeats):
            _nothing()
        bare = now() - began
        began = now()
        for _ in range(repeats):
            timed()
        costs.append((now() - began - bare) / repeats)
    return sorted(costs)[2]


def _nothing():
    return None
