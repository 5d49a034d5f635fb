"""Bench section: replay every plan in MuJoCo, closed-form and identified side by side.

Acceptance (issue #5) is checked per plan: tracking RMS <= 1 mrad, replayed
energy within 2 % of the planned energy, minimum centre-to-segment clearance
>= lambda - 5 mm when the plan avoids an obstacle (threshold > 0).
"""

from __future__ import annotations

import re
from dataclasses import asdict
from pathlib import Path

from harness.replay.figures import (
    clearance_figure,
    model_power_figure,
    path_figure,
    power_figure,
    tracking_figure,
)
from harness.replay.reference import plan_reference
from harness.replay.simulate import ReplayResult, ReplayTrace, replay
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, load_mujoco, load_pinocchio

TRACKING_LIMIT = 1e-3  # rad
ENERGY_TOLERANCE = 0.02  # relative
CLEARANCE_MARGIN = 0.005  # m


def role(name: str) -> str:
    """'closed-form', 'identified' or 'other' from a plan's name."""
    lowered = name.lower()
    if any(k in lowered for k in ("ident", "sparse", "sindy")):
        return "identified"
    if any(k in lowered for k in ("pinocchio", "closed", "analytic", "baseline")):
        return "closed-form"
    return "other"


def checks(result: ReplayResult) -> dict[str, bool]:
    """Acceptance checks of one replay."""
    out = {
        "tracking_rms_le_1mrad": result.tracking_rms <= TRACKING_LIMIT,
        "energy_within_2pct": abs(result.energy_error) <= ENERGY_TOLERANCE,
        # The planner's own figure may be a coarse quadrature (paper: N = 10 samples);
        # this separates replay fidelity from that quadrature error.
        "energy_within_2pct_of_dense_plan": abs(result.energy / result.energy_reference - 1)
        <= ENERGY_TOLERANCE,
    }
    if result.threshold > 0:
        out["clearance_ge_threshold_minus_5mm"] = (
            result.min_clearance >= result.threshold - CLEARANCE_MARGIN
        )
    return out


def comparison(results: dict[str, ReplayResult]) -> dict | None:
    """Identified vs closed-form: energy ratios (replayed and planned) and clearances."""
    by_role = {role(name): (name, r) for name, r in results.items()}
    if "identified" not in by_role or "closed-form" not in by_role:
        return None
    (ident_name, ident), (closed_name, closed) = by_role["identified"], by_role["closed-form"]
    return {
        "identified": ident_name,
        "closed_form": closed_name,
        "energy_ratio_replayed": ident.energy / closed.energy,
        "energy_ratio_planned": ident.energy_planned / closed.energy_planned,
        "min_clearance_identified": ident.min_clearance,
        "min_clearance_closed_form": closed.min_clearance,
    }


def table_row(name: str, r: ReplayResult, ok: dict[str, bool]) -> str:
    surface = "–" if r.surface_clearance is None else f"{r.surface_clearance * 1e3:.1f}"
    failed = [k for k, v in ok.items() if not v]
    verdict = "FAIL: " + ", ".join(failed) if failed else "pass"
    return (f"| {name} | {r.energy_planned:.4f} | {r.energy_reference:.4f} | {r.energy:.4f} "
            f"| {100 * r.energy_error:+.2f} % "
            f"| {r.min_clearance * 1e3:.1f} | {surface} | {r.threshold * 1e3:.0f} "
            f"| {r.tracking_rms * 1e3:.3f} | {r.max_tracking_error * 1e3:.3f} | {verdict} |")


def verdict_line(verdicts: dict[str, dict[str, bool]]) -> str:
    """One bold line: how many acceptance checks failed, and which."""
    total = sum(len(v) for v in verdicts.values())
    failed = [f"{name}: {k}" for name, v in verdicts.items() for k, ok in v.items() if not ok]
    if not failed:
        return f"All {total} acceptance checks passed."
    return f"**{len(failed)} of {total} acceptance checks failed** ({', '.join(failed)})."


