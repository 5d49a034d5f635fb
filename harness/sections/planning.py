"""Bench section: energy-optimal planning with moving-obstacle avoidance (paper III.G).

Plans the paper's scenario with the closed-form (Pinocchio) model and, when one is
given, the identified model; evaluates every executed trajectory's energy with
Pinocchio on a 2 ms grid; adds a scenario whose obstacle crosses the optimal path,
a minimum-jerk comparison, an N = 10 vs N = 40 energy-sample comparison, the
solver timings (cold plans, warm re-plans, scipy trust-constr on the same NLP), the
paper's parametrization against dense quadrature and higher degrees (true energy
against the net-work lower bound), and a swaying obstacle that forces repeated
re-planning.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, load_pinocchio
from harness.sections import planning_figures as figures
from planning.baselines import MinimumJerk, solve_trust_constr
from planning.config import PlannerConfig
from planning.energy import absolute_energy, net_work
from planning.replanning import execute
from planning.result import PlanResult, evaluate, sample_execution, to_json
from planning.scenarios import crossing_scenario, paper_scenario, swaying_scenario
from planning.screening import screen
from planning.solver import ObstacleForecast, Planner
from planning.speed import measure
from planning.variants import PARAMETRIZATIONS, Parametrization

CLEARANCE_SLACK = 2e-3  # m: acceptance allows lambda - 2 mm where avoidance is needed


def _summary(result: PlanResult, free: PlanResult, baseline, threshold: float) -> dict:
    """Headline numbers of one executed plan; `free` is the unobstructed optimum."""
    needed = free.sample_clearance < threshold
    return {
        "energy_pinocchio_J": absolute_energy(baseline, result.t, result.q, result.qd,
                                              result.qdd),
        "energy_own_model_J": result.energy,
        "objective_energy_first_solve_J": result.execution.segments[0].energy,
        "min_clearance_m": float(result.sample_clearance.min()),
        "samples_needing_avoidance": int(needed.sum()),
        "min_clearance_where_needed_m": float(result.sample_clearance[needed].min())
        if needed.any() else None,
        "end_error_rad": result.end_error,
        "limit_violation_rad": result.limit_violation,
        "replans": len(result.execution.segments) - 1,
        "max_penalty_weight_used": max(s.penalty_weight for s in result.execution.segments),
        "solve_ms": list(result.execution.solve_ms),
        "feasible": result.feasible, "problems": list(result.problems),
    }


def _plan(model, scenario, config=None, avoid=True) -> PlanResult:
    planner = Planner(model, config)
    return evaluate(execute(planner, scenario, avoid=avoid), scenario, model, planner.config)


def _minimum_jerk(baseline, scenario, config: PlannerConfig) -> dict:
    """Energy (Pinocchio, 2 ms grid) of the minimum-jerk motion and of the unobstructed
    energy optimum, rest to rest and with free end velocity, for N = 10 and N = 40."""
    grid = np.linspace(0.0, scenario.duration, 1001)
    jerk = MinimumJerk(np.asarray(scenario.start), np.asarray(scenario.goal), scenario.duration)
    e_jerk = absolute_energy(baseline, grid, *jerk.state(grid))
    out = {"energy_minimum_jerk_J": e_jerk}
    for n in (config.energy_samples, 40):
        for rest in (True, False):
            variant = dataclasses.replace(config, energy_samples=n, rest_at_goal=rest)
            result = _plan(baseline, scenario, variant, avoid=False)
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
    planner = Planner(baseline, config)
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


def _parametrizations(baseline, scenario, quick: bool) -> dict:
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


def _swaying(baseline, free_trajectory, quick: bool) -> tuple[dict, PlanResult, object]:
    """The crossing obstacle swaying sideways: the constant-velocity prediction from the last
    two samples is never exact, so Algorithm 2 re-plans wherever the forecast threatens."""
    planner = Planner(baseline)
    scenario = swaying_scenario(free_trajectory, planner.config.geometry)
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


def _scenario_replans(solve_ms) -> dict:
    """Timings (ms, wall) of a scenario's actual solves: the first plan, the first re-plan
    (the forecast switches from 'standing still' to 'moving' there, so it is the largest
    change) and all re-plans, each incl. re-screening and penalty escalation."""
    ms = np.asarray(solve_ms, float)
    replans = ms[1:]
    return {"first_plan_ms": float(ms[0]), "replans_timed": len(replans),
            "first_replan_ms": float(replans[0]) if len(replans) else None,
            "replan_median_ms": float(np.median(replans)) if len(replans) else None,
            "replan_p95_ms": float(np.percentile(replans, 95)) if len(replans) else None,
            "replan_max_ms": float(np.max(replans)) if len(replans) else None}


def _speed(baseline, scenario, quick: bool) -> dict:
    """IPOPT cold and warm timings, and scipy trust-constr on the same cold problem."""
    planner = Planner(baseline)
    # one obstacle sample apart, over the whole motion, also in quick mode (about 2 s)
    timings, _ = measure(planner, scenario, cold_repeats=3 if quick else 5)
    out = timings.summary()
    obstacle = scenario.obstacle
    forecast = ObstacleForecast(obstacle.sample_times, obstacle.position(obstacle.sample_times))
    free = planner.solve(scenario.start, scenario.start_velocity, scenario.duration,
                         scenario.goal)
    subset = screen(forecast, free.trajectory, planner.config.geometry,
                    planner.config.threshold, planner.config.obstacle_slots)
    args = (scenario.start, scenario.start_velocity, scenario.duration, scenario.goal)
    ipopt = planner.solve(*args, subset, 0.0, reference=free.trajectory)
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


def run(out_dir: Path, quick: bool = False, identified_model=None) -> dict:
    """Plan, evaluate, time and draw; returns markdown, results, figures and plans."""
    out_dir = Path(out_dir)
    baseline = PinocchioModel(load_pinocchio(DEFAULT_ROBOT))
    config, scenario = PlannerConfig(), paper_scenario()
    models = {"pinocchio": baseline}
    if identified_model is not None:
        models["identified"] = identified_model
    free = _plan(baseline, scenario, avoid=False)
    paper, summaries, plans = {}, {}, {}
    for name, model in models.items():
        paper[name] = _plan(model, scenario)
        summaries[name] = _summary(paper[name], free, baseline, config.threshold)
        plans[f"paper_{name}"] = to_json(paper[name], scenario, config, name)
    crossing = crossing_scenario(free.execution.segments[0].trajectory, config.geometry)
    crossing_free = _plan(baseline, crossing, avoid=False)
    crossing_avoid = _plan(baseline, crossing)
    plans["crossing_obstacle"] = to_json(crossing_avoid, crossing, config, "pinocchio")
    crossing_summary = _summary(crossing_avoid, crossing_free, baseline, config.threshold)
    crossing_summary["energy_unobstructed_J"] = _summary(crossing_free, crossing_free, baseline,
                                                         config.threshold)["energy_pinocchio_J"]
    crossing_summary["detour_cost_J"] = (crossing_summary["energy_pinocchio_J"]
                                         - crossing_summary["energy_unobstructed_J"])
    crossing_summary["detour_cost_pct"] = (100 * crossing_summary["detour_cost_J"]
                                           / crossing_summary["energy_unobstructed_J"])
    crossing_summary["obstacle_from"] = list(crossing.obstacle.start)
    crossing_summary["obstacle_to"] = list(crossing.obstacle.end)
    jerk = _minimum_jerk(baseline, scenario, config)
    fine = _plan(baseline, scenario, dataclasses.replace(config, energy_samples=40))
    samples = {"energy_N10_J": summaries["pinocchio"]["energy_pinocchio_J"],
               "energy_N40_J": _summary(fine, free, baseline, config.threshold)
               ["energy_pinocchio_J"]}
    samples["difference_pct"] = 100 * (samples["energy_N10_J"] - samples["energy_N40_J"]) \
        / samples["energy_N40_J"]
    speed = _speed(baseline, scenario, quick)
    crossing_timings, _ = measure(Planner(baseline), crossing, cold_repeats=3)
    speed["crossing"] = crossing_timings.summary()
    free_trajectory = free.execution.segments[0].trajectory
    sway, sway_result, sway_scenario = _swaying(baseline, free_trajectory, quick)
    plans["swaying_obstacle"] = to_json(sway_result, sway_scenario, config, "pinocchio")
    speed["scenarios"] = {**{f"paper ({k})": _scenario_replans(v.execution.solve_ms)
                                for k, v in paper.items()},
                          "crossing": _scenario_replans(crossing_avoid.execution.solve_ms),
                          "swaying": _scenario_replans(sway_result.execution.solve_ms)}
    results = {"paper": summaries, "crossing": crossing_summary, "minimum_jerk": jerk,
               "parametrizations": _parametrizations(baseline, scenario, quick),
               "swaying": sway,
               "energy_samples": samples, "speed": speed,
               "unobstructed_min_clearance_m": float(free.sample_clearance.min())}
    results["acceptance"] = _acceptance(results, config.threshold)
    results["headline"] = _headline(results)
    figure_dir = out_dir / "figures"
    figs = [figures.path3d(free, paper, figure_dir / "planning_path3d.png"),
            figures.clearance(paper, crossing_avoid, config.threshold,
                              figure_dir / "planning_clearance.png", sway_result),
            figures.power(baseline, free, paper, figure_dir / "planning_power.png")]
    return {"markdown": figures.markdown(results, config), "results": results,
            "figures": [str(f) for f in figs], "plans": plans}


def _acceptance(results: dict, threshold: float) -> dict:
    paper, speed = results["paper"], results["speed"]
    out = {}
    for name, s in paper.items():
        needed = s["min_clearance_where_needed_m"]
        out[f"{name}_end_error_le_1e-6"] = s["end_error_rad"] <= 1e-6
        out[f"{name}_clearance_held"] = needed is None or needed >= threshold - CLEARANCE_SLACK
        out[f"{name}_feasible"] = s["feasible"]
    if "identified" in paper:
        e_id, e_pin = (paper[k]["energy_pinocchio_J"] for k in ("identified", "pinocchio"))
        out["identified_energy_within_2pct"] = abs(e_id - e_pin) / e_pin <= 0.02
    cross = results["crossing"]
    out["crossing_avoidance_active"] = cross["samples_needing_avoidance"] > 0 \
        and cross["replans"] >= 1
    out["crossing_clearance_held"] = cross["min_clearance_where_needed_m"] >= threshold \
        - CLEARANCE_SLACK
    out["swaying_replans_repeatedly"] = results["swaying"]["replans"] >= 5
    out["swaying_clearance_held"] = results["swaying"]["min_clearance_m"] >= threshold \
        - CLEARANCE_SLACK
    # issue's definition: warm re-plan with the obstacle one sample further (synthetic sweep);
    # the scenarios' actual re-plans are reported beside it (speed.scenarios), not checked
    out["synthetic_replan_median_le_10ms"] = speed["replan_median_ms"] <= 10
    out["synthetic_replan_p95_le_50ms"] = speed["replan_p95_ms"] <= 50
    out["cold_plan_le_500ms"] = speed["cold_max_ms"] <= 500
    return out


def _headline(results: dict) -> dict:
    paper, speed = results["paper"], results["speed"]
    out = {f"paper.{k}.energy_J": v["energy_pinocchio_J"] for k, v in paper.items()}
    out.update({f"paper.{k}.min_clearance_m": v["min_clearance_m"] for k, v in paper.items()})
    if "identified" in paper:
        e_id, e_pin = (paper[k]["energy_pinocchio_J"] for k in ("identified", "pinocchio"))
        out["identified_vs_pinocchio_energy_pct"] = 100 * (e_id - e_pin) / e_pin
    out["crossing.detour_cost_pct"] = results["crossing"]["detour_cost_pct"]
    out["crossing.min_clearance_m"] = results["crossing"]["min_clearance_m"]
    out["minimum_jerk_saving_N10_rest_pct"] = results["minimum_jerk"]["saving_N10_rest_to_rest_pct"]
    out["minimum_jerk_saving_N40_rest_pct"] = results["minimum_jerk"]["saving_N40_rest_to_rest_pct"]
    par = results["parametrizations"]
    out["net_work_bound_J"] = par["net_work_bound_J"]
    out["minimum_jerk_true_energy_J"] = par["minimum_jerk_true_energy_J"]
    for name, v in par["variants"].items():
        out[f"parametrization.{name}.free_true_energy_J"] = v["free_true_energy_J"]
        out[f"parametrization.{name}.paper_true_energy_J"] = v["paper_true_energy_J"]
    out["swaying.replans"] = results["swaying"]["replans"]
    out["swaying.replan_median_ms"] = results["swaying"]["replan_median_ms"]
    out["swaying.min_clearance_m"] = results["swaying"]["min_clearance_m"]
    out["synthetic_replan_median_ms (warm, obstacle one sample further)"] = \
        speed["replan_median_ms"]
    out["synthetic_replan_p95_ms"] = speed["replan_p95_ms"]
    out["synthetic_replan_cpu_median_ms"] = speed["replan_cpu_median_ms"]
    for name, v in speed["scenarios"].items():
        if v["replans_timed"]:
            out[f"{name}: actual re-plan median / max ms"] = [v["replan_median_ms"],
                                                              v["replan_max_ms"]]
    out["cold_plan_median_ms"] = speed["cold_median_ms"]
    same = speed["same_problem"]
    if same["scipy_success"]:
        out["scipy_trust_constr_ms"] = same["scipy_trust_constr_ms"]
    else:
        out["scipy_trust_constr"] = (
            f"did not converge within {same['scipy_iterations']} iterations "
            f"({same['scipy_trust_constr_ms'] / 1e3:.1f} s), objective "
            f"{same['scipy_objective_J']:.4f} vs IPOPT {same['ipopt_objective_J']:.4f}")
    return out
