"""Figures and markdown of the paper_planning study (paper Figs. 9, 10, 11)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.paper.planning.scenario import paper_scenario
from harness.report.figures import plt, save_figure
from planning.formulation.energy import power as mechanical_power
from planning.formulation.kinematics import paper_arm

COLORS = {"pinocchio": "tab:green", "identified": "tab:orange"}


def path3d(free, paper: dict, path: Path) -> Path:
    """End-effector paths: unobstructed optimum, executed plans, obstacle path (Fig. 9)."""
    geometry = paper_arm()
    fig = plt.figure(figsize=(6.5, 5.5))
    ax = fig.add_subplot(projection="3d")
    tip = geometry.flange_position(free.q)
    ax.plot(*tip.T, color="tab:red", label="energy-optimal, no obstacle")
    for name, result in paper.items():
        tip = geometry.flange_position(result.q)
        ax.plot(*tip.T, color=COLORS.get(name, "tab:blue"), ls="-" if name == "pinocchio"
                else "--", label=f"executed ({name})")
    obstacle = next(iter(paper.values())).obstacle
    ax.plot(*obstacle.T, color="black", label="obstacle centre")
    ax.scatter(*obstacle[0], color="black", marker="o", s=12)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.set_title("End-effector path, paper scenario")
    ax.legend(fontsize=7, loc="upper left")
    return save_figure(fig, path)


def clearance(paper: dict, crossing, threshold: float, path: Path, swaying=None) -> Path:
    """Distance from the obstacle centre to link 2 (d1) and link 3 (d2) (Fig. 10); re-plans
    as grey lines."""
    runs = [("paper scenario", paper.get("pinocchio")), ("crossing obstacle", crossing)]
    if swaying is not None:
        runs.append(("swaying obstacle", swaying))
    fig, axes = plt.subplots(1, len(runs), figsize=(5 * len(runs), 3.6), sharey=True)
    for ax, (title, result) in zip(axes, runs, strict=True):
        ax.plot(result.t, result.clearance[:, 0], label="d1: shoulder-elbow")
        ax.plot(result.t, result.clearance[:, 1], label="d2: elbow-end effector")
        ax.axhline(threshold, color="red", ls="--", label=f"threshold {threshold} m")
        for t in result.execution.replan_times[1:]:
            ax.axvline(t, color="grey", lw=0.5)
        ax.set_xlabel("time (s)")
        ax.set_title(title)
        ax.set_ylim(0, None)
    axes[0].set_ylabel("distance to obstacle centre (m)")
    axes[0].legend(fontsize=7)
    return save_figure(fig, path)


def power(baseline, free, paper: dict, path: Path) -> Path:
    """Mechanical power along each plan, Pinocchio torques (Fig. 11)."""
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(free.t, mechanical_power(baseline, free.q, free.qd, free.qdd), color="tab:red",
            lw=1, label="no obstacle (closed-form)")
    for name, result in paper.items():
        p = mechanical_power(baseline, result.q, result.qd, result.qdd)
        ax.plot(result.t, p, color=COLORS.get(name, "tab:blue"),
                ls="-" if name == "pinocchio" else "--", label=f"avoiding, planned with {name}")
    ax.axhline(0, color="black", lw=0.5)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("power sum tau_i qd_i (W)")
    ax.legend(fontsize=7)
    return save_figure(fig, path)


def _row(name: str, s: dict) -> str:
    needed = s["min_clearance_where_needed_m"]
    return (f"| {name} | {s['energy_pinocchio_J']:.4f} | {s['energy_own_model_J']:.4f} | "
            f"{s['min_clearance_m']:.4f} | {needed if needed is None else f'{needed:.4f}'} | "
            f"{s['end_error_rad']:.1e} | {s['replans']} | {'yes' if s['feasible'] else 'NO'} |")


def markdown(results: dict, config) -> str:
    """The section's text: tables of every headline number."""
    paper, cross, jerk = results["paper"], results["crossing"], results["minimum_jerk"]
    speed, same, samples = results["speed"], results["speed"]["same_problem"], \
        results["energy_samples"]
    lines = [
        f"Quartic joint polynomials, energy sum |P| sigma/N (N = {config.energy_samples}) plus "
        f"alpha max(0, lambda - d)^2 (alpha = {config.penalty_weight}, lambda = "
        f"{config.threshold} m) to the link *segments* at every predicted obstacle sample, "
        f"{config.penalty.solver} with exact CasADi derivatives; re-planning per Algorithm 2 (the "
        "paper's parametrization; the row 'default' is the default planner, which integrates "
        "the true energy: see below). alpha is raised "
        "x10 while a solution dips more than 1 mm below lambda (exterior penalty method); "
        "largest alpha used: " + ", ".join(f"{k} {v['max_penalty_weight_used']:g}" for k, v in
                                           {**paper, "crossing": cross}.items())
        + ". Energies are integral |P| dt with Pinocchio torques on a 2 ms grid.", "",
        "| plan (paper scenario) | energy, Pinocchio (J) | energy, own model (J) | min clearance"
        " (m) | min clearance where needed (m) | end error (rad) | re-plans | feasible |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [_row(name, s) for name, s in paper.items()]
    lines.append(_row("crossing obstacle (pinocchio)", cross))
    if "identified" in paper:
        e_id, e_pin = (paper[k]["energy_pinocchio_J"] for k in ("identified", "pinocchio"))
        lines += ["", f"Identified vs closed-form energy: {100 * (e_id - e_pin) / e_pin:+.3f} %."]
    lines += [
        "", f"Unobstructed optimum's closest approach: "
        f"{results['unobstructed_min_clearance_m']:.4f} m; samples needing avoidance: "
        f"{paper['pinocchio']['samples_needing_avoidance']} (paper), "
        f"{cross['samples_needing_avoidance']} (crossing).",
        f"Crossing obstacle detour: {cross['energy_pinocchio_J']:.4f} J vs "
        f"{cross['energy_unobstructed_J']:.4f} J unobstructed, cost "
        f"{cross['detour_cost_J']:+.4f} J ({cross['detour_cost_pct']:+.2f} %).",
        f"Minimum-jerk (rest to rest) {jerk['energy_minimum_jerk_J']:.4f} J. Unobstructed "
        "energy optimum, saving against it: " + "; ".join(
            f"{key.replace('_', ' ')} {jerk[f'energy_optimal_{key}_J']:.4f} J "
            f"({jerk[f'saving_{key}_pct']:+.1f} %)" for key in
            ("N10_rest_to_rest", "N10_free_end_velocity", "N40_rest_to_rest",
             "N40_free_end_velocity")) + ". " + _quadrature_note(results["parametrizations"]),
        f"Energy samples: N = 10 plan {samples['energy_N10_J']:.4f} J vs N = 40 plan "
        f"{samples['energy_N40_J']:.4f} J ({samples['difference_pct']:+.2f} %).", "",
        "| timing | value |", "|---|---|",
        f"| cold plan (median / max) | {speed['cold_median_ms']:.1f} / "
        f"{speed['cold_max_ms']:.1f} ms |",
        f"| **synthetic** re-plan (the issue's definition: warm, previous plan, obstacle one "
        f"sample further; median / p95 / max over {speed['replans_timed']}) | "
        f"{speed['replan_median_ms']:.1f} / "
        f"{speed['replan_p95_ms']:.1f} / {speed['replan_max_ms']:.1f} ms |",
        f"| of which the solver calls (median, any plugin) | {speed['replan_solver_median_ms']:.1f} ms |",
        f"| crossing scenario, synthetic: cold plan median; re-plan median / p95 / max | "
        f"{speed['crossing']['cold_median_ms']:.1f} ms; {speed['crossing']['replan_median_ms']:.1f}"
        f" / {speed['crossing']['replan_p95_ms']:.1f} / {speed['crossing']['replan_max_ms']:.1f}"
        " ms |",
        *_actual_rows(speed.get("scenarios", {})),
        f"| paper scenario re-plans, CPU time of the solving thread (median / p95) | "
        f"{speed['replan_cpu_median_ms']:.1f} / {speed['replan_cpu_p95_ms']:.1f} ms |",
        f"| cold plan, CPU time (median) | {speed['cold_cpu_median_ms']:.1f} ms |",
        f"| same cold NLP: IPOPT, exact derivatives | {same['ipopt_ms']:.1f} ms, "
        f"{same['ipopt_iterations']} it, objective {same['ipopt_objective_J']:.5f} J |",
        f"| same cold NLP: scipy trust-constr, finite differences | {_scipy(same)} |",
        "", "Wall times depend on the machine's load (CPU time does not); the re-plan period "
        f"of the obstacle's {_rate(paper_scenario()):g} Hz sampling is {1e3 / _rate(paper_scenario()):g} ms. "
        "Actual re-plans include re-screening rounds and penalty escalation; the first plan "
        "sees one observation (a standing obstacle), the first re-plan a moving one.",
        "", *_parametrization_lines(results["parametrizations"]),
        "", *_swaying_lines(results["swaying"], config.threshold),

        "", "Acceptance: " + ", ".join(f"{k} {'yes' if v else 'NO'}"
                                       for k, v in results["acceptance"].items()) + ".",
    ]
    return "\n".join(lines)


def _parametrization_lines(par: dict) -> list[str]:
    """The paper's parametrization against dense quadrature and higher degrees."""
    bound, jerk = par["net_work_bound_J"], par["minimum_jerk_true_energy_J"]
    lines = [
        "What the paper's parametrization costs (one run, free end velocity, Pinocchio; true "
        "energy = integral |P| dt on a 0.5 ms grid). Lower bound: |integral P dt| = change of "
        f"potential energy = {bound:.5f} J, whatever the path; minimum-jerk (rest to rest) "
        f"{jerk:.5f} J ({100 * (jerk - bound) / bound:+.2f} % above the bound).", "",
        "| parametrization | no obstacle: true (J) | planned (J) | vs min-jerk | paper "
        "scenario: true (J) | min clearance (m) | re-plans | cold (ms) | re-plan median / "
        "p95 (ms) | feasible |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name, v in par["variants"].items():
        saving = 100 * (jerk - v["free_true_energy_J"]) / jerk
        lines.append(
            f"| {name} | {v['free_true_energy_J']:.5f} | {v['free_planned_energy_J']:.5f} | "
            f"{saving:+.2f} % | {v['paper_true_energy_J']:.5f} | "
            f"{v['paper_min_clearance_m']:.4f} | {v['paper_replans']} | "
            f"{v['cold_median_ms']:.0f} | {v['replan_median_ms']:.1f} / "
            f"{v['replan_p95_ms']:.1f} (over {v['replans_timed']}) | "
            f"{'yes' if v['paper_feasible'] else 'NO: ' + '; '.join(v['paper_problems'])} |")
    lines += ["", "Saving vs min-jerk > 0 means less energy. With the power summed over "
              "joints and no friction, every motion whose power never goes negative attains "
              f"the bound; minimum jerk is {100 * (jerk - bound) / bound:.2f} % above it, so no "
              "parametrization can save more than that gap."]
    return lines


def _rate(scenario) -> float:
    """Obstacle samples per second of the scenario (Hz)."""
    return scenario.obstacle.samples / scenario.duration


def _quadrature_note(par: dict) -> str:
    """Whether the paper's coarse power quadrature let the optimizer under-count energy."""
    paper = [(n, v) for n, v in par["variants"].items() if v.get("quadrature") == "paper"]
    if not paper:
        return ""
    name, v = paper[0]
    planned, true = v["free_planned_energy_J"], v["free_true_energy_J"]
    if planned < true:
        return (f"With the paper's {v['energy_samples']} power samples ({name}) the optimizer "
                f"plans {planned:.4f} J for a motion that truly costs {true:.4f} J: it puts low "
                "power at the samples, higher between.")
    return (f"With the paper's {v['energy_samples']} power samples ({name}) the planned energy "
            f"{planned:.4f} J is not below the true {true:.4f} J.")


def _swaying_lines(sway: dict, threshold: float) -> list[str]:
    """Repeated re-planning against an obstacle the constant-velocity forecast misjudges."""
    clearance = np.asarray(sway["sample_clearance_m"])
    close = clearance < threshold + 0.02
    return [
        f"Swaying obstacle (crossing path + sway {np.linalg.norm(sway['sway_m']):.3f} m x "
        f"sin(2 pi {sway['sway_periods']:g} t / T); forecast: constant velocity from the last "
        f"two samples): {sway['replans']} re-plans ({len(sway['replan_failures'])} failed), "
        f"re-plan median / p95 / max {_ms(sway['replan_median_ms'])} / "
        f"{_ms(sway['replan_p95_ms'])} / {_ms(sway['replan_max_ms'])} ms, first plan "
        f"{sway['first_plan_ms']:.0f} ms; executed clearance min {sway['min_clearance_m']:.4f} m "
        f"over all {len(clearance)} obstacle samples ({int(close.sum())} samples within "
        f"lambda + 2 cm, every sample in plans['swaying_obstacle'].sample_clearance); energy "
        f"{sway['energy_pinocchio_J']:.4f} J; feasible: {sway['feasible']}."]


def _scipy(same: dict) -> str:
    """The scipy baseline: a time to a solution only if it converged."""
    if same["scipy_success"]:
        return (f"{same['scipy_trust_constr_ms']:.0f} ms, {same['scipy_iterations']} it, "
                f"objective {same['scipy_objective_J']:.5f} J")
    return (f"**did not converge** within {same['scipy_iterations']} iterations "
            f"({same['scipy_trust_constr_ms'] / 1e3:.1f} s), objective "
            f"{same['scipy_objective_J']:.4f} vs IPOPT {same['ipopt_objective_J']:.4f} J")


def _actual_rows(scenarios: dict) -> list[str]:
    """Table rows: the actual re-plans of each scenario's executed run."""
    rows = []
    for name, v in scenarios.items():
        if not v["replans_timed"]:
            rows.append(f"| {name}, actual: first plan; no re-plan | {v['first_plan_ms']:.1f} ms |")
            continue
        rows.append(
            f"| {name}, **actual** re-plans ({v['replans_timed']}): first plan; first re-plan; "
            f"median / p95 / max | {v['first_plan_ms']:.1f} ms; {v['first_replan_ms']:.1f} ms; "
            f"{v['replan_median_ms']:.1f} / {v['replan_p95_ms']:.1f} / {v['replan_max_ms']:.1f}"
            " ms |")
    return rows


def _ms(value) -> str:
    return "-" if value is None else f"{value:.1f}"
