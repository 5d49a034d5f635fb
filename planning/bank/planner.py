"""A bank of plans, one per homotopy class of the motion around the obstacle
(planning.bank.classes), as a SegmentPlanner (planning.types): topology-driven re-planning
(de Groot, Ferranti, Gavrila & Alonso-Mora, IEEE T-RO 2024) on Algorithm 2.

- **Members**: lineages of plans, each held in its class and re-planned warm from the arm's
  state. A re-plan that leaves its class joins as a new lineage; the member keeps its plan.
- **Discovery**: the first plan's starts, and every plan the global search finds
  (planning.globalsearch.planner with bank True) once its work up to it is done, unless a
  member of its class already promises as much. Two converged lineages of one class merge.
- **Followed**: the cheapest plan re-planned from the arm's state at this sample (safe
  first, then the energy to go: planning.globalsearch.multistart.objective); a switch of
  class only past BankOptions.hysteresis.
- **Dropped**: a member missing the threshold on BankOptions.patience forecasts in a row,
  and the one promising least when a better plan needs room (BankOptions.size).
- **Budget**: the plan followed gets the re-plan budget unless another member promises
  less (then BankOptions.followed_share; a safe plan re-planned only to improve yields its
  turn); the others share what it leaves. The whole bank's work at a sample counts, its
  checks of its plans with its solves (planning.bank.work; docs/realtime.md).
"""

from __future__ import annotations

import dataclasses
import math

from planning.anytime.solver import CONVERGED
from planning.bank.classes import label, same_class
from planning.bank.members import BankRecord, Member, cheaper, choose
from planning.bank.scoring import Scores
from planning.bank.work import Work, described, recent, timed_search
from planning.globalsearch.planner import ADOPTED
from planning.timing import collection_deferred
from planning.types import ITERATE, KEPT, Segment, SegmentPlan, SegmentPlanner

SWITCHED = " (bank: switched class)"


