"""Re-plan latency: cold plans and warm re-plans one obstacle sample apart.

Times are end to end (screening, parameter packing, every solver call and the
bookkeeping around it), wall clock and CPU time of the planning thread, in ms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planning.config import Scenario
from planning.replanning import forecast_at
from planning.types import Segment, SegmentPlan, SegmentPlanner


@dataclass(frozen=True)
class Timings:
    """Wall and CPU times (ms) of every cold plan and every re-plan of the sweep."""

    cold_ms: tuple[float, ...]
    replan_ms: tuple[float, ...]
    replan_failures: int
    cold_cpu_ms: tuple[float, ...]
    replan_cpu_ms: tuple[float, ...]
    replan_solver_ms: tuple[float, ...]  # the solver calls alone (wall)

    def summary(self) -> dict:
        replan = np.asarray(self.replan_ms)
        return {"cold_median_ms": float(np.median(self.cold_ms)),
                "cold_max_ms": float(np.max(self.cold_ms)),
                "replan_median_ms": float(np.median(replan)),
                "replan_p95_ms": float(np.percentile(replan, 95)),
                "replan_max_ms": float(np.max(replan)), "replans_timed": len(replan),
                "replan_failures": self.replan_failures,
                "cold_cpu_median_ms": float(np.median(self.cold_cpu_ms)),
                "replan_cpu_median_ms": float(np.median(self.replan_cpu_ms)),
                "replan_cpu_p95_ms": float(np.percentile(self.replan_cpu_ms, 95)),
                "replan_solver_median_ms": float(np.median(self.replan_solver_ms))}


def measure(planner: SegmentPlanner, scenario: Scenario, cold_repeats: int = 5,
            stride: int = 1) -> tuple[Timings, SegmentPlan]:
    """Cold plans of the whole motion, then a re-plan at every `stride`-th obstacle sample,
    each warm-started from the previous plan with the obstacle one sample further."""
    obstacle, goal, T = scenario.obstacle, scenario.goal, scenario.duration
    cold, cold_cpu, plan = [], [], None
    for _ in range(cold_repeats):
        plan = planner.plan(Segment(scenario.start, scenario.start_velocity, 0.0, T, goal,
                                    forecast_at(obstacle, obstacle.sample_times[0])))
        cold.append(plan.solve_ms)
        cold_cpu.append(plan.solve_cpu_ms)
    walls, cpus, solver, failures = [], [], [], 0
    for t in obstacle.sample_times[:-1:stride]:
        q, qd, _ = plan.trajectory.state(t)
        before = planner.solver_ms
        new = planner.plan(Segment(q[0], qd[0], t, T - t, goal, forecast_at(obstacle, t)),
                           warm=plan)
        walls.append(new.solve_ms)
        cpus.append(new.solve_cpu_ms)
        solver.append(planner.solver_ms - before)
        if new.success:
            plan = new
        else:
            failures += 1
    return Timings(tuple(cold), tuple(walls), failures, tuple(cold_cpu), tuple(cpus),
                   tuple(solver)), plan
