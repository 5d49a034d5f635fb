"""Bench section: the arm planning section's plans replayed in MuJoCo (any arm but the
Lynxmotion).

The scene is built around the arm (harness.robots.scene: floor, light, mocap obstacle, one
motor per joint limited to the model's torque limits); tracking is the Lynxmotion's
(Pinocchio feedforward + PD at 0.5 ms, harness.replay.simulate). Checked per plan (the
replay section's checks): tracking RMS <= 1 mrad, replayed energy within 2 % of the plan's,
centre-to-link clearance >= lambda - 5 mm; and the identified model's plan replayed within
1 % of the closed-form plan's replayed (true) energy.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import numpy as np

from harness.replay.figures import power_figure, tracking_figure
from harness.replay.reference import plan_reference
from harness.replay.simulate import ReplayResult, ReplayTrace, replay
from harness.report.figures import plt, save_figure
from harness.robots.arm import arm_geometry
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from harness.robots.scene import replay_scene
from harness.sections.replay import checks, comparison, role, table_row, verdict_line

IDENTIFIED_TOLERANCE = 0.01  # replayed energy, identified plan vs closed-form plan


def clearance_per_link(trace: ReplayTrace, names, threshold: float, title: str,
                       path: Path) -> Path:
    """Centre-to-segment distance of every link to the obstacle over time, replayed."""
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for k, name in enumerate(names):
        ax.plot(trace.t, trace.clearance[:, k], color=f"C{k}", label=name)
    ax.axhline(threshold, color="k", lw=1, label=f"threshold λ = {threshold * 1e3:.0f} mm")
    ax.set(xlabel="time t [s]", ylabel="obstacle centre to link [m]", title=title,
           ylim=(0, max(4 * threshold, float(np.percentile(trace.clearance, 60)))))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return save_figure(fig, path)


def run(out_dir: Path, quick: bool = False, plans: dict | None = None, video: bool = True,
        robot: str = "ur5") -> dict:
    if not plans:
        return {"markdown": "No plans to replay (the arm planning section returned none).",
                "results": {}, "figures": []}
    model, geometry = replay_scene(robot), arm_geometry(robot)
    feedforward = PinocchioModel(load_pinocchio(robot))
    results: dict[str, ReplayResult] = {}
    traces: dict[str, ReplayTrace] = {}
    for name, plan in plans.items():
        results[name], traces[name] = replay(model, plan_reference(plan), feedforward,
                                             geometry=geometry)
    verdicts = {name: checks(r) for name, r in results.items()}
    side = comparison(results)
    acceptance = {f"{name}: {k}": v for name, c in verdicts.items() for k, v in c.items()}
    if side is not None:
        acceptance["identified_replayed_energy_within_1pct_of_closed_form"] = \
            abs(side["energy_ratio_replayed"] - 1) <= IDENTIFIED_TOLERANCE
    figure_dir = Path(out_dir) / "figures"
    threshold = next(iter(results.values())).threshold
    figures = [power_figure(traces, figure_dir / f"arm_replay_{robot}_power.png"),
               tracking_figure(traces, figure_dir / f"arm_replay_{robot}_tracking.png")]
    for name, trace in traces.items():
        figures.append(clearance_per_link(
            trace, geometry.link_names, threshold, f"{robot}, {name}: clearance per link, "
            "replayed", figure_dir / f"arm_replay_{name}_clearance.png"))
    videos = _videos(model, traces, Path(out_dir)) if video and not quick else []
    payload = {name: {**asdict(r), "energy_error": r.energy_error, "role": role(name),
                      "link_min_clearance_m": dict(zip(geometry.link_names,
                                                       traces[name].clearance.min(axis=0).tolist(),
                                                       strict=True))}
               for name, r in results.items()}
    return {"markdown": _markdown(robot, results, verdicts, side, acceptance),
            "results": {"robot": robot, "plans": payload, "comparison": side,
                        "videos": videos, "acceptance": acceptance},
            "figures": [str(f) for f in figures]}


def _markdown(robot, results, verdicts, side, acceptance) -> str:
    lines = [verdict_line(verdicts), "",
             f"Scene built around `{robot}` with MjSpec; MuJoCo forward simulation at 0.5 ms "
             "through one motor per joint, Pinocchio feedforward + PD.", "",
             "| plan | energy planned [J] | energy of plan, dense [J] | energy replayed [J] "
             "| deviation from planned | min clearance centre–segment [mm] "
             "| min surface distance [mm] | λ [mm] | tracking RMS [mrad] | max error [mrad] "
             "| acceptance |", "|---|---|---|---|---|---|---|---|---|---|---|",
             *(table_row(name, r, verdicts[name]) for name, r in results.items())]
    if side:
        ok = acceptance["identified_replayed_energy_within_1pct_of_closed_form"]
        lines += ["", f"Identified vs closed-form plan, replayed (true) energy: "
                  f"{100 * (side['energy_ratio_replayed'] - 1):+.2f} % "
                  f"({'within' if ok else 'outside'} {IDENTIFIED_TOLERANCE:.0%})."]
    return "\n".join(lines)


def _videos(model, traces: dict[str, ReplayTrace], out_dir: Path) -> list[str]:
    from harness.replay.video import render_video

    name = next((n for n in traces if role(n) == "closed-form"), next(iter(traces)))
    path = out_dir / f"arm_replay_{name}.mp4"
    return [str(path)] if render_video(model, traces[name], path) else []
