"""The paper_planning study's entry: plans the scenarios, checks acceptance, writes the
tables and figures. What is measured: see the package docstring (harness.paper.studies.paper_planning)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from harness.paper.planning.scenario import paper_default_config, paper_scenario
from harness.paper.planning.variants import PAPER
from harness.paper.studies.paper_planning import figures
from harness.paper.studies.paper_planning.studies import (
    minimum_jerk_study,
    parametrization_study,
    plan_scenario,
    scenario_replans,
    speed_study,
    swaying_study,
)
from harness.plan.speed import measure
from harness.report.results import Context, SectionResult, Target, check
from planning.config import nominal_iteration_ms
from planning.formulation.energy import absolute_energy
from planning.planners import segment_planner
from planning.result import PlanResult, to_json
from planning.scenarios import crossing_scenario

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


def run(ctx: Context) -> SectionResult:
    """Plan, evaluate, time and draw: the study's report (the identification section's model
    planned beside the closed form when the bench ran it first: `bench --full`)."""
    out_dir, quick = Path(ctx.out_dir), ctx.quick
    identified_model = ctx.output("identification", "model")
    baseline = ctx.arm.nominal
    # the paper reproduction plans with the paper's quadrature (eq. 18, N = 10); the
    # default planner (true energy) runs beside it as "default"
    config, scenario = PAPER.config(), paper_scenario()
    models = {"pinocchio": baseline}
    if identified_model is not None:
        models["identified"] = identified_model
    free = plan_scenario(baseline, scenario, config, avoid=False)
    paper, summaries, plans = {}, {}, {}
    for name, model in models.items():
        paper[name] = plan_scenario(model, scenario, config)
        summaries[name] = _summary(paper[name], free, baseline, config.threshold)
        plans[f"paper_{name}"] = to_json(paper[name], scenario, config, name)
    # on the nominal clock, as `plan` by default: its checks must not depend on the machine
    default = paper_default_config().with_anytime(
        iteration_ms=nominal_iteration_ms(config.geometry.dof))
    paper["default"] = plan_scenario(baseline, scenario, default)
    summaries["default"] = _summary(paper["default"], free, baseline, config.threshold)
    plans["paper_default"] = to_json(paper["default"], scenario, default, "pinocchio")
    crossing = crossing_scenario(free.execution.segments[0].trajectory, config.geometry,
                                 scenario)
    crossing_free = plan_scenario(baseline, crossing, config, avoid=False)
    crossing_avoid = plan_scenario(baseline, crossing, config)
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
    jerk = minimum_jerk_study(baseline, scenario, config)
    fine = plan_scenario(baseline, scenario, dataclasses.replace(config, energy_samples=40))
    samples = {"energy_N10_J": summaries["pinocchio"]["energy_pinocchio_J"],
               "energy_N40_J": _summary(fine, free, baseline, config.threshold)
               ["energy_pinocchio_J"]}
    samples["difference_pct"] = 100 * (samples["energy_N10_J"] - samples["energy_N40_J"]) \
        / samples["energy_N40_J"]
    speed = speed_study(baseline, scenario, quick, config)
    crossing_timings, _ = measure(segment_planner(baseline, config), crossing, cold_repeats=3)
    speed["crossing"] = crossing_timings.summary()
    free_trajectory = free.execution.segments[0].trajectory
    sway, sway_result, sway_scenario = swaying_study(baseline, free_trajectory, quick, config)
    plans["swaying_obstacle"] = to_json(sway_result, sway_scenario, config, "pinocchio")
    speed["scenarios"] = {**{f"paper ({k})": scenario_replans(v.execution.solve_ms)
                                for k, v in paper.items()},
                          "crossing": scenario_replans(crossing_avoid.execution.solve_ms),
                          "swaying": scenario_replans(sway_result.execution.solve_ms)}
    results = {"paper": summaries, "crossing": crossing_summary, "minimum_jerk": jerk,
               "parametrizations": parametrization_study(baseline, scenario, quick),
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
    speed = results["speed"]
    timing = {"synthetic_replan_median_le_10ms": ("synthetic warm re-plan, median", "replan_median_ms", 10),
              "synthetic_replan_p95_le_50ms": ("synthetic warm re-plan, p95", "replan_p95_ms", 50),
              "cold_plan_le_500ms": ("cold plan, max", "cold_max_ms", 500)}
    checks = [check(k, v) for k, v in results["acceptance"].items() if k not in timing]
    targets = [Target(name, speed[key], limit, "ms", timing=True)
               for name, key, limit in timing.values()]
    results["timing"] = {"speed": results.pop("speed")}
    return SectionResult(figures.markdown({**results, "speed": speed}, config), results, checks,
                         targets, figures=figs, outputs={"plans": plans})


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
            f"did not converge within {same['scipy_iterations']} iterations, objective "
            f"{same['scipy_objective_J']:.4f} vs IPOPT {same['ipopt_objective_J']:.4f}")
        out["scipy_trust_constr_ms"] = same["scipy_trust_constr_ms"]
    return out
