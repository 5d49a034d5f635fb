"""The study's simulated UR5 plant on several draws (harness.studies.sysid_peer.plant.DRAWS):
per draw, where identify and its refinement stand against the peer on the held-out part
(torque error, 0.5 s rollout q RMS, per joint), and the worst case across draws as targets."""

from __future__ import annotations

import numpy as np

from harness.report.results import Target
from harness.studies.sysid_peer.scoring import Scored, joints_worse, window

JUDGED = 0.5  # s, the rollout window the targets judge


def draw_figures(seeds: tuple[int, int], ours: Scored, peer: Scored, refined: Scored,
                 still: list[dict]) -> dict:
    """One draw's figures: its seeds, per joint the 0.5 s rollout q RMS and torque error of
    identify, the peer and the refinement (and the rollout of no model, scoring.
    constant_velocity's), and the joints where each of ours is above the peer's."""
    def q(s: Scored):
        return window(s, JUDGED)["q_rms"]
    return {"seeds": list(seeds),
            "rollout_q_rms": {"identify": q(ours), "peer": q(peer), "refined": q(refined),
                              "constant_velocity": next(
                                  w["q_rms"] for w in still if w["seconds"] == JUDGED)},
            "torque_error": {"identify": ours.torque_error.tolist(),
                             "peer": peer.torque_error.tolist(),
                             "refined": refined.torque_error.tolist()},
            "joints_above_peer": {
                "identify_torque": int(np.sum(ours.torque_error > peer.torque_error)),
                "refined_torque": int(np.sum(refined.torque_error > peer.torque_error)),
                "identify_rollout": joints_worse(ours, peer, JUDGED),
                "refined_rollout": joints_worse(refined, peer, JUDGED)}}


def _ratio(draw: dict, ours: str, kind: str) -> float:
    """The largest per-joint ratio of ours to the peer's figure (inf: a rollout diverged)."""
    figures = draw[kind]
    if figures[ours] is None or figures["peer"] is None:
        return float("inf")
    return float(np.max(np.asarray(figures[ours]) / np.asarray(figures["peer"])))


def _joints(n: int) -> str:
    return f"{n} joint" + ("" if n == 1 else "s")


def draws_markdown(draws: list[dict]) -> list[str]:
    """Per draw: the joints where identify and the refinement are above the peer, and the
    largest per-joint ratio to the peer's figure; the worst case across draws."""
    lines = [f"Per plant draw, on the held-out part: joints (of 6) where the model's figure is "
             f"above mujoco.sysid's, and its largest per-joint ratio to the peer's; rollout: "
             f"q RMS over {JUDGED:g} s windows.", "",
             "| seeds | refined rollout | refined torque | identify rollout | identify torque |",
             "|---|---|---|---|---|"]

    def cell(d: dict, ours: str, kind: str, key: str) -> str:
        return f"{_joints(d['joints_above_peer'][key])}, x{_ratio(d, ours, kind):.3g}"
    columns = (("refined", "rollout_q_rms", "refined_rollout"),
               ("refined", "torque_error", "refined_torque"),
               ("identify", "rollout_q_rms", "identify_rollout"),
               ("identify", "torque_error", "identify_torque"))
    for d in draws:
        lines.append(f"| {d['seeds'][0]}, {d['seeds'][1]} | "
                     + " | ".join(cell(d, *c) for c in columns) + " |")
    worst = [f"{_joints(max(d['joints_above_peer'][key] for d in draws))}, "
             f"x{max(_ratio(d, ours, kind) for d in draws):.3g}" for ours, kind, key in columns]
    lines.append("| worst | " + " | ".join(worst) + " |")
    return lines


def draws_targets(draws: list[dict]) -> list[Target]:
    """The refinement (and identify's torque) at or below the peer on every joint of every
    draw: the worst draw's count of joints above it (the gap)."""
    note = (f"worst of {len(draws)} plants drawn once (seeds in harness.studies.sysid_peer."
            "plant.DRAWS); no setting was chosen on them")
    head = f"ur5, worst of {len(draws)} plants: joints where"
    return [Target(f"{head} identify --refine rollout's 0.5 s rollout q RMS is above "
                   "mujoco.sysid's", max(d["joints_above_peer"]["refined_rollout"]
                                         for d in draws), 0, "joints", note=note),
            Target(f"{head} identify --refine rollout's held-out torque error is above "
                   "mujoco.sysid's", max(d["joints_above_peer"]["refined_torque"]
                                         for d in draws), 0, "joints", note=note),
            Target(f"{head} identify's held-out torque error is above mujoco.sysid's",
                   max(d["joints_above_peer"]["identify_torque"] for d in draws), 0, "joints",
                   note=note)]
