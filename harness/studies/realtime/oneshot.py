"""The optimizer alone: one plan per random scenario with the obstacle's whole path known.

The realtime study (harness.studies.realtime.ways) scores Algorithm 2, whose executed energy
also depends on what the constant-velocity forecast got wrong. Here nothing is forecast:
each scenario of the study (same seed) is planned once, the obstacle at every sample where
it will be, no re-planning; every plan is replayed in MuJoCo. The default (4 starts, Gauss
N = 20) against the best of a global check: each of 8 start points alone, and the default's
starts at Gauss N = 40; beside it the split quadrature (Gauss between the power's sign
changes, planning.formulation.breaks: 7 breaks, 3 nodes each), 4 starts; and polished: 8 starts on the
default's rule, the best 2 distinct plans solved again with the split rule at 40 nodes
(config.penalty.polish). Printed per scenario, then how many of the default's, the split and the
polished plans are within 0.5 % of the best of all of them.

    python -m harness.studies.realtime.oneshot [--scenarios 20] [--seed 2026]
"""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.plan.arm_config import planner_config
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from harness.studies.realtime import measure as realtime
from harness.studies.realtime import options as random_scenarios
from planning.penalty.solver import Planner
from planning.planners import segment_planner
from planning.replanning import Execution
from planning.starts import start_points
from planning.types import ObstacleForecast, Segment

GLOBAL_STARTS = 8
FINE_SAMPLES = 40


def _execution(plan) -> Execution:
    return Execution((plan,), (0.0,), (plan.solve_ms,), () if plan.success else (plan.status,),
                     (), (plan.solve_cpu_ms,))


def main() -> None:
    args = random_scenarios.parser(__doc__).parse_args()
    baseline = Arm.of(DEFAULT_ROBOT).nominal
    plant = Arm.of(DEFAULT_ROBOT).scene
    config = planner_config(Arm.of(DEFAULT_ROBOT), compile_code=True)
    cases = realtime.scenarios(baseline, config, random_scenarios.setup(args))
    default, numbers = segment_planner(baseline, config), Planner(baseline, config)
    fine = segment_planner(baseline, dataclasses.replace(config, energy_samples=FINE_SAMPLES,
                                                 compile_code=False))
    # the planners scored against the best of all: the default, and those beside it
    scored = {"default": default,
              "split": segment_planner(baseline,
                                       dataclasses.replace(config, **random_scenarios.SPLIT)),
              "polished": segment_planner(baseline,
                                          random_scenarios.polished(config))}

    def replayed(plan, planner):
        return realtime.replayed_energy(plant, baseline, _execution(plan), case, planner.config)

    def mark(ok: bool) -> str:
        return "" if ok else " (infeasible)"

    within = dict.fromkeys(scored, 0)
    for i, case in enumerate(cases):
        t = case.obstacle.sample_times
        segment = (case.start, case.start_velocity, 0.0, case.duration, case.goal,
                   ObstacleForecast(t, case.obstacle.position(t)))
        runs = {}  # name: (replayed energy, feasible, cold CPU ms)
        for name, planner in scored.items():
            plan, _ = planner.plan_cold(Segment(*segment))
            runs[name] = (*replayed(plan, planner), plan.solve_cpu_ms)
        points = start_points(numbers, case.start, case.start_velocity, case.duration,
                              case.goal, GLOBAL_STARTS)
        singles = [replayed(default.plan(Segment(*segment, x0=x if k else None)), default)
                   for k, x in enumerate(points)]
        fine_energy, fine_feasible = replayed(fine.plan_cold(Segment(*segment))[0], fine)
        candidates = [e for e, ok in singles if ok] + ([fine_energy] if fine_feasible else [])
        candidates += [e for e, ok, _ in runs.values() if ok]
        best = min(candidates) if candidates else np.nan
        excess = {name: 100 * (e - best) / best if ok else np.nan
                  for name, (e, ok, _) in runs.items()}
        for name in scored:
            within[name] += bool(excess[name] <= 100 * realtime.OPTIMALITY_TOLERANCE)
        starts = " ".join(f"{e:.4f}{'' if ok else '(x)'}" for e, ok in singles)
        (energy, feasible, cpu), (split_energy, split_ok, split_cpu), \
            (polished_energy, polished_ok, polished_cpu) = runs.values()
        print(f"{i:2d} default {energy:.5f} J{mark(feasible)}, "
              f"cold CPU {cpu:.0f} ms | single starts {starts} | Gauss N = {FINE_SAMPLES} "
              f"{fine_energy:.5f} J | split {split_energy:.5f} J{mark(split_ok)}, cold CPU "
              f"{split_cpu:.0f} ms | polished {polished_energy:.5f} J{mark(polished_ok)}, "
              f"cold CPU {polished_cpu:.0f} ms | vs best: "
              + ", ".join(f"{name} {value:+.2f} %" for name, value in excess.items()),
              flush=True)
    print(f"within {100 * realtime.OPTIMALITY_TOLERANCE:g} % of the best on: "
          + ", ".join(f"{name} {count}" for name, count in within.items())
          + f" of {len(cases)} scenarios ((x): infeasible, its replay comes within the "
          "threshold)")

if __name__ == "__main__":
    main()
