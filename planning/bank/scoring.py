"""The bank's measures of its plans at one sample (planning.bank.planner), each plan checked
once: its objective (planning.globalsearch.multistart.objective's: keeping the threshold
first, then the energy to go), its class (planning.bank.classes) and whether it must be
re-planned (planning.replanning.stale), all three from one check of its motion from the
sample on (the dense energy integral and each link's clearance at every forecast sample,
compiled: planning.anytime.safety), the forecast's samples packed once per sample.

The same numbers as those functions (the clearances are the compiled check's, not numpy's:
equal to rounding), at a fraction of their CPU: the class reads each link's closest approach
off the clearances and computes the arm's pose only where a link comes near, and the
objective skips the joint- and torque-limit check it does not use (docs/realtime.md, 'The
bank of plans')."""

from __future__ import annotations

import time

import numpy as np

from planning.bank.classes import motion_class, near_sides
from planning.replanning import TRIGGER_TOLERANCE, stale
from planning.types import Segment, SegmentPlan

TOLERANCE = 1e-12  # s: a forecast sample at the segment's end counts (as objective's)


class Scores:
    """The measures of plans on one segment (a re-plan's: from the arm's state at its sample,
    with its forecast), each plan measured once while this stands. `checked`: how many plans
    it has checked (the bank's work on the nominal clock); costs: where each check's CPU (ms)
    goes (what a check costs under CPU clocks: planning.bank.work.Work.check_ms)."""

    def __init__(self, check, config, problem: Segment, costs=None):
        self.check, self.config, self.problem = check, config, problem
        self.costs = [] if costs is None else costs
        self.t, self.duration, self.forecast = problem.t_begin, problem.duration, problem.forecast
        self._entries: dict = {}  # id(plan) -> (plan, clearances, objective); plan held alive
        self._classes: dict = {}
        self._bound = None
        self.checked = 0
        if self.forecast is not None:
            times = np.asarray(self.forecast.times, float)
            keep = (times > self.t + TOLERANCE) & (times <= self.t + self.duration + TOLERANCE)
            self.times, self.centres = times[keep], np.asarray(self.forecast.centres)[keep]
            self.whole = bool(np.all(keep)) and bool(np.any(keep))

    def unchecked(self, plans) -> int:
        """How many of the plans are not checked yet."""
        return sum(id(plan) not in self._entries for plan in plans)

    def objective(self, plan: SegmentPlan) -> tuple[int, float]:
        """multistart.objective of the plan's motion from the segment's start on: (2 if
        unusable, 1 if it misses the threshold beyond the penalty tolerance, else 0; the
        energy to go, J, plus elastic_weight times the L1 violation of the threshold)."""
        return self._entry(plan)[2]

    def motion_class(self, plan: SegmentPlan) -> tuple:
        """classes.motion_class of the plan on the forecast from the segment's start on."""
        key = id(plan)
        if key not in self._classes:
            self._classes[key] = (plan, self._class(plan))
        return self._classes[key][1]

    def _class(self, plan: SegmentPlan) -> tuple:
        trajectory = plan.trajectory
        if self.forecast is None:
            return ()
        if abs(trajectory.t_end - (self.t + self.duration)) > TOLERANCE:  # another horizon
            return motion_class(self.config.geometry, trajectory, self.forecast,
                                self.config.threshold, self.t)
        links = self._entry(plan)[1]
        return near_sides(self.config.geometry, links,
                          lambda k: trajectory.position(self.times[k : k + 1])[0],
                          self.centres, self.config.threshold,
                          angles=lambda: trajectory.position(self.times)[:, 0])

    def dips(self, plan: SegmentPlan) -> bool:
        """replanning.stale of the plan on the forecast (its motion from the segment's start
        on covers every forecast sample: the plans the bank follows)."""
        if self.forecast is None:
            return False
        if not self.whole:
            return stale(self.config, plan, self.forecast)
        clearance, threshold = float(self._entry(plan)[1].min()), self.config.threshold
        return clearance < threshold - TRIGGER_TOLERANCE or \
            ((plan.penalty > 0.0 or plan.detour) and clearance > threshold + TRIGGER_TOLERANCE)

    def _entry(self, plan: SegmentPlan) -> tuple:
        key = id(plan)
        if key not in self._entries:
            self.checked += 1
            began = time.thread_time()
            self._entries[key] = self._measured(plan)
            self.costs.append(1e3 * (time.thread_time() - began))
        return self._entries[key]

    def _measured(self, plan: SegmentPlan) -> tuple:
        """(plan, its clearances (k, links) or None without a forecast, its objective)."""
        rest = plan.trajectory.restrict(self.t, self.duration)
        energy, config = self.check.energy(rest), self.config
        if self.forecast is None:
            return plan, None, (2 * (not plan.success), energy)
        if self._bound is None:
            self._bound = self.check.against(self.times, self.centres, self.t, self.duration)
        links = self._bound.links(rest.coefficients)
        violation = float(np.sum(np.maximum(config.threshold - links, 0.0)))
        unsafe = config.threshold - float(np.min(links, initial=np.inf)) > \
            config.penalty_tolerance
        return plan, links, (2 * (not plan.success) or int(unsafe),
                             energy + config.anytime.elastic_weight * violation)