class BankPlanner:
    """`inner`'s plans (a SegmentPlanner), kept one per homotopy class (the module's
    docstring). anytime: inner's SQP (planning.anytime.solver.Anytime: its safety check
    scores the plans, its round cost says when a re-plan no longer fits the budget); search:
    the global search around inner (bank True), or None."""

    def __init__(self, inner: SegmentPlanner, anytime, search=None):
        self.inner, self.anytime, self.search = inner, anytime, search
        self._timed = timed_search(search)  # the global search's, its time left out
        self.check, self.config, self.options = anytime.check, inner.config, inner.config.bank
        self.front = inner if search is None else search  # plans the plan followed
        self._costs = recent()  # CPU ms of the recent checks of plans (Scores)
        self._forget()

    def _forget(self) -> None:
        self.members: list[Member] = []
        self.followed: Member | None = None
        self.record = BankRecord()
        self._settle = math.inf
        self._current: tuple | None = None  # the objective of the plan followed, this sample
        self._scores: Scores | None = None  # this sample's measures of plans

    @property
    def solver_ms(self) -> float:
        return self.inner.solver_ms
    search_failures = property(lambda self: getattr(self.search, "search_failures", 0))

    def account(self) -> dict:
        """PLAN.json's `bank`: how its work was counted, the classes admitted and dropped,
        the search's plans it took, the switches, and at each re-plan the classes re-planned
        from the arm's state (their energies to go, J, and whether they keep the threshold)
        and the one followed."""
        clock = "nominal" if self.config.anytime.iteration_ms is not None else "cpu"
        mode = (f"{clock}: every class's re-plan at a sample in this thread, sharing the "
                f"re-plan's budget with the bank's checks of its plans, the plan followed "
                f"first; the global search's plans handed over when its work up to them is done"
                + ("" if clock == "nominal" else " (another process where there are cores)"))
        self._checks(None)
        return {**self.record.to_json(self.options.size, mode), "guided": self.options.guided,
                "work": described(clock == "nominal")}

    def prepare(self, goal) -> None:
        self.front.prepare(goal)

    def offers(self, t: float) -> bool:
        """Whether the bank re-plans at t though the plan followed is safe: it holds another
        class before the settle horizon, or the search hands it plans."""
        return t < self._settle - 1e-9 and (len(self.members) > 1 or self.search is not None) \
            or self.front.offers(t)

    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        best, plans = self.front.plan_cold(problem, starts)
        self._forget()
        self._scores = self._checks(Scores(self.check, self.config, problem, self._costs))
        self._settle = problem.t_begin + problem.duration - self.config.settle_horizon
        self.followed = self._seed(best, problem)
        for plan in sorted(plans, key=lambda p: self._score(p, problem)):
            if plan.success:
                self._admit(plan, problem)
        return best, plans

    @collection_deferred
    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        """A re-plan of the bank: the plan followed re-planned if Algorithm 2 must (it dips
        below the threshold, is stale or unconverged), the search's plans admitted, then the
        other classes re-planned from the arm's state with what the budget has left:
        first those whose plan promises to spend less than the plan followed (by the
        hysteresis), cheapest first, then the one re-planned longest ago. warm itself if the
        arm goes on as it was (nothing re-planned that it follows)."""
        if warm is None:
            return self.front.plan(problem)
        self._scores = self._checks(Scores(self.check, self.config, problem, self._costs))
        if self.followed is None:  # a plan not made by plan_cold: a bank of its own
            self._settle = problem.t_begin + problem.duration - self.config.settle_horizon
            self.followed = self._seed(warm, problem)
        work = Work(self.config.anytime.iteration_ms, self._scores, self._timed)
        total, followed = self._budget(problem), self.followed
        t = problem.t_begin
        rest = dataclasses.replace(warm, trajectory=warm.trajectory.restrict(
            t, problem.duration))
        dips = self._scores.dips(rest)
        must = warm.status.startswith(ITERATE) or dips or self.front.offers(t)  # the
        # search offers a better plan of its own
        current = self._current = self._score(rest, problem)
        if t < self._settle - 1e-9:  # the search's plans, each to its class
            for found in ([] if self.search is None else self.search.collect(t)):
                self.record.found += 1
                if found.success:
                    self._admit(found, problem)
        promising = t < self._settle - 1e-9 and self._promising(current, problem)
        if must and promising and current[0] == 0 and not dips:
            must = False  # safe and only to improve: the budget goes to a better class
        if must:  # the plan followed first, with the budget the others may need
            share = total * self.options.followed_share if promising else total
            new = self._replan(problem, warm, min(share, self._left(total, work)), work,
                               self.front)
            if not new.success:
                return work.timed(new)
            followed = self._placed(followed, new, problem)
            current = self._score(new, problem)
        else:
            new = rest
        candidates = [(followed, new)]
        if t < self._settle - 1e-9:
            for member in self._to_replan(followed, current, problem):
                left = self._left(total, work)
                if member not in self.members or left < self.anytime.round_ms():
                    continue
                again = self._replan(problem, member.plan, left, work, guided=self.options.guided
                                     and self._score(member.plan, problem)[0] == 0)  # if safe
                member.replanned = t
                if again.success and self._placed(member, again, problem) is member:
                    candidates.append((member, again))
        for member in self.members:
            if member is not followed and all(m is not member for m, _ in candidates):
                member.blocked += self._score(member.plan, problem)[0] > 0
        chosen, plan = self._choose(candidates, problem)
        self._drop()
        self._merge(problem)
        self._account(problem, candidates, chosen)
        if chosen is not followed and not same_class(chosen.found, followed.found):
            self.record.switches.append({"t": round(t, 9), "from": label(followed.found),
                                         "to": label(chosen.found)})
            plan = dataclasses.replace(plan, status=plan.status + SWITCHED)
        elif chosen is not followed:  # a better plan of the same class: the search's
            plan = dataclasses.replace(plan, status=plan.status + ADOPTED)
        self.followed = chosen
        if plan is rest:  # nothing solved: no re-plan (the bookkeeping's work not reported)
            self.record.kept += bool(work.solved)
            return warm if not work.solved else work.timed(dataclasses.replace(
                warm, status=KEPT))
        return work.timed(plan)

    def _promising(self, current: tuple, problem: Segment) -> bool:
        return any(self._better(member, current, problem) for member in self.members
                   if member is not self.followed)

    def _better(self, member: Member, current: tuple, problem: Segment) -> bool:
        """Whether member's plan (its last that kept the threshold), from now on, keeps the
        threshold and spends less than the plan followed (current: its objective) by the
        hysteresis."""
        return self._cheaper(self._score(member.promise, problem), current)

    def _cheaper(self, score: tuple, current: tuple) -> bool:
        return cheaper(score, current, self.options.hysteresis)

    def _to_replan(self, followed: Member, current: tuple, problem: Segment) -> list[Member]:
        """The other members to re-plan, in order: the promising ones, cheapest first, then
        the one re-planned longest ago."""
        others = [m for m in self.members if m is not followed]
        promising = sorted((m for m in others if self._better(m, current, problem)),
                           key=lambda m: self._score(m.promise, problem))
        rest = sorted((m for m in others if m not in promising), key=lambda m: m.replanned)
        return promising + rest[:1]

    def _replan(self, problem: Segment, warm: SegmentPlan, budget: float, work: Work,
                planner: SegmentPlanner | None = None, guided: bool = False) -> SegmentPlan:
        return work.solve((planner or self.inner).plan, dataclasses.replace(
            problem, budget_ms=max(budget, 0.0), guided=guided), warm)

    def _left(self, total: float, work: Work) -> float:
        """The budget left to a solve: the checks after it (its plan's, the members' not
        checked yet) kept back."""
        after = 1 + self._scores.unchecked([member.plan for member in self.members])
        return total - work.clock_ms() - work.check_ms() * after

    def _budget(self, problem: Segment) -> float:
        budget = self.config.anytime.replan_budget_ms if problem.budget_ms is None \
            else problem.budget_ms
        return budget if problem.deadline_ms is None else min(budget, problem.deadline_ms)

    def _checks(self, scores: Scores | None) -> Scores | None:
        """scores as the sample's, the last sample's checks counted in the record."""
        self.record.checks += 0 if self._scores is None else self._scores.checked
        self._scores = scores
        return scores

    def _class(self, plan: SegmentPlan, problem: Segment) -> tuple:  # each plan once a
        return self._scores.motion_class(plan)  # sample (planning.bank.scoring)

    def _score(self, plan: SegmentPlan, problem: Segment) -> tuple[int, float]:
        return self._scores.objective(plan)

    def _seed(self, plan: SegmentPlan, problem: Segment) -> Member:
        """The plan the arm follows first, the bank's first member whatever it promises."""
        member = Member(self._class(plan, problem), plan)
        self.members = [member]
        return member

    def _admit(self, plan: SegmentPlan, problem: Segment) -> Member | None:
        """The plan as a new member (a lineage) unless a member of its class already
        promises as much, or it misses the threshold; room made by dropping the member
        (not the one followed) that promises least, if the plan promises more. The member,
        or None if it was not kept."""
        found, score = self._class(plan, problem), self._score(plan, problem)
        if score[0] > 0 and not (self._current is not None and score < self._current):
            return None  # a plan that misses the threshold, unless the plan followed does worse
        if any(same_class(m.found, found) and self._score(m.promise, problem) <= score
               for m in self.members):
            return None
        if len(self.members) >= self.options.size:
            worst = max((m for m in self.members if m is not self.followed),
                        key=lambda m: self._score(m.promise, problem), default=None)
            if worst is None or self._score(worst.promise, problem) <= score:
                return None
            self._remove(worst)
        member = Member(found, plan)
        self.members.append(member)
        self.record.admitted += len(self.members) > 1
        return member

    def _merge(self, problem: Segment) -> None:
        """Of two members of one class whose plans both converged, the one promising less
        leaves (not the one followed): the class's lineages met."""
        done = [m for m in self.members if m.promise.status.startswith(CONVERGED)]
        for i, first in enumerate(done):
            for second in done[i + 1:]:
                if first in self.members and second in self.members and \
                        same_class(first.found, second.found):
                    worse = max((first, second), key=lambda m: (
                        m is not self.followed, self._score(m.promise, problem)))
                    if worse is not self.followed:
                        self._remove(worse)

    def _placed(self, member: Member, new: SegmentPlan, problem: Segment) -> Member:
        """Where a successful re-plan of member's plan belongs: member itself if it kept the
        class or misses the threshold (its plan replaced), else the member of its new class
        (admitted), member keeping its old plan."""
        unsafe = self._score(new, problem)[0] > 0
        member.blocked = member.blocked + 1 if unsafe else 0
        member.replanned = problem.t_begin
        found = None if unsafe else self._class(new, problem)
        if unsafe or same_class(found, member.found):
            member.plan = new
            # an unconverged re-plan from the arm's state is gone on from; what the class
            # promises stays the better of it and the last promise until one converges
            if not unsafe and (not new.status.startswith(ITERATE) or self._score(
                    new, problem) < self._score(member.promise, problem)):
                member.promise = new
            return member
        other = self._admit(new, problem)
        return member if other is None else other

    def _remove(self, member: Member) -> None:
        self.members.remove(member)
        self.record.dropped += 1

    def _choose(self, candidates, problem: Segment) -> tuple[Member, SegmentPlan]:
        """The candidate to follow (members.choose)."""
        return choose([(self._score(plan, problem), member, plan)
                       for member, plan in candidates], self.options.hysteresis)

    def _drop(self) -> None:
        for member in list(self.members):
            if member is not self.followed and member.blocked >= self.options.patience:
                self._remove(member)

    def _account(self, problem: Segment, candidates, chosen: Member) -> None:
        self.record.replan(problem.t_begin, [(member.found, self._score(plan, problem))
                                             for member, plan in candidates],
                           len(self.members), chosen.found)
