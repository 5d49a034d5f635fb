"""The causal reference of a re-planner's executed energy (the realtime study's (ii) and the
bench's planning section): Algorithm 2 whose every plan and re-plan is a multi-start of
IPOPT run to convergence on the elastic NLP (planning.globalsearch: the obstacle passed each
side, above and below, random start points and the warm plan), another solver than the
anytime SQP."""

from __future__ import annotations

from harness.plan.scoring import summary
from planning.config import PlannerConfig, Scenario
from planning.globalsearch.multistart import MultiStart
from planning.replanning import Execution, execute
from planning.result import evaluate
from planning.types import Segment, SegmentPlan


def multistart(baseline, config: PlannerConfig, starts: int) -> MultiStart:
    """IPOPT from the global search's detours and `starts` random start points."""
    return MultiStart(baseline, config.with_global_search(solver="ipopt", random_starts=starts))


class CausalMultiStart:
    """The causal reference as a SegmentPlanner (planning.types): every plan and re-plan the
    multi-start's best."""

    def __init__(self, search: MultiStart):
        self.search, self.config = search, search.config

    solver_ms = 0.0

    def offers(self, t: float) -> bool:
        return False

    def prepare(self, goal) -> None:
        self.search.prepare(goal)

    def plan(self, problem: Segment, warm: SegmentPlan | None = None) -> SegmentPlan:
        return self.search.search(problem, warm)[0]

    def plan_cold(self, problem: Segment, starts: int | None = None
                  ) -> tuple[SegmentPlan, list[SegmentPlan]]:
        return self.plan(problem), []


def causal_multistart(baseline, config: PlannerConfig, cases: list[Scenario],
                      starts: int) -> list[Execution]:
    """Algorithm 2 on each case, its every plan and re-plan the IPOPT multi-start's."""
    planner = CausalMultiStart(multistart(baseline, config, starts))
    return [execute(planner, case) for case in cases]




def against_causal(baseline, config: PlannerConfig, scenario: Scenario, ours: float,
                   starts: int) -> dict:
    """A re-planner's executed energy `ours` (J, its true energy) against the causal
    reference's on the scenario: both energies and the excess (%)."""
    run = causal_multistart(baseline, config, [scenario], starts)[0]
    reference = summary(evaluate(run, scenario, baseline, config), baseline, config)
    energy = reference["true_energy_J"]
    return {"executed_J": ours, "reference_J": energy,
            "reference_feasible": reference["feasible"],
            "excess_pct": 100 * (ours - energy) / energy if energy > 0 else 0.0}
