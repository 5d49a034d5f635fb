"""Bench section "replay": the planning section's plans executed in MuJoCo.

The scene is the robot's own (the Lynxmotion's scene.xml) or one built around the arm
(harness.robots.scene: floor, light, mocap obstacle, one motor per joint limited to the
model's torque limits); tracking is Pinocchio feedforward + PD at 0.5 ms
(harness.replay.simulate). Checked per plan (harness.replay.checks): tracking RMS <= 1 mrad,
replayed energy within 2 % of the plan's own and of its dense figure, centre-to-link
clearance >= lambda - 5 mm. Target: the identified model's plan replayed within 1 % of the
closed-form plan's replayed (true) energy, per scenario.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import numpy as np

from harness.replay.checks import checks, pairs, role, table_row
from harness.replay.clearance import ClearanceProbe
from harness.replay.figures import power_figure, tracking_figure
from harness.replay.reference import plan_reference
from harness.replay.simulate import ReplayResult, ReplayTrace, replay
from harness.report.figures import plt, save_figure
from harness.report.results import Context, Row, SectionResult, Target, check
from harness.robots.scene import replay_scene

IDENTIFIED_TOLERANCE = 0.01  # replayed energy, identified plan vs closed-form plan


def clearance_per_link(trace: ReplayTrace, names, threshold: float, title: str,
                       path: Path) -> Path:
    """Centre-to-segment distance of every link to the obstacle over time, replayed."""
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for k, name in enumerate(names):
        ax.plot(trace.t, trace.clearance[:, k], color=f"C{k}", label=name)
    ax.axhline(threshold, color="k", lw=1, label=f"threshold λ = {threshold * 1e3:.0f} mm")
    ax.set(xlabel="time t (s)", ylabel="obstacle centre to link (m)", title=title,
           ylim=(0, max(4 * threshold, float(np.percentile(trace.clearance, 60)))))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return save_figure(fig, path)


def run(ctx: Context) -> SectionResult:
    plans = ctx.output("planning", "plans") or {}
    if not plans:
        return SectionResult("No plans to replay (the planning section did not run).",
                             checks=[check("plans_to_replay", False, "none handed on")])
    arm = ctx.arm
    robot, model, geometry, feedforward = arm.reference, replay_scene(arm), arm.geometry, arm.nominal
    results: dict[str, ReplayResult] = {}
    traces: dict[str, ReplayTrace] = {}
    for name, plan in plans.items():
        results[name], traces[name] = replay(model, plan_reference(plan), feedforward,
                                             geometry=geometry)
    verdicts = {name: checks(r) for name, r in results.items()}
    out_checks = [check(f"{name}.{k}", ok) for name, v in verdicts.items() for k, ok in v.items()]
    targets, headline, ratios = [], [], {}
    for scenario, (ident, closed) in pairs(results).items():
        ratios[scenario] = results[ident].energy / results[closed].energy
        targets.append(Target(f"{scenario}: identified plan's replayed energy against the "
                              "closed-form plan's", 100 * abs(ratios[scenario] - 1),
                              100 * IDENTIFIED_TOLERANCE, "%"))
        headline.append(Row(f"Replayed in MuJoCo ({scenario}): energy of the identified vs the "
                            "closed-form plan; smallest clearance of each",
                            f"{results[ident].energy:.4f} J vs {results[closed].energy:.4f} J "
                            f"({100 * (ratios[scenario] - 1):+.2f} %); "
                            f"{1e3 * results[ident].min_clearance:.1f} / "
                            f"{1e3 * results[closed].min_clearance:.1f} mm (threshold "
                            f"{1e3 * results[closed].threshold:.0f} mm)"))
    figure_dir = ctx.figures_dir
    replans = {name: list(plan.get("replan_times", [])) for name, plan in plans.items()
               if isinstance(plan, dict)}
    figures = [power_figure(traces, figure_dir / "replay_power.png", replans),
               tracking_figure(traces, figure_dir / "replay_tracking.png")]
    for name, trace in traces.items():
        if trace.clearance.size and results[name].threshold > 0:
            figures.append(clearance_per_link(
                trace, geometry.link_names, results[name].threshold,
                f"{robot}, {name}: clearance per link, replayed",
                figure_dir / f"replay_{name}_clearance.png"))
    videos = _videos(model, traces, Path(ctx.out_dir)) if ctx.video and not ctx.quick else []
    payload = {name: {**asdict(r), "energy_error": r.energy_error, "role": role(name),
                      "link_min_clearance_m": dict(zip(geometry.link_names,
                                                       traces[name].clearance.min(axis=0).tolist(),
                                                       strict=True))}
               for name, r in results.items()}
    results_json = {"robot": robot, "plans": payload, "identified_energy_ratio": ratios,
                    "videos": [Path(v).name for v in videos]}
    note = surface_note(model, geometry)
    return SectionResult(_markdown(robot, results, verdicts, ratios, note), results_json,
                         out_checks, targets, headline, figures)


def surface_note(model, geometry) -> str:
    """What separates the table's two clearance columns, with the scene's radii: the surface
    distance is MuJoCo's between the link capsules and the obstacle sphere."""
    probe = ClearanceProbe.of(model, geometry)
    if not probe.has_surface:
        return "No surface distance: the scene has no link capsules or no obstacle sphere."
    links = sorted({round(float(model.geom_size[g][0]) * 1e3, 1) for g in probe.link_geoms})
    obstacle = float(model.geom_size[probe.obstacle_geom][0]) * 1e3
    text = ("'min clearance centre–segment' is the planner's measure, from the obstacle's "
            "centre to each link; 'min surface distance' is MuJoCo's, between the scene's link "
            "capsules (radius " + " / ".join(f"{r:g}" for r in links) + " mm) and the obstacle "
            f"sphere (radius {obstacle:g} mm). ")
    if probe.radii:  # the capsules are the planner's: the first column is already less them
        return text + (f"The planner's distance is already to the capsule's surface: the two "
                       f"differ by the obstacle's radius, {obstacle:g} mm. λ bounds the first.")
    return text + ("The planner's links are lines (the first column is to their centre line): "
                   "the two differ by a capsule's radius plus the obstacle's, "
                   + " / ".join(f"{r + obstacle:g}" for r in links) + " mm. λ bounds the first.")


def _markdown(robot, results, verdicts, ratios, note: str = "") -> str:
    lines = [f"Scene of `{robot}`; MuJoCo forward simulation at 0.5 ms through one motor per "
             "joint, Pinocchio feedforward + PD. 'energy of plan, dense': the plan's torques "
             "integrated densely along it (the planner's own figure may be a coarse "
             "quadrature).", "",
             "| plan | energy planned (J) | energy of plan, dense (J) | energy replayed (J) "
             "| deviation from planned | min clearance centre–segment (mm) "
             "| min surface distance (mm) | λ (mm) | tracking RMS (mrad) | max error (mrad) "
             "| checks |", "|---|---|---|---|---|---|---|---|---|---|---|",
             *(table_row(name, r, verdicts[name]) for name, r in results.items()),
             *(["", note] if note else [])]
    for scenario, ratio in ratios.items():
        lines += ["", f"{scenario}: identified vs closed-form plan, replayed (true) energy "
                  f"{100 * (ratio - 1):+.2f} %."]
    return "\n".join(lines)


def _videos(model, traces: dict[str, ReplayTrace], out_dir: Path) -> list[str]:
    from harness.replay.video import render_video

    name = next((n for n in traces if role(n) == "closed-form"), next(iter(traces)))
    path = out_dir / f"replay_{name}.mp4"
    return [str(path)] if render_video(model, traces[name], path) else []
