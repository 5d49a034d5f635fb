"""The arm planning section: plans, checks, times and draws (see the package docstring)."""

from __future__ import annotations

from pathlib import Path

from harness.data.generate import generate
from harness.robots.arm import bench_motion, planner_config
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.robots.torque_models import robot_library
from harness.sections.arm_planning import figures
from identification.identify import identify
from planning.energy import absolute_energy
from planning.replanning import execute
from planning.result import CLEARANCE_TOLERANCE, END_TOLERANCE, closest_link, evaluate, to_json
from planning.scenarios import crossing_scenario
from planning.solver import Planner
from planning.speed import measure

NOISE, SAMPLES, SEED = 0.05, 4000, 1
COLD_LIMIT_MS, REPLAN_LIMIT_MS = 150.0, 15.0  # issue #12, on the UR5
SPEED_ROBOT = "ur5"


def identified_model(robot: str):
    """A torque model identified from SAMPLES samples at NOISE (the generated library)."""
    data = generate(robot, SAMPLES, NOISE, SEED, "inverse")
    result = identify(data.q, data.qd, data.qdd, data.tau, robot_library(robot), 0.25,
                      data.tau_clean)
    return result.model, [float(x) for x in result.heldout_rel_rmse]


def _summary(result, baseline, config) -> dict:
    """What one executed plan costs and how close it comes (true energy: Pinocchio)."""
    links = closest_link(result, config)
    return {"energy_J": result.energy,
            "true_energy_J": absolute_energy(baseline, result.t, result.q, result.qd, result.qdd),
            "min_clearance_m": float(result.clearance.min()),
            "closest_link": links["closest_link"],
            "link_min_clearance_m": dict(zip(links["links"],
                                             map(float, links["link_min_clearance"]),
                                             strict=True)),
            "end_error_rad": result.end_error, "replans": len(result.execution.segments) - 1,
            "peak_torque_Nm": result.peak_torque.tolist(),
            "solve_ms": list(result.execution.solve_ms), "feasible": result.feasible,
            "problems": list(result.problems)}


def run(out_dir: Path, quick: bool = False, robot: str = "ur5") -> dict:
    baseline = PinocchioModel(load_pinocchio(robot))
    config = planner_config(robot, compile_code=True, starts=4)  # as `plan` plans
    base, link = bench_motion(robot)
    planner = Planner(baseline, config)
    free = evaluate(execute(planner, base, avoid=False), base, baseline, config)
    scenario = crossing_scenario(free.execution.segments[0].trajectory, config.geometry,
                                 base=base, link=link)
    crossed = config.geometry.link_names[link]
    free_crossing = evaluate(execute(planner, scenario, avoid=False), scenario, baseline, config)
    results = {"robot": robot, "dof": config.geometry.dof, "links": config.geometry.link_names,
               "crossed_link": crossed, "start": base.start, "goal": base.goal,
               "duration_s": base.duration, "threshold_m": config.threshold,
               "torque_limit_Nm": config.torque_limit,
               "obstacle_from": list(scenario.obstacle.start),
               "obstacle_to": list(scenario.obstacle.end),
               "unobstructed": _summary(free_crossing, baseline, config)}
    plans, executed = {}, {"unobstructed": free_crossing}
    model, heldout = identified_model(robot)
    results.update(identified_heldout_rel_rmse=heldout, identified_samples=SAMPLES,
                   identified_noise=NOISE)
    for name, m in (("pinocchio", baseline), ("identified", model)):
        p = planner if m is baseline else Planner(m, config)
        executed[name] = evaluate(execute(p, scenario), scenario, m, config)
        results[name] = _summary(executed[name], baseline, config)
        plans[f"{robot}_crossing_{name}"] = to_json(executed[name], scenario, config, name)
    timings, _ = measure(planner, scenario, cold_repeats=2 if quick else 5,
                         stride=10 if quick else 1)
    results["speed"] = timings.summary()
    results["acceptance"] = _acceptance(results, robot)
    results["headline"] = _headline(results)
    figure_dir = Path(out_dir) / "figures"
    figs = [figures.path3d(executed, scenario, config.geometry,
                           figure_dir / f"arm_planning_{robot}_path3d.png")]
    return {"markdown": "\n".join(figures.markdown(results)), "results": results,
            "figures": [str(f) for f in figs], "plans": plans}


def _acceptance(r: dict, robot: str) -> dict:
    out = {}
    for name in ("pinocchio", "identified"):
        s = r[name]
        out[f"{name}_clearance_held_whole_path"] = s["min_clearance_m"] >= r["threshold_m"] \
            - CLEARANCE_TOLERANCE
        out[f"{name}_end_error_le_1e-6"] = s["end_error_rad"] <= END_TOLERANCE
        out[f"{name}_feasible"] = s["feasible"]
    out["obstacle_crosses_free_path"] = r["unobstructed"]["min_clearance_m"] < r["threshold_m"]
    out["avoidance_replanned"] = r["pinocchio"]["replans"] >= 1
    if robot == SPEED_ROBOT:
        speed = r["speed"]
        out[f"cold_plan_median_le_{COLD_LIMIT_MS:g}ms"] = speed["cold_median_ms"] <= COLD_LIMIT_MS
        out[f"warm_replan_median_le_{REPLAN_LIMIT_MS:g}ms"] = \
            speed["replan_median_ms"] <= REPLAN_LIMIT_MS
    return out


def _headline(r: dict) -> dict:
    p, speed = r["pinocchio"], r["speed"]
    return {"min clearance over the whole path, closed form / identified (mm)":
                f"{1e3 * p['min_clearance_m']:.1f} / {1e3 * r['identified']['min_clearance_m']:.1f}",
            "closest link": p["closest_link"],
            "identified plan's true energy vs closed form (%)":
                100 * (true_energy_ratio(r) - 1),
            "cold plan median ms (CPU)": f"{speed['cold_median_ms']:.0f} "
                                         f"({speed['cold_cpu_median_ms']:.0f})",
            "warm re-plan median ms (CPU)": f"{speed['replan_median_ms']:.1f} "
                                            f"({speed['replan_cpu_median_ms']:.1f})"}


def true_energy_ratio(r: dict) -> float:
    """Identified plan's true energy over the closed-form plan's (Pinocchio, dense grid)."""
    return r["identified"]["true_energy_J"] / r["pinocchio"]["true_energy_J"]

