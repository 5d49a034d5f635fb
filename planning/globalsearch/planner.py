"""GlobalSearchPlanner: the real-time loop's planner (the anytime SQP) with a global search
beside it (GlobalSearchOptions), a SegmentPlanner (planning.types) like the one it wraps.

After a re-plan the latest forecast goes to the search (when none runs, the obstacle still
shapes the plan and the forecast is new), planned from the plan the arm now follows. On the
nominal clock the search runs there and then, synchronously (the same plans on any machine),
and every plan it finds better than those before it is offered at the re-plan where the
search's work up to it is done, at least `lag` obstacle samples later; under CPU clocks each
better plan the other process sends back is offered as it arrives. A re-plan with an offer whose motion
from now on scores better on the current forecast than the plan followed
(multistart.objective: safe first, then the energy to go) goes on from it with the whole
budget, and adopts the result (its status marked ADOPTED) if it keeps the clearance and
spends less than the plan followed; otherwise the arm keeps that plan (Algorithm 2 re-plans
from it at the next sample if it must). An offer that scores no better leaves the re-plan as
it was."""

from __future__ import annotations

import dataclasses
import math

from identification.torque_model import TorqueModel
from planning.anytime.safety import SafetyCheck
from planning.config import PlannerConfig
from planning.globalsearch.background import Background, cores
from planning.globalsearch.multistart import MultiStart, bank_search, objective
from planning.replanning import same_prediction
from planning.types import Segment, SegmentPlan, SegmentPlanner

ADOPTED = " (global search)"  # the status's tail of a re-plan adopted from the search
NEAR = 0.1  # m above the threshold within which the obstacle still shapes a plan: searched
SAMPLE_TOLERANCE = 1e-9  # s


