"""The bank's members (one lineage of plans each, held in its homotopy class), its record
(PLAN.json's `bank`) and how it compares plans (planning.bank.planner)."""

from __future__ import annotations

from dataclasses import dataclass, field

from planning.bank.classes import label
from planning.types import SegmentPlan


@dataclass(eq=False)
class Member:
    """One class's plan: its class, its last plan and how many forecasts in a row it missed
    the threshold on."""

    found: tuple
    plan: SegmentPlan
    blocked: int = 0
    replanned: float = -1.0  # the last sample time it was re-planned at (s)
    # the last plan of it that kept the threshold (what it promises while a re-plan from
    # the arm's state, gone on from, has not yet reached it)
    promise: SegmentPlan | None = None

    def __post_init__(self):
        self.promise = self.plan if self.promise is None else self.promise


@dataclass
class BankRecord:
    """PLAN.json's `bank`: each re-plan's classes, their energies to go and the one followed,
    and the switches."""

    replans: list = field(default_factory=list)
    switches: list = field(default_factory=list)
    admitted: int = 0
    dropped: int = 0
    found: int = 0  # plans the global search handed to the bank
    kept: int = 0  # re-plans of other classes only, the arm going on as it was
    checks: int = 0  # plans checked (planning.bank.scoring), what the bank's bookkeeping did

    def to_json(self, size: int, mode: str) -> dict:
        return {"size": size, "mode": mode, "admitted": self.admitted,
                "dropped": self.dropped, "search_plans": self.found, "kept": self.kept,
                "checks": self.checks,
                "switches": self.switches, "replans": self.replans}

    def replan(self, t: float, candidates: list, held: int, followed: tuple) -> None:
        """One re-plan's entry: the classes re-planned from the arm's state, each (class,
        objective), how many the bank held and the one followed."""
        self.replans.append({"t": round(t, 9), "held": held, "followed": label(followed),
                             "classes": [{"class": label(found),
                                          "energy_to_go": round(score[1], 6),
                                          "safe": score[0] == 0}
                                         for found, score in candidates]})


def cheaper(score: tuple, current: tuple, hysteresis: float) -> bool:
    """Whether a plan of this objective (planning.globalsearch.multistart.objective: missing
    the threshold or not, then energy plus weighted violation) beats the plan followed's
    (current): it keeps the threshold where that one misses it, or, both alike, spends less
    by the hysteresis (a fraction)."""
    if score[0] != current[0]:
        return score[0] < current[0]
    return score[1] < current[1] * (1 - hysteresis)


def choose(scored: list, hysteresis: float) -> tuple:
    """Of (objective, member, plan) candidates, the first the plan followed: the cheapest's
    (member, plan), unless the one followed is within the hysteresis of it (a plan of the
    followed member wins outright)."""
    first, best = scored[0], min(scored, key=lambda s: s[0])
    if best[1] is first[1] or cheaper(best[0], first[0], hysteresis):
        return best[1], best[2]
    return first[1], first[2]
