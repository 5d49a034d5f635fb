"""What an anytime plan may spend and what its parts recently cost: the clock its budget
counts (CPU time of the planning thread, or nominal units for reproducible runs) and the
recent costs of a plan's rounds that keep the budget (planning.anytime; an iteration's own
in planning.anytime.sqp)."""

from __future__ import annotations

import time
from collections import deque

RECENT = 32  # iterations (or rounds) whose CPU cost predicts the next one's


class Clock:
    """What a budget counts: the planning thread's CPU time (ms) since the clock was made, or,
    for reproducible runs (AnytimeOptions.iteration_ms), iteration_ms per unit of work ticked
    whatever CPU it took: an SQP iteration (a QP and an evaluation), a second-order
    correction (another), and ROUND_ITERATIONS for each round of a plan (its screening,
    checks and bookkeeping, about two iterations' CPU: (docs/realtime.md, 'planning.anytime.budget'))."""

    ROUND_ITERATIONS = 2

    def __init__(self, iteration_ms: float | None = None):
        self.nominal, self.ticks, self._began = iteration_ms, 0, time.thread_time()

    def ms(self) -> float:
        if self.nominal is not None:
            return self.ticks * self.nominal
        return 1e3 * (time.thread_time() - self._began)

    def tick(self, units: int = 1) -> None:
        self.ticks += units

    def iteration(self, measured_ms: float) -> float:
        """What the next iteration is expected to cost: measured_ms (a recent one's CPU) or
        the nominal cost."""
        return measured_ms if self.nominal is None else self.nominal


class RoundCosts:
    """The CPU recent rounds of plans spent outside their iterations: after their solve
    (packing the plan, and choosing it: per iterate checked, since a solve's iterates may
    all need their check; both kept from the next solve's budget) and in all (a further
    round or cold start begins only with that and two iterations left). Counted under CPU
    clocks only; a nominal clock charges Clock.ROUND_ITERATIONS a round."""

    def __init__(self):
        self.after: deque[float] = deque(maxlen=RECENT)
        self.check: deque[float] = deque(maxlen=RECENT)  # the choice's CPU per iterate checked
        self.fixed: deque[float] = deque(maxlen=RECENT)
        self.ranking: deque[float] = deque(maxlen=RECENT)  # of a cold plan's starts

    def clear(self) -> None:
        for costs in (self.after, self.check, self.fixed, self.ranking):
            costs.clear()

    def record(self, clock: Clock, after_ms: float, fixed_ms: float, check_ms: float) -> None:
        if clock.nominal is None:
            self.after.append(after_ms)
            self.fixed.append(fixed_ms)
            self.check.append(check_ms)

    def check_ms(self, clock: Clock) -> float:
        """What to keep from a solve's budget for each iterate it accepts: its check in the
        choice after the solve (a solve may accept many iterates:
        (docs/realtime.md, 'planning.anytime.budget'))."""
        return max(self.check, default=0.0) if clock.nominal is None else 0.0

    def record_ranking(self, clock: Clock, ms: float) -> None:
        if clock.nominal is None:
            self.ranking.append(ms)

    def ranking_ms(self, clock: Clock) -> float:
        """What to keep from a cold plan's budget for ranking its starts (ms on the clock)."""
        return max(self.ranking, default=0.0) if clock.nominal is None else 0.0

    def reserve(self, clock: Clock) -> float:
        """What to keep from a solve's budget for the work after it but the choice (ms on
        the clock)."""
        return max(self.after, default=0.0) if clock.nominal is None else 0.0

    def round_ms(self, clock: Clock, iteration_ms: float) -> float:
        """What a round with two iterations of iteration_ms is expected to cost."""
        if clock.nominal is not None:
            return (Clock.ROUND_ITERATIONS + 2) * clock.nominal
        return max(self.fixed, default=0.0) + 2.0 * iteration_ms
