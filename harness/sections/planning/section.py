"""The planning section: plans, checks, times and draws (see the package docstring)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from harness.robots.arm import bench_motion, planner_config
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.sections.base import Context, Row, SectionResult, Target, check
from harness.sections.paper import EXTRAS
from harness.sections.planning import figures
from planning.energy import absolute_energy
from planning.replanning import execute
from planning.result import CLEARANCE_TOLERANCE, END_TOLERANCE, closest_link, evaluate, to_json
from planning.scenarios import crossing_scenario
from planning.solver import Planner
from planning.speed import measure

REST_TOLERANCE = 1e-6  # rad/s at the goal
ENERGY_TOLERANCE = 1e-3  # J below the physical bound still counted (quadrature)
IDENTIFIED_TARGET = 0.02  # identified plan's true energy within 2 % of the closed form's
COLD_TARGET_MS, REPLAN_MEDIAN_MS, REPLAN_MAX_MS = 25.0, 2.0, 10.0


def energy_bound(model: pin.Model, result) -> float:
    """What any motion from rest to rest along result's path must spend (J): |V(T) - V(0)
    + dissipated|, the work the motors do net of the viscous damping's, since the kinetic
    energy is zero at both ends and integral |P| >= |integral P|."""
    data = model.createData()
    v = [pin.computePotentialEnergy(model, data, result.q[k]) for k in (0, -1)]
    damping = np.asarray(model.damping)
    p = np.sum(damping * result.qd**2, axis=1)
    dissipated = float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(result.t)))
    return abs(v[1] - v[0] + dissipated)


def summary(result, baseline: PinocchioModel, config) -> dict:
    """What one executed plan costs and how close it comes (true energy: Pinocchio)."""
    links = closest_link(result, config)
    return {"energy_J": result.energy,
            "true_energy_J": absolute_energy(baseline, result.t, result.q, result.qd, result.qdd),
            "energy_bound_J": energy_bound(baseline.model, result),
            "end_speed_rad_s": float(np.max(np.abs(result.qd[-1]))),
            "min_clearance_m": float(result.clearance.min()),
            "closest_link": links["closest_link"],
            "end_error_rad": result.end_error, "replans": len(result.execution.segments) - 1,
            "peak_torque_Nm": result.peak_torque.tolist(), "feasible": result.feasible,
            "problems": list(result.problems)}


def plan_checks(name: str, s: dict, threshold: float, rest: bool) -> list:
    out = [check(f"{name}_feasible", s["feasible"], "; ".join(s["problems"]) or "no problem"),
           check(f"{name}_reaches_goal", s["end_error_rad"] <= END_TOLERANCE,
                 f"end error {s['end_error_rad']:.1e} rad"),
           check(f"{name}_clearance_held", s["min_clearance_m"] >= threshold - CLEARANCE_TOLERANCE,
                 f"min clearance {1e3 * s['min_clearance_m']:.1f} mm, threshold "
                 f"{1e3 * threshold:.0f} mm")]
    if rest:
        out += [check(f"{name}_ends_at_rest", s["end_speed_rad_s"] <= REST_TOLERANCE,
                      f"end speed {s['end_speed_rad_s']:.1e} rad/s"),
                check(f"{name}_spends_the_physical_bound",
                      s["true_energy_J"] >= s["energy_bound_J"] - ENERGY_TOLERANCE,
                      f"{s['true_energy_J']:.4f} J spent, |dV + dissipated| = "
                      f"{s['energy_bound_J']:.4f} J")]
    return out


def run(ctx: Context) -> SectionResult:
    robot = ctx.robot.name
    baseline = PinocchioModel(load_pinocchio(robot))
    config = planner_config(robot, compile_code=True, starts=4)  # as `plan` plans
    base, link = bench_motion(robot)
    planner = Planner(baseline, config)
    free = evaluate(execute(planner, base, avoid=False), base, baseline, config)
    scenario = crossing_scenario(free.execution.segments[0].trajectory, config.geometry,
                                 base=base, link=link)
    free_crossing = evaluate(execute(planner, scenario, avoid=False), scenario, baseline, config)
    models = {"pinocchio": baseline}
    identified = ctx.output("identification", "model")
    if identified is not None:
        models["identified"] = identified
    results = {"robot": robot, "dof": config.geometry.dof, "links": config.geometry.link_names,
               "crossed_link": config.geometry.link_names[link], "start": base.start,
               "goal": base.goal, "duration_s": base.duration, "threshold_m": config.threshold,
               "torque_limit_Nm": config.torque_limit,
               "obstacle_from": list(scenario.obstacle.start),
               "obstacle_to": list(scenario.obstacle.end),
               "unobstructed": summary(free_crossing, baseline, config)}
    plans, executed = {}, {"unobstructed": free_crossing}
    checks = [check("obstacle_crosses_the_free_path",
                    free_crossing.clearance.min() < config.threshold,
                    f"unobstructed clearance {1e3 * free_crossing.clearance.min():.1f} mm")]
    for name, model in models.items():
        p = planner if model is baseline else Planner(model, config)
        executed[name] = evaluate(execute(p, scenario), scenario, model, config)
        results[name] = summary(executed[name], baseline, config)
        plans[f"{name}_crossing"] = to_json(executed[name], scenario, config, name)
        checks += plan_checks(name, results[name], config.threshold, config.rest_at_goal)
    checks.append(check("pinocchio_replanned", results["pinocchio"]["replans"] >= 1,
                        f"{results['pinocchio']['replans']} re-plans"))
    timings, _ = measure(planner, scenario, cold_repeats=2 if ctx.quick else 5,
                         stride=10 if ctx.quick else 2)
    speed = {**timings.summary(), "cold_cpu_max_ms": float(np.max(timings.cold_cpu_ms)),
             "replan_cpu_max_ms": float(np.max(timings.replan_cpu_ms))}
    results["timing"] = {"speed": speed}
    targets = [Target("cold plan CPU time, max", speed["cold_cpu_max_ms"], COLD_TARGET_MS,
                      "ms", timing=True),
               Target("warm re-plan CPU time, median", speed["replan_cpu_median_ms"],
                      REPLAN_MEDIAN_MS, "ms", timing=True),
               Target("warm re-plan CPU time, max", speed["replan_cpu_max_ms"],
                      REPLAN_MAX_MS, "ms", timing=True)]
    headline = []
    if "identified" in results:
        ratio = results["identified"]["true_energy_J"] / results["pinocchio"]["true_energy_J"]
        results["identified_true_energy_ratio"] = ratio
        targets.append(Target("identified plan's true energy against the closed-form plan's",
                              abs(ratio - 1) * 100, 100 * IDENTIFIED_TARGET, "%"))
        headline.append(Row(f"Obstacle crossing the motion ({robot}, rest to rest): true energy "
                            "of the identified model's plan vs the closed-form plan's",
                            f"{results['identified']['true_energy_J']:.4f} J vs "
                            f"{results['pinocchio']['true_energy_J']:.4f} J "
                            f"({100 * (ratio - 1):+.2f} %)"))
    out = SectionResult("\n".join(figures.markdown(results)), results, checks, targets, headline,
                        outputs={"plans": plans})
    out.figures.append(figures.path3d(executed, scenario, config.geometry,
                                      ctx.figures_dir / "planning_path3d.png"))
    for extra in ctx.robot.extras:
        out.extend(EXTRAS[extra].planning(ctx, models), extra)
    return out
