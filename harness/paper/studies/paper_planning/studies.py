"""The paper_planning study's comparisons: minimum jerk, parametrizations against dense quadrature,
the swaying obstacle, and the solver timings (cold plans, warm re-plans, per scenario)."""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.paper.planning.baselines import MinimumJerk, solve_trust_constr
from harness.paper.planning.scenario import paper_scenario
from harness.paper.planning.variants import PARAMETRIZATIONS, Parametrization
from harness.plan.speed import measure
from planning.config import PlannerConfig
from planning.formulation.energy import absolute_energy, net_work
from planning.formulation.screening import screen
from planning.penalty.solver import Planner
from planning.planners import segment_planner
from planning.replanning import execute
from planning.result import PlanResult, evaluate, sample_execution
from planning.scenarios import swaying_scenario
from planning.types import ObstacleForecast, Segment


def plan_scenario(model, scenario, config: PlannerConfig, avoid=True) -> PlanResult:
    planner = segment_planner(model, config)
    return evaluate(execute(planner, scenario, avoid=avoid), scenario, model, planner.config)


def minimum_jerk_study(baseline, scenario, config: PlannerConfig) -> dict:
    """Energy (Pinocchio, 2 ms grid) of the minimum-jerk motion and of the unobstructed
    energy optimum, rest to rest and with free end velocity, for N = 10 and N = 40."""
    grid = np.linspace(0.0, scenario.duration, 1001)
    jerk = MinimumJerk(np.asarray(scenario.start), np.asarray(scenario.goal), scenario.duration)
    e_jerk = absolute_energy(baseline, grid, *jerk.state(grid))
    out = {"energy_minimum_jerk_J": e_jerk}
    for n in (config.energy_samples, 40):
        for rest in (True, False):
            variant = dataclasses.replace(config, energy_samples=n, rest_at_goal=rest)
            result = plan_scenario(baseline, scenario, variant, avoid=False)
            energy = absolute_energy(baseline, result.t, result.q, result.qd, result.qdd)
            key = f"N{n}_{'rest_to_rest' if rest else 'free_end_velocity'}"
            out[f"energy_optimal_{key}_J"] = energy
            out[f"saving_{key}_pct"] = 100 * (e_jerk - energy) / e_jerk
    return out


def _true_energy(baseline, result: PlanResult) -> float:
    """integral |P| dt (J) of an executed plan under Pinocchio on a 0.5 ms grid."""
    t = np.linspace(0.0, result.t[-1], 4001)
    return absolute_energy(baseline, t, *sample_execution(result.execution, t))


def _parametrization(baseline, scenario, variant: Parametrization, stride: int) -> dict:
    """True energy of the unobstructed optimum and of the executed paper-scenario plan,
    the planned (objective) energy, and cold / re-plan timings for one parametrization."""
    config = variant.config()
    planner = segment_planner(baseline, config)
    free = evaluate(execute(planner, scenario, avoid=False), scenario, baseline, config)
    paper = evaluate(execute(planner, scenario), scenario, baseline, config)
    timings, _ = measure(planner, scenario, cold_repeats=2, stride=stride)
    summary = timings.summary()
    return {
        "degree": variant.degree, "quadrature": variant.quadrature,
        "energy_samples": variant.samples, "power_smoothing_W": variant.smoothing,
        "free_true_energy_J": _true_energy(baseline, free),
        "free_planned_energy_J": free.execution.segments[0].energy,
        "paper_true_energy_J": _true_energy(baseline, paper),
        "paper_min_clearance_m": float(paper.sample_clearance.min()),
        "paper_replans": len(paper.execution.segments) - 1,
        "paper_feasible": paper.feasible, "paper_problems": list(paper.problems),
        "cold_median_ms": summary["cold_median_ms"],
        "replan_median_ms": summary["replan_median_ms"],
        "replan_p95_ms": summary["replan_p95_ms"],
        "replans_timed": summary["replans_timed"], "replan_failures": summary["replan_failures"],
    }


def parametrization_study(baseline, scenario, quick: bool) -> dict:
    """The paper's parametrization against dense quadrature and higher degrees, next to the
    minimum-jerk motion and the net-work bound |integral P dt| (J) no motion can beat."""
    grid = np.linspace(0.0, scenario.duration, 4001)
    jerk = MinimumJerk(np.asarray(scenario.start), np.asarray(scenario.goal), scenario.duration)
    states = jerk.state(grid)
    out = {"minimum_jerk_true_energy_J": absolute_energy(baseline, grid, *states),
           "net_work_bound_J": abs(net_work(baseline, grid, *states)),
           "variants": {}}
    for variant in PARAMETRIZATIONS:
        out["variants"][variant.name] = _parametrization(baseline, scenario, variant,
                                                         stride=16 if quick else 8)
    return out