def markdown(results: dict[str, ReplayResult], verdicts: dict, side: dict | None) -> str:
    step = ", ".join(sorted({f"{1e3 * r.timestep:g}" for r in results.values()}))
    lines = [
        verdict_line(verdicts), "",
        f"Each plan is executed by MuJoCo forward simulation ({step} ms steps) through the motor "
        "actuators, tracked by Pinocchio feedforward + PD; the obstacle moves as a mocap body. "
        "'energy planned' is the planner's own figure; 'energy of plan, dense' integrates "
        f"|Σ τ q̇| of the closed-form torques along the planned trajectory every {step} ms.",
        "",
        "| plan | energy planned [J] | energy of plan, dense [J] | energy replayed [J] "
        "| deviation from planned | min clearance "
        "centre–segment [mm] | min surface distance [mm] | λ [mm] | tracking RMS [mrad] "
        "| max error [mrad] | acceptance |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *(table_row(name, r, verdicts[name]) for name, r in results.items()),
    ]
    if side:
        lines += ["", f"Identified vs closed-form, replayed energy ratio "
                  f"**{side['energy_ratio_replayed']:.4f}** (planned "
                  f"{side['energy_ratio_planned']:.4f}): the identified model's plan spends "
                  f"{'more' if side['energy_ratio_replayed'] > 1 else 'no more'} energy here; "
                  "the paper's Fig. 11 found slightly more for the identified model."]
    return "\n".join(lines)


def run(out_dir: Path, quick: bool = False, plans: dict | None = None,
        video: bool = True) -> dict:
    """Replay plans {name: PLAN dict}; figures under out_dir/figures, videos in out_dir."""
    out_dir = Path(out_dir)
    if not plans:
        return {"markdown": "No plans to replay (the planning section returned none).",
                "results": {}, "figures": []}
    model = load_mujoco(DEFAULT_ROBOT, scene=True)
    feedforward = PinocchioModel(load_pinocchio(DEFAULT_ROBOT))
    results: dict[str, ReplayResult] = {}
    traces: dict[str, ReplayTrace] = {}
    for name, plan in plans.items():
        results[name], traces[name] = replay(model, plan_reference(plan), feedforward)
    verdicts = {name: checks(r) for name, r in results.items()}
    side = comparison(results)
    figures_dir = out_dir / "figures"
    threshold = next(iter(results.values())).threshold
    figures = [power_figure(traces, figures_dir / "replay_power.png"),
               clearance_figure(traces, threshold, figures_dir / "replay_clearance.png"),
               path_figure(traces, figures_dir / "replay_path3d.png"),
               tracking_figure(traces, figures_dir / "replay_tracking.png")]
    paper = _paper_pair(traces)
    if paper:
        figures.append(model_power_figure(paper, figures_dir / "replay_power_models.png"))
    videos = _videos(model, traces, out_dir) if video and not quick else []
    payload = {name: {**asdict(r), "energy_error": r.energy_error, "role": role(name),
                      "acceptance": verdicts[name]} for name, r in results.items()}
    failed = sum(not ok for v in verdicts.values() for ok in v.values())
    return {"markdown": markdown(results, verdicts, side),
            "results": {"plans": payload, "comparison": side, "videos": videos,
                        "acceptance_failed": failed},
            "figures": figures}


def _paper_pair(traces: dict[str, ReplayTrace]) -> dict[str, ReplayTrace] | None:
    """The paper scenario's closed-form and identified replays (paper Fig. 11), if both ran.
    Plans named 'paper_*' are preferred over other plans of the same role."""
    chosen = {}
    for wanted in ("closed-form", "identified"):
        names = [n for n in traces if role(n) == wanted]
        names.sort(key=lambda n: not n.lower().startswith("paper"))
        if not names:
            return None
        chosen[names[0]] = traces[names[0]]
    return chosen


def _video_subjects(traces: dict[str, ReplayTrace]) -> dict[str, ReplayTrace]:
    """The closed-form and identified replays (rendering is slow), else the first one."""
    chosen = {}
    for wanted in ("closed-form", "identified"):
        name = next((n for n in traces if role(n) == wanted), None)
        if name is not None:
            chosen[name] = traces[name]
    return chosen or dict([next(iter(traces.items()))])


def _videos(model, traces: dict[str, ReplayTrace], out_dir: Path) -> list[str]:
    from harness.replay.video import render_video

    written = []
    for name, trace in _video_subjects(traces).items():
        stem = re.sub(r"[^\w.-]", "_", name)
        path = out_dir / f"replay_{stem}.mp4"
        if render_video(model, trace, path):
            written.append(str(path))
    return written
