"""Real time and the true optimum over random scenarios (start, goal, obstacle path and sway
drawn from a seed; the obstacle crosses the unobstructed optimum, so avoidance is active).

- timing: Algorithm 2 on every scenario; the first (cold, multi-start) plan and every warm
  re-plan timed in wall and CPU time of the planning thread, as distributions; re-plans
  dropped at the deadline (the arm keeps its last plan) and failed ones counted.
- backends: the same scenarios each way (the re-planner, solver, compiled code, warm start,
  Hessian, penalty samples, real-time iterations), side by side, with what each way's
  executed motions spend, replayed, and how safe they are (clearance, limits, torques).
- references: the anytime SQP against causal optimality references (.references).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from harness.errors import UserError
from harness.plan.arm_config import planner_config
from harness.plan.causal import causal_multistart
from harness.replay.reference import plan_reference
from harness.replay.simulate import replay
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from harness.studies.realtime import references
from planning.config import PlannerConfig, Scenario
from planning.penalty.solver import Planner
from planning.planners import segment_planner
from planning.replanning import Execution, execute
from planning.result import evaluate, to_json
from planning.scenarios import random_scenarios
from planning.types import DEADLINE, Segment

DEVELOPMENT_SEED = 2026


@dataclass(frozen=True)
class Setup:
    """What the study runs: scenario count and seed, the references' starts, the deadline."""

    scenarios: int = 20
    # drawn once on 2026-11-28 (numpy.random.default_rng().integers(10_000)): scenarios no
    # setting was chosen on. The planner's settings (the search's screens, warm_radius,
    # settle_horizon, offers as found) were chosen on DEVELOPMENT_SEED's, which `--seed 2026`
    # still gives for development, never for the targets' record
    seed: int = 8744
    # random starts of each reference's multi-start (docs/realtime.md, 'planning.globalsearch')
    reference_starts: int = 2
    replan_stride: int = 4  # (i) on every this many re-plans
    deadline_ms: float = 10.0


def distribution(values) -> dict:
    """median, p95, max and count of a sample (ms); None entries for an empty one."""
    v = np.asarray(values, float)
    if not len(v):
        return {"median": None, "p95": None, "max": None, "count": 0}
    return {"median": float(np.median(v)), "p95": float(np.percentile(v, 95)),
            "max": float(np.max(v)), "count": len(v)}


def study_config(compile_code: bool, **changes) -> PlannerConfig:
    """The default planner on the Lynxmotion, its global search's plans entering a fixed
    number of samples later (the study's executions run faster than real time)."""
    return planner_config(Arm.of(DEFAULT_ROBOT), compile_code=compile_code,
                          **changes).with_global_search(background=False)


def scenarios(baseline, config: PlannerConfig, setup: Setup) -> list[Scenario]:
    """The random scenarios, their obstacles placed on the unobstructed optimum."""
    planner = Planner(baseline, dataclasses.replace(config, compile_code=False))

    def free_motion(start, goal, duration):
        return planner.solve(Segment.from_rest(start, duration, goal)).trajectory

    return random_scenarios(setup.scenarios, setup.seed, free_motion, config.geometry,
                            config.lower, config.upper, config.threshold)


def timing(baseline, config: PlannerConfig, cases: list[Scenario]) -> tuple[dict, list]:
    """Algorithm 2 on every case: distributions of cold and warm times (wall and CPU, ms),
    deadline misses and failures; and the executions."""
    planner = segment_planner(baseline, config)
    runs = [execute(planner, case) for case in cases]
    cold_wall = [r.solve_ms[0] for r in runs]
    cold_cpu = [r.solve_cpu_ms[0] for r in runs]
    warm_wall = [ms for r in runs for ms in r.solve_ms[1:]]
    warm_cpu = [ms for r in runs for ms in r.solve_cpu_ms[1:]]
    misses = sum(s.startswith(DEADLINE) for r in runs for s in r.replan_failures)
    failures = sum(not s.startswith(DEADLINE) for r in runs for s in r.replan_failures)
    return {"cold_wall_ms": distribution(cold_wall), "cold_cpu_ms": distribution(cold_cpu),
            "replan_wall_ms": distribution(warm_wall), "replan_cpu_ms": distribution(warm_cpu),
            "replans_attempted": len(warm_wall), "deadline_misses": int(misses),
            "replan_failures": int(failures),
            "first_plan_failures": sum(len(r.failures) for r in runs)}, runs