def swaying_study(baseline, free_trajectory, quick: bool,
                  config: PlannerConfig) -> tuple[dict, PlanResult, object]:
    """The crossing obstacle swaying sideways: the constant-velocity prediction from the last
    two samples is never exact, so Algorithm 2 re-plans wherever the forecast threatens."""
    planner = segment_planner(baseline, config)
    scenario = swaying_scenario(free_trajectory, planner.config.geometry, paper_scenario())
    result = evaluate(execute(planner, scenario), scenario, baseline, planner.config)
    replan_ms = np.asarray(result.execution.solve_ms[1:])
    obstacle = scenario.obstacle
    return {
        "sway_m": list(obstacle.sway), "sway_periods": obstacle.periods,
        "replans": len(result.execution.segments) - 1,
        "replan_failures": list(result.execution.replan_failures),
        "solves_after_first": len(replan_ms),
        "replan_median_ms": float(np.median(replan_ms)) if len(replan_ms) else None,
        "replan_p95_ms": float(np.percentile(replan_ms, 95)) if len(replan_ms) else None,
        "replan_max_ms": float(np.max(replan_ms)) if len(replan_ms) else None,
        "first_plan_ms": result.execution.solve_ms[0],
        "min_clearance_m": float(result.sample_clearance.min()),
        "sample_clearance_m": result.sample_clearance.tolist(),
        "energy_pinocchio_J": _true_energy(baseline, result),
        "feasible": result.feasible, "problems": list(result.problems),
    }, result, scenario


def scenario_replans(solve_ms) -> dict:
    """Timings (ms, wall, end to end) of a scenario's actual plans: the first plan, the first
    re-plan (the forecast switches from 'standing still' to 'moving' there, so it is the
    largest change) and all re-plans, each incl. re-screening and penalty escalation."""
    ms = np.asarray(solve_ms, float)
    replans = ms[1:]
    return {"first_plan_ms": float(ms[0]), "replans_timed": len(replans),
            "first_replan_ms": float(replans[0]) if len(replans) else None,
            "replan_median_ms": float(np.median(replans)) if len(replans) else None,
            "replan_p95_ms": float(np.percentile(replans, 95)) if len(replans) else None,
            "replan_max_ms": float(np.max(replans)) if len(replans) else None}


def speed_study(baseline, scenario, quick: bool, config: PlannerConfig) -> dict:
    """Cold and warm timings, and scipy trust-constr on the same cold problem."""
    planner = Planner(baseline, config)
    # one obstacle sample apart, over the whole motion, also in quick mode (about 2 s)
    timings, _ = measure(segment_planner(baseline, planner.config, planner), scenario,
                         cold_repeats=3 if quick else 5)
    out = timings.summary()
    obstacle = scenario.obstacle
    forecast = ObstacleForecast(obstacle.sample_times, obstacle.position(obstacle.sample_times))
    segment = Segment.of(scenario)
    free = planner.solve(segment)
    subset = screen(forecast, free.trajectory, planner.config.geometry,
                    planner.config.threshold, planner.config.obstacle_slots).subset
    args = (scenario.start, scenario.start_velocity, scenario.duration, scenario.goal)
    ipopt = planner.solve(dataclasses.replace(segment, forecast=subset), reference=free.trajectory)
    p = planner.parameters(*args, subset, 0.0, free.trajectory)
    scipy = solve_trust_constr(planner, planner.initial_guess(*args), p,
                               max_iterations=20 if quick else 150)
    out["same_problem"] = {
        "ipopt_ms": ipopt.solve_ms, "ipopt_iterations": ipopt.iterations,
        "ipopt_objective_J": ipopt.energy + ipopt.penalty, "ipopt_success": ipopt.success,
        "scipy_trust_constr_ms": scipy.solve_ms, "scipy_iterations": scipy.iterations,
        "scipy_objective_J": scipy.objective, "scipy_success": scipy.success,
        "scipy_message": scipy.message, "scipy_max_iterations": 20 if quick else 150,
    }
    return out