class GlobalSearchPlanner:
    """`inner`'s plans, its re-plans adopting the global search's plans when they win."""

    def __init__(self, inner: SegmentPlanner, model: TorqueModel, config: PlannerConfig,
                 bank: bool = False):
        """bank: a bank of plans' search (planning.bank): from the arm's state at the
        re-plan, shallower (bank_search), and every plan it finds is also collected
        (GlobalSearchPlanner.collect) as it enters, when the search's work up to it is done."""
        self.inner, self.config, self.bank = inner, config, bank
        lagged = config.anytime.iteration_ms is not None or not config.global_search.background
        # with one core the search would take the real-time loop's: the loop runs alone
        self.mode = "lagged" if lagged else ("process" if cores() > 1 else "one core")
        self._search = MultiStart(model, config) if lagged else None
        self._background = Background(model, config, every=bank) \
            if self.mode == "process" else None
        self.check = self._search.check if lagged else SafetyCheck(model, config,
                                                                    config.compile_code)
        self.searches = self.adoptions = 0
        self._forget()

    @property
    def solver_ms(self) -> float:
        return self.inner.solver_ms

    @property
    def search_failures(self) -> int:
        """Searches in the other process that raised, or a worker that died (the loop went
        on without them), a search done by now included (one still running is not); 0 on
        the nominal clock, where a failure raises."""
        if self._background is None:
            return 0
        self._background.busy()  # counts a search that has failed since the last re-plan
        return self._background.failures

    def prepare(self, goal) -> None:
        self.inner.prepare(goal)
        if self._search is not None:
            self._search.prepare(goal)

    def offers(self, t: float) -> bool:
        """Whether a search's plan is offered at sample time t (Algorithm 2 re-plans); none
        is within the settle horizon (PlannerConfig.settle_horizon) of the motion's end."""
        if t > self._settle - SAMPLE_TOLERANCE:  # no re-plan for an offer there
            return False
        if self._background is not None:
            return self._background.done()
        return bool(self._offers) and t >= self._offers[0][0] - SAMPLE_TOLERANCE

    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        self._forget()  # a new motion
        if self._background is None:
            return self.inner.plan_cold(problem, starts)
        self._background.prepare(problem.goal)  # the other process readies its search
        found = self.inner.plan_cold(problem, starts)
        self._background.wait()  # the motion starts with both ready (not plan time)
        return found

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        if warm is None:
            self._forget()
            return self.inner.plan(problem)
        self._settle = problem.t_begin + problem.duration - self.config.settle_horizon
        result = self._replan(problem, warm, self._offered(problem.t_begin))
        # searched from the plan the arm will be on when the offer enters: the re-plan's if
        # it succeeded, else the one it started from; the search starts once it is done
        self._launch(problem, result if result.success else warm, result.clock_ms)
        return result

    def _replan(self, problem: Segment, warm: SegmentPlan, offered: SegmentPlan | None
                ) -> SegmentPlan:
        """The re-plan: from the offered plan if it scores better than warm (the plan
        followed) on the current forecast, else from warm (the module's docstring)."""
        if offered is None:  # nothing offered: no plan scored (a check, ~1 ms on a UR5)
            return self.inner.plan(problem, warm)
        ours, other = (self._score(plan, problem) for plan in (warm, offered))
        if other >= ours:  # nothing promising
            return self.inner.plan(problem, warm)
        # the re-plan goes on from the offered plan instead, with the whole budget; kept if
        # it wins on the current forecast, else the arm keeps its plan (re-planned from at
        # the next sample if it must be)
        theirs = self.inner.plan(problem, offered)
        if not theirs.success or self._score(theirs, problem) >= ours:
            return dataclasses.replace(warm, trajectory=_rest(warm, problem),
                                       iterations=theirs.iterations,
                                       solve_ms=theirs.solve_ms,
                                       solve_cpu_ms=theirs.solve_cpu_ms,
                                       clock_ms=theirs.clock_ms)
        self.adoptions += 1
        return dataclasses.replace(theirs, status=theirs.status + ADOPTED)

    def _score(self, plan: SegmentPlan | None, problem: Segment) -> tuple[int, float]:
        """multistart.objective of the plan's motion from the re-plan's time on (inf for
        none)."""
        if plan is None:
            return (3, math.inf)
        motion = dataclasses.replace(plan, trajectory=_rest(plan, problem))
        return objective(self.check, self.config, motion, problem.t_begin, problem.duration,
                         problem.forecast)

    def _forget(self) -> None:
        # the running search's plans still to be offered: (sample time, plan), each better
        # than the ones before it, in the order the other core finds them
        self._offers: list[tuple[float, SegmentPlan]] = []
        self._harvest: list[tuple[float, SegmentPlan]] = []  # a bank's: every plan found
        self._searched = None  # the forecast of the last search
        self._settle = math.inf  # offers enter before this time (the motion's settle horizon)
        if self._background is not None:
            self._background.forget()

    def collect(self, t: float) -> list[SegmentPlan]:
        """Every plan found that entered by sample time t, taken once (a bank's; under CPU
        clocks, those the other process has sent)."""
        if t > self._settle - SAMPLE_TOLERANCE:
            return []
        if self._background is not None:
            return self._background.ready_all()
        ready = [entry for entry in self._harvest if entry[0] <= t + SAMPLE_TOLERANCE]
        self._harvest = self._harvest[len(ready):]
        return [plan for _, plan in ready]

    def _offered(self, t: float) -> SegmentPlan | None:
        """The plan offered at t, taken (None if none)."""
        if self._background is not None:
            return self._background.ready()
        if not self.offers(t):
            return None
        ready = [offer for offer in self._offers if offer[0] <= t + SAMPLE_TOLERANCE]
        self._offers = self._offers[len(ready):]
        return ready[-1][1]  # the best found so far

    def _launch(self, problem: Segment, warm: SegmentPlan, after_ms: float = 0.0) -> None:
        """Search this re-plan's forecast unless a search runs, the obstacle no longer comes
        near the plan followed (within NEAR above the threshold) or the last search saw the
        same prediction. after_ms: the re-plan's work on the budgets' clock, which the search
        waits for."""
        forecast = problem.forecast
        if self.mode == "one core" or forecast is None or len(forecast.times) < 2 or \
                self._offers or self._harvest or (self._background is not None and (
                    self._background.busy() or self._background.done())):
            return
        if self._searched is not None and same_prediction(self._searched, forecast):
            return
        # by the compiled check: numpy's predicted_clearance took ~1.5 ms on a UR5 here
        clearance = self.check.clearance(warm.trajectory, forecast.times, forecast.centres)
        if clearance > self.config.threshold + NEAR and not warm.detour:
            return
        self._searched = forecast
        self.searches += 1
        if self._background is not None:
            if not self._background.submit(_segment(problem, warm, problem.t_begin), warm):
                self.searches -= 1  # the worker failed: the loop goes on alone
            return
        # planned from where the plan followed will be `lag` samples on: the plan re-solved
        # then starts near its own start; a bank's from where the arm is now (it re-plans
        # every plan it takes from the arm's state), entering when its work is done
        period = float(forecast.times[1] - forecast.times[0])
        end = min(problem.t_begin + problem.duration - period, self._settle)
        lag = 1 if self.bank else self.config.global_search.lag
        due = problem.t_begin + (0 if self.bank else lag) * period
        if due >= end:
            return
        # each plan better than those before enters when the search's work up to it on the
        # budgets' clock is done, if that is later (docs/realtime.md, 'Offers when the
        # search is done', 'Offers as the search goes')
        offers, work, harvest = [], [after_ms], []

        def found(plan: SegmentPlan, better: bool) -> None:
            work[0] += plan.clock_ms
            samples = max(lag, math.ceil(work[0] / (1e3 * period) - 1e-9))
            enters = problem.t_begin + samples * period
            if self.bank and enters < end:  # a bank takes every plan found
                harvest.append((enters, plan))
            if not better or enters >= end:
                return
            if offers and offers[-1][0] >= enters - SAMPLE_TOLERANCE:
                offers.pop()  # a better plan is done by the same sample
            offers.append((enters, plan))

        # a bank holds the plan followed already: its shape is no start of the search
        self._search.search(_segment(problem, warm, due), None if self.bank else warm,
                            found=found, **(bank_search(self.config) if self.bank else {}))
        self._offers, self._harvest = offers, harvest


