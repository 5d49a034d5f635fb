"""Figure and markdown of the arm planning section."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.report.figures import plt, save_figure
from planning.kinematics import ArmGeometry

STYLES = {"unobstructed": ("tab:red", ":"), "pinocchio": ("tab:green", "-"),
          "identified": ("tab:orange", "--")}


def path3d(executed: dict, scenario, geometry: ArmGeometry, path: Path) -> Path:
    """Flange paths of the unobstructed optimum and the executed plans, the obstacle's path,
    and the arm (its links) of each plan at mid-time, when the obstacle crosses."""
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    for name, result in executed.items():
        color, style = STYLES.get(name, ("tab:blue", "-"))
        ax.plot(*geometry.flange_position(result.q).T, color=color, ls=style,
                label=f"flange, {name}")
        mid = np.searchsorted(result.t, 0.5 * result.t[-1])
        points = geometry.points(result.q[mid])[0]
        for i, j in geometry.links:
            ax.plot(*points[[i, j]].T, color=color, ls=style, lw=2.5, alpha=0.6)
    obstacle = scenario.obstacle.position(np.linspace(0, scenario.duration, 50))
    ax.plot(*obstacle.T, color="black", label="obstacle centre")
    ax.scatter(*scenario.obstacle.position(0.5 * scenario.duration)[0], color="black", s=20)
    ax.set(xlabel="x (m)", ylabel="y (m)", zlabel="z (m)",
           title=f"{geometry.name}: flange paths, links at mid-time")
    ax.legend(fontsize=7, loc="upper left")
    return save_figure(fig, path)


def markdown(r: dict) -> list[str]:
    speed = r["speed"]
    md = [f"Robot `{r['robot']}` ({r['dof']} joints, links checked: {', '.join(r['links'])}). "
          f"Motion {_angles(r['start'])} -> {_angles(r['goal'])} rad in {r['duration_s']:g} s; "
          f"the obstacle crosses the middle of {r['crossed_link']} of the unobstructed optimum "
          f"at t = {r['duration_s'] / 2:g} s (from {_angles(r['obstacle_from'])} to "
          f"{_angles(r['obstacle_to'])} m); threshold {r['threshold_m']:g} m; torque limits "
          f"{r['torque_limit_Nm']} N m from the model. Identified model: "
          f"{r['identified_samples']} samples at {100 * r['identified_noise']:g} % noise, "
          "library generated from the kinematics (held-out rel. error per joint "
          f"{', '.join(f'{100 * e:.2f} %' for e in r['identified_heldout_rel_rmse'])}).", "",
          "| plan | energy, own model (J) | true energy (J) | min clearance, whole path (mm) | "
          "closest link | re-plans | end error (rad) | feasible |", "|---|---|---|---|---|---|---|---|"]
    for name in ("unobstructed", "pinocchio", "identified"):
        s = r[name]
        md.append(f"| {name} | {s['energy_J']:.4f} | {s['true_energy_J']:.4f} | "
                  f"{1e3 * s['min_clearance_m']:.1f} | {s['closest_link']} | {s['replans']} | "
                  f"{s['end_error_rad']:.1e} | {s['feasible']} |")
    ratio = r["identified"]["true_energy_J"] / r["pinocchio"]["true_energy_J"]
    md += ["", f"True energy (Pinocchio on the plan's dense grid) of the identified model's plan: "
           f"{100 * (ratio - 1):+.2f} % against the closed-form plan's.", "",
           f"Speed (closed form, crossing scenario; wall clock, CPU in brackets): cold plan "
           f"median {speed['cold_median_ms']:.0f} ms ({speed['cold_cpu_median_ms']:.0f} ms), "
           f"warm re-plan with the obstacle one sample further median "
           f"{speed['replan_median_ms']:.1f} ms ({speed['replan_cpu_median_ms']:.1f} ms), p95 "
           f"{speed['replan_p95_ms']:.1f} ms over {speed['replans_timed']} re-plans "
           f"({speed['replan_failures']} failed)."]
    failed = [k for k, v in r["acceptance"].items() if not v]
    md += ["", f"Acceptance: {sum(r['acceptance'].values())} of {len(r['acceptance'])} checks "
           "pass" + (f"; failing: {', '.join(failed)}." if failed else ".")]
    return md


def _angles(values) -> str:
    return "(" + ", ".join(f"{v:.3g}" for v in values) + ")"
