"""Figure and markdown of the arm planning section."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.report.figures import plt, save_figure
from planning.formulation.kinematics import ArmGeometry

STYLES = {"unobstructed": ("tab:red", ":"), "pinocchio": ("tab:green", "-"),
          "identified": ("tab:orange", "--")}


def path3d(executed: dict, scenario, geometry: ArmGeometry, path: Path,
           threshold: float | None = None) -> Path:
    """Flange paths of the unobstructed optimum and the executed plans, the obstacle's path,
    the arm (its links) of each plan at mid-time, when the obstacle crosses, and (threshold
    given, m) the clearance threshold: a sphere of that radius about the obstacle at its
    closest approach to the closed-form plan, with that plan's links then."""
    fig = plt.figure(figsize=(7.5, 6.5))
    ax = fig.add_subplot(projection="3d")
    for name, result in executed.items():
        color, style = STYLES.get(name, ("tab:blue", "-"))
        ax.plot(*geometry.flange_position(result.q).T, color=color, ls=style,
                label=f"flange, {name}")
        mid = np.searchsorted(result.t, 0.5 * result.t[-1])
        points = geometry.points(result.q[mid])[0]
        for i, j in geometry.links:
            ax.plot(*points[[i, j]].T, color=color, ls=style, lw=2.5, alpha=0.6)
    ax.plot([], [], color="grey", lw=2.5, alpha=0.6,
            label=f"links at mid-time (t = {0.5 * scenario.duration:g} s), each plan's colour")
    obstacle = scenario.obstacle.position(np.linspace(0, scenario.duration, 50))
    ax.plot(*obstacle.T, color="black", label="obstacle centre")
    ax.scatter(*scenario.obstacle.position(0.5 * scenario.duration)[0], color="black", s=20)
    closest = next((n for n in ("pinocchio", *executed) if n in executed and n != "unobstructed"),
                   None)
    if threshold and closest is not None:
        _threshold_sphere(ax, executed[closest], closest, geometry, threshold)
    ax.set(xlabel="x (m)", ylabel="y (m)", zlabel="z (m)",
           title=f"{geometry.name}: flange paths, links at mid-time")
    ax.set_aspect("equal")
    fig.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.04), ncol=2)  # below the axes
    return save_figure(fig, path, tight="bbox")


def _threshold_sphere(ax, result, name: str, geometry: ArmGeometry, threshold: float) -> None:
    """The obstacle's threshold sphere (radius threshold, m) at the instant the plan's links
    come closest to its centre, and the plan's links at that instant."""
    k = int(np.argmin(result.clearance.min(axis=1)))
    centre = result.obstacle[k]
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 24), np.linspace(0, np.pi, 12))
    sphere = [centre[0] + threshold * np.cos(u) * np.sin(v),
              centre[1] + threshold * np.sin(u) * np.sin(v), centre[2] + threshold * np.cos(v)]
    ax.plot_wireframe(*sphere, color="tab:purple", lw=0.4, alpha=0.5,
                      label=f"clearance threshold λ = {1e3 * threshold:.0f} mm about the obstacle, "
                            f"at its closest approach to {name} (t = {result.t[k]:.2f} s)")
    points = geometry.points(result.q[k])[0]
    for n, (i, j) in enumerate(geometry.links):
        ax.plot(*points[[i, j]].T, color="tab:purple", lw=1.2,
                label=f"{name}'s links then" if n == 0 else None)


