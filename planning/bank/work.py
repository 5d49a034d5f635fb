"""The bank's work at one sample (planning.bank.planner): its solves and its own bookkeeping
(checking its plans: planning.bank.scoring), on the budgets' clock and in wall and CPU time
of the planning thread (docs/realtime.md, 'The bank of plans').

On the nominal clock (AnytimeOptions.iteration_ms) the bookkeeping counts CHECK_ITERATIONS
SQP iterations of the arm per plan checked: a count of what was done, the same on any
machine. Under CPU clocks it counts its CPU, and keeps back from a solve's
budget what its checks after the solve recently cost. The times reported (SegmentPlan.solve_ms,
solve_cpu_ms) are all the planning thread spent in the bank's re-plan (its solves, the
global search's checks around the plan followed's, the bank's own) but the global search's
own work there: on the nominal clock the search itself, run there and then as if on
another core, under CPU clocks its hand-over to the other process (TimedSearch)."""

from __future__ import annotations

import dataclasses
import time
from collections import deque

from planning.anytime.budget import RECENT
from planning.types import SegmentPlan

# a plan checked (its dense energy integral, each link's clearance at every forecast sample,
# its class where a link comes near), in SQP iterations of the arm: on the Lynxmotion the
# bank's bookkeeping at a sample took 0.27 ms per plan checked (fitted over 3580 samples of
# the bank study's 20 scenarios, fixed part about nil) where an SQP iteration took 0.79 ms
# (each nominally 0.5 ms), both at load 6 on 2 cores
CHECK_ITERATIONS = 0.35


class TimedSearch:
    """The global search's object in the planning thread (planning.globalsearch: the nominal
    clock's MultiStart, or under CPU clocks the Background handing searches to the other
    process), the wall and CPU time of its method `name` summed (ms) to be left out of the
    bank's: the search runs as if on another core; its first hand-over starts that process."""

    def __init__(self, search, name: str):
        self._search, self._name, self.wall, self.cpu = search, name, 0.0, 0.0

    def __getattr__(self, name):
        method = getattr(self._search, name)
        return self._timed(method) if name == self._name else method

    def _timed(self, method):
        def timed(*args, **kwargs):
            wall, cpu = time.perf_counter(), time.thread_time()
            try:
                return method(*args, **kwargs)
            finally:
                self.wall += 1e3 * (time.perf_counter() - wall)
                self.cpu += 1e3 * (time.thread_time() - cpu)
        return timed


def recent() -> deque:
    """Where the CPU (ms) of the recent checks of plans goes (Scores.costs)."""
    return deque(maxlen=RECENT)


def timed_search(planner) -> TimedSearch | None:
    """The global search of a planning.globalsearch.planner.GlobalSearchPlanner timed where
    it runs in the planning thread (its search on the nominal clock, its hand-over to the
    other process under CPU clocks), None without one."""
    for attribute, name in (("_search", "search"), ("_background", "submit")):
        if getattr(planner, attribute, None) is not None:
            timed = TimedSearch(getattr(planner, attribute), name)
            setattr(planner, attribute, timed)
            return timed
    return None


class Work:
    """One sample's work. nominal: AnytimeOptions.iteration_ms (None: CPU clocks); scores:
    the sample's planning.bank.scoring.Scores (its `checked` count); search: the TimedSearch
    whose time is left out, or None."""

    def __init__(self, nominal: float | None, scores, search: TimedSearch | None = None):
        self.nominal, self.scores, self.search = nominal, scores, search
        self.wall, self.cpu = time.perf_counter(), time.thread_time()
        self._searched = (search.wall, search.cpu) if search is not None else (0.0, 0.0)
        self.solved = 0.0  # the solves' work on the budgets' clock (ms)

    def solve(self, plan, problem, warm: SegmentPlan) -> SegmentPlan:
        """plan(problem, warm) (a SegmentPlanner's), counted."""
        new = plan(problem, warm)
        self.solved += new.clock_ms
        return new

    def _outside(self, k: int) -> float:
        if self.search is None:
            return 0.0
        return (self.search.wall, self.search.cpu)[k] - self._searched[k]

    def clock_ms(self) -> float:
        """The work so far on the budgets' clock (ms)."""
        if self.nominal is None:
            return self.cpu_ms()
        return self.solved + self.check_ms() * self.scores.checked

    def check_ms(self) -> float:
        """What a plan checked counts on the budgets' clock: nominally CHECK_ITERATIONS
        iterations; under CPU clocks the most a recent check took (Scores.costs)."""
        if self.nominal is None:
            return max(self.scores.costs, default=0.0)
        return self.nominal * CHECK_ITERATIONS

    def cpu_ms(self) -> float:
        return 1e3 * (time.thread_time() - self.cpu) - self._outside(1)

    def timed(self, plan: SegmentPlan) -> SegmentPlan:
        """The plan with the sample's whole work as its times."""
        return dataclasses.replace(plan, clock_ms=self.clock_ms(), solve_cpu_ms=self.cpu_ms(),
                                   solve_ms=1e3 * (time.perf_counter() - self.wall) -
                                   self._outside(0))


def described(nominal: bool) -> str:
    """What the bank's times and clock count (PLAN.json's bank.work, timing.replan_work)."""
    clock = (f"on the nominal clock its solves' SQP iterations and {CHECK_ITERATIONS} of an "
             f"iteration per plan checked" if nominal else "under CPU clocks all its CPU")
    return (f"the whole bank's at each re-plan: its solves and its checks of its plans "
            f"(CPU and wall: all the planning thread's but the global search's own; "
            f"{clock})")