def _rest(plan: SegmentPlan, problem: Segment):
    """The plan's motion on the re-plan's horizon."""
    return plan.trajectory.restrict(problem.t_begin, problem.duration)


def _segment(problem: Segment, warm: SegmentPlan, t: float) -> Segment:
    """The search's segment from t (>= problem.t_begin) on: from the state the plan followed,
    warm, reaches then, with the re-plan's forecast."""
    q, qd, _ = warm.trajectory.state(t)
    return Segment(q[0], qd[0], t, problem.t_begin + problem.duration - t, problem.goal,
                   problem.forecast)


def report(config: PlannerConfig, segments, failures: int = 0) -> dict | None:
    """PLAN.json's account of the global search (None without one): how it ran, how many
    of the segments followed were adopted from it and how many searches failed (another
    process's: the loop went on without them)."""
    options = config.global_search
    if not options.enabled or config.replanner != "anytime":
        return None
    if config.bank.size > 1 and (config.anytime.iteration_ms is not None or
                                 not options.background):
        mode = ("nominal: each search on a re-plan's forecast from the arm's state, every "
                "plan handed to the bank when the search's work up to it on the budgets' "
                "clock is done")
    elif config.anytime.iteration_ms is not None or not options.background:
        mode = (f"nominal: each search on a re-plan's forecast, each better plan offered when "
                f"the search's work up to it on the budgets' clock is done, at least "
                f"{options.lag} obstacle samples later")
    elif cores() > 1:
        mode = "another process, each better plan adopted when it arrives"
    else:
        mode = "one core: the real-time loop ran alone, no global search"
    return {"mode": mode, "adoptions": sum(s.status.endswith(ADOPTED) for s in segments),
            "solver": options.solver, "lag_samples": options.lag, "failures": failures}