def markdown(r: dict) -> list[str]:
    speed = r["timing"]["speed"]
    md = [f"Robot `{r['robot']}` ({r['dof']} joints, links checked: {', '.join(r['links'])}). "
          f"Motion {_angles(r['start'])} -> {_angles(r['goal'])} rad in {r['duration_s']:g} s, "
          "from rest to rest; the obstacle crosses the middle of "
          f"{r['crossed_link']} of the unobstructed optimum at t = {r['duration_s'] / 2:g} s "
          f"(from {_angles(r['obstacle_from'])} to {_angles(r['obstacle_to'])} m); threshold "
          f"{r['threshold_m']:g} m; torque limits {r['torque_limit_Nm']} N m from the model. "
          "The identified model is the identification section's.", "",
          "| plan | energy, own model (J) | true energy (J) | physical bound (J) | "
          "min clearance, whole path (mm) | closest link | re-plans | end error (rad) | "
          "end speed (rad/s) |", "|---|---|---|---|---|---|---|---|---|"]
    for name in ("unobstructed", "pinocchio", "identified", "swaying"):
        if name not in r:
            continue
        s = r[name]
        md.append(f"| {name} | {s['energy_J']:.4f} | {s['true_energy_J']:.4f} | "
                  f"{s['energy_bound_J']:.4f} | {1e3 * s['min_clearance_m']:.1f} | "
                  f"{s['closest_link']} | {s['replans']} | {s['end_error_rad']:.1e} | "
                  f"{s['end_speed_rad_s']:.1e} |")
    md += ["", "True energy: integral of |P| under Pinocchio on the plan's dense grid. Physical "
           "bound: |V(T) - V(0) + dissipated|, what any rest-to-rest motion along that path "
           "must spend. The unobstructed optimum ignores the obstacle placed on it; `swaying`: "
           "the same crossing with the obstacle swaying 4 cm sideways (closed form).", "",
           "Against the causal reference (Algorithm 2 re-planning by a multi-start of IPOPT to "
           "convergence at every re-plan, harness.plan.causal; true energy): " + "; ".join(
               f"{name} {c['executed_J']:.4f} J against {c['reference_J']:.4f} J "
               f"({c['excess_pct']:+.2f} %)" for name, c in r.get("against_causal", {}).items())
           + " (the crossing and the swaying crossing are the planner's development scenarios)."
           + fresh_text(r.get("fresh_scenarios")), "",
           f"Speed (closed form, crossing scenario; CPU time of the planning thread): cold plan "
           f"median {speed['cold_cpu_median_ms']:.0f} ms, max {speed['cold_cpu_max_ms']:.0f} ms; "
           f"warm re-plan with the obstacle one sample further median "
           f"{speed['replan_cpu_median_ms']:.1f} ms, max {speed['replan_cpu_max_ms']:.1f} ms over "
           f"{speed['replans_timed']} re-plans ({speed['replan_failures']} failed)."]
    fatrop = r["timing"].get("penalty_loop_speed")
    if fatrop is not None:
        md[-1] += (" The anytime SQP plans and re-plans under its CPU budget (10 ms a re-plan, "
                   "25 ms a cold plan); the paper's penalty loop (fatrop, `plan --replanner "
                   f"fatrop`) beside, same measure: cold median {fatrop['cold_cpu_median_ms']:.0f}"
                   f" ms, max {fatrop['cold_cpu_max_ms']:.0f} ms; re-plan median "
                   f"{fatrop['replan_cpu_median_ms']:.1f} ms, max "
                   f"{fatrop['replan_cpu_max_ms']:.1f} ms ({fatrop['replan_failures']} failed). "
                   "The executed plans above count each SQP iteration as "
                   f"{r['timing']['replay_iteration_ms']:g} ms of the budgets (the same plans on "
                   "any load); their re-plans' real CPU, max "
                   f"{speed['executed_replan_cpu_max_ms']:.1f} ms.")
    return md


def _angles(values) -> str:
    return "(" + ", ".join(f"{v:.3g}" for v in values) + ")"


def fresh_text(fresh: dict | None) -> str:
    """The planner on the fresh scenarios (harness.bench.planning.section.fresh_scenarios)."""
    if not fresh:
        return ""
    rows = "; ".join(f"{c['executed_J']:.4f} J against {c['reference_J']:.4f} J "
                     f"({c['excess_pct']:+.2f} %{'' if c['reference_feasible'] else ', reference infeasible'}"
                     f"{'' if c['clear'] else ', clearance not kept'})" for c in fresh["rows"])
    return (f" On {len(fresh['rows'])} fresh scenarios (seed {fresh['seed']}, drawn once; start "
            f"and goal within +-{fresh['span_rad']:g} rad; no setting chosen on them): {rows}.")