def replayed_energy(plant, baseline, execution: Execution, case: Scenario,
                    config: PlannerConfig, safety: dict | None = None) -> tuple[float, bool]:
    """Energy (J) MuJoCo measures executing the plan, and whether the plan is feasible;
    safety (a dict): gets the executed motion's smallest clearance (m), limit excursion (rad)
    and largest |tau| / torque limit."""
    result = evaluate(execution, case, baseline, config)
    if safety is not None:
        limit = np.inf if config.torque_limit is None else np.asarray(config.torque_limit)
        safety.update(clearance=float(result.sample_clearance.min()),
                      limits=result.limit_violation,
                      torque=float(np.max(result.peak_torque / limit)))
    try:
        measured, _ = replay(plant, plan_reference(to_json(result, case, config, "pinocchio")),
                             baseline)
    except UserError:  # the replay refuses a plan beyond the joint limits: infeasible
        return np.nan, False
    return measured.energy, result.feasible


def spent(plant, baseline, config: PlannerConfig, cases: list[Scenario], runs: list) -> dict:
    """What each executed motion spends, replayed in MuJoCo (J; None where it is infeasible),
    how many were infeasible (the way a re-plan goes changes the path the arm takes), and
    its safety: the smallest executed clearance (m), the worst limit excursion (rad) and the
    largest |tau| / torque limit over the scenarios."""
    safety = [{} for _ in cases]
    replayed = [replayed_energy(plant, baseline, run, case, config, s)
                for case, run, s in zip(cases, runs, safety, strict=True)]
    return {"executed_J": [float(e) if ok else None for e, ok in replayed],
            "executed_infeasible": sum(not ok for _, ok in replayed),
            "executed_min_clearance_m": min(s["clearance"] for s in safety),
            "executed_limit_excursion_rad": max(s["limits"] for s in safety),
            "executed_torque_ratio": max(s["torque"] for s in safety)}


def common_sums(rows: dict) -> tuple[dict, int]:
    """Each way's executed energy summed over the scenarios every way executed feasibly (a
    way with more infeasible executions would otherwise sum fewer terms), and their count."""
    energies = [row["executed_J"] for row in rows.values()]
    common = [i for i in range(len(energies[0])) if all(e[i] is not None for e in energies)]
    return {name: float(sum(row["executed_J"][i] for i in common))
            for name, row in rows.items()}, len(common)


def ways_in(config: PlannerConfig, quick: bool) -> dict[str, PlannerConfig]:
    """The configurations compared side by side: the previous default (IPOPT in CasADi's
    virtual machine), each change alone, and the default."""
    vm = dataclasses.replace(config, compile_code=False)
    previous = dataclasses.replace(vm.with_penalty(solver="ipopt"), energy_quadrature="paper",
                                   energy_samples=10, starts=1)
    rows = {"ipopt, virtual machine, paper quadrature, 1 start (previous default)": previous}
    if quick:
        return {**rows, "default: " + describe(config): config}
    rows |= {"ipopt, virtual machine, primal-only warm start":
                vm.with_penalty(solver="ipopt", dual_warm_start=False),
            "ipopt, virtual machine, limited-memory Hessian":
                vm.with_penalty(solver="ipopt", hessian="limited-memory"),
            "fatrop, virtual machine": vm.with_penalty(solver="fatrop"),
            "ipopt, compiled": config.with_penalty(solver="ipopt"),
            "sqpmethod (qpOASES), compiled": config.with_penalty(solver="sqpmethod"),
            "fatrop, compiled, 8 penalty samples": dataclasses.replace(config, obstacle_slots=8),
            "fatrop, compiled, 1 start": dataclasses.replace(config, starts=1),
            "fatrop, compiled, real-time iterations (1 feasible-SQP iteration a re-plan)":
                config.with_penalty(replan_iterations=1)}
    return rows | fast_ways(config)


def fast_ways(config: PlannerConfig) -> dict[str, PlannerConfig]:
    """The two re-planners side by side: the penalty loop (fatrop) and the anytime SQP, with
    and without its global search."""
    rows = {}
    anytime = dataclasses.replace(config, replanner="anytime")
    for variant in (dataclasses.replace(config, replanner="penalty"),
                    anytime.with_global_search(enabled=not anytime.global_search.enabled),
                    anytime):
        label = "default: " if variant == config else ""
        rows[label + describe(variant)] = variant
    return rows


def describe(config: PlannerConfig) -> str:
    """One line naming what a configuration solves with."""
    code = "compiled" if config.compile_code else "virtual machine"
    if config.replanner == "anytime":
        search = config.global_search
        return (f"anytime elastic SQP (DAQP), {code}, {config.energy_quadrature} N = "
                f"{config.energy_samples}, {config.starts} start(s) in "
                f"{config.anytime.cold_budget_ms:g} ms, re-plans in {config.anytime.replan_budget_ms:g} ms"
                + (f", global search offered {search.lag} samples later" if search.enabled
                   else ", no global search"))
    return (f"{config.penalty.solver}, {code}, {config.energy_quadrature} N = {config.energy_samples}, "
            f"{config.starts} start(s), {config.obstacle_slots} penalty samples")


def run(baseline, plant, quick: bool, setup: Setup | None = None,
        ways: dict[str, PlannerConfig] | None = None, **changes) -> dict:
    """The whole study; quick: 2 scenarios, references without random starts on every 8th
    re-plan, the previous default and the default only, nothing compiled; changes: to the
    planner configuration (e.g. the paper's free end, rest_at_goal=False)."""
    setup = setup or (Setup(scenarios=2, reference_starts=0, replan_stride=8) if quick else Setup())
    config = study_config(not quick, **changes)
    cases = scenarios(baseline, config, setup)
    ways = ways_in(config, quick) if ways is None else ways
    rows, executed = {}, {}
    for name, variant in ways.items():
        rows[name], executed[name] = timing(baseline, variant, cases)
        rows[name] |= spent(plant, baseline, variant, cases, executed[name])
    live = dataclasses.replace(config, replan_deadline_ms=setup.deadline_ms)
    default, _ = timing(baseline, live, cases)
    anytime = dataclasses.replace(config, replanner="anytime")
    name = next((n for n, v in ways.items() if v == anytime), None)
    if name is None:
        name = describe(anytime)
        rows[name], executed[name] = timing(baseline, anytime, cases)
        rows[name] |= spent(plant, baseline, anytime, cases, executed[name])
    return {"setup": dataclasses.asdict(setup), "config": describe(config),
            "ways_in": rows, "default": default, "anytime_way": name,
            "references": _references(baseline, plant, anytime, cases, rows[name], setup, rows),
            "scenarios": [_scenario_json(case) for case in cases]}


def _references(baseline, plant, config, cases, row: dict, setup: Setup, rows: dict) -> dict:
    """The anytime SQP against the fair references (harness.studies.realtime.references)."""
    starts = setup.reference_starts
    causal = spent(plant, baseline, config, cases,
                   causal_multistart(baseline, config, cases, starts))
    oneshot = spent(plant, baseline, config, cases,
                    references.one_shot(baseline, config, cases, starts))
    return {"starts": starts, "stride": setup.replan_stride,
            "per_replan": references.per_replan(baseline, config, cases, starts,
                                                setup.replan_stride),
            "causal": references.compare(row["executed_J"], causal["executed_J"]),
            # every way (the anytime SQP without its global search too) against it
            "causal_other_way": {name: references.compare(other["executed_J"],
                                 causal["executed_J"]) for name, other in rows.items()},
            "causal_executed_J": causal["executed_J"],
            "value_of_information": references.compare(row["executed_J"],
                                                       oneshot["executed_J"]),
            "one_shot_executed_J": oneshot["executed_J"]}


def _scenario_json(case: Scenario) -> dict:
    obstacle = case.obstacle
    return {"start": case.start, "goal": case.goal, "obstacle_from": obstacle.start,
            "obstacle_to": obstacle.end, "sway_m": obstacle.sway, "sway_periods": obstacle.periods}
