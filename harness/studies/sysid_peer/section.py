"""Study `sysid_peer`: mujoco.sysid (harness.studies.sysid_peer.peer) beside the project's
`identify`, on the shipped real Panda log (data/panda_gaz2019, ingested as the bench's
real-data section ingests it) with its last HOLDOUT held out: each fitted on the first part,
judged on the held-out part (harness.studies.sysid_peer.scoring): torque error per joint,
rollout error at 0.1 and 0.5 s, each body's physical consistency, the fit's wall time.

The peer is the toolbox's fit on 0.5 s rollout windows tiling the fitted part, from the robot's
file, stopped at BUDGET s of wall time (its optimizer has no time limit of its own). The
project's figures are what `identify --robot panda` and `predict --rollout 0.1,0.5
--rollout-holdout 0.25` give on the same ingested log (the docs' commands).

Quick form (the smoke test): the peer on QUICK_WINDOWS windows for QUICK_BUDGET s.
"""

from __future__ import annotations

import time

import numpy as np

from data import DATA
from harness.bench.real_data.rollout import rollout_figures
from harness.data.ingest import ingest
from harness.identify.fits import arm_identification
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm
from harness.studies.sysid_peer.peer import PeerFit, Windows, fit_peer
from harness.studies.sysid_peer.scoring import Scored, held_slice, score_mujoco
from identification.identify import identify
from identification.metrics import rel_error
from identification.physical import CONSISTENT_TOL

LOG = DATA / "panda_gaz2019" / "panda_gaz2019.csv.gz"
ROBOT = "panda"
RATE = 100.0  # Hz, as the real-data section hands the log over
HOLDOUT = 0.25
WINDOW = 0.5  # s, the peer's rollout windows
BUDGET = 300.0  # s of wall time for the peer's fit (the peer ran 373 s on a 6-joint arm)
QUICK_BUDGET, QUICK_WINDOWS = 5.0, 2


def run(ctx: Context) -> SectionResult:
    arm = Arm.of(ROBOT)
    a = ingest(LOG, arm, RATE, None).arrays
    split = held_slice(len(a["q"]), HOLDOUT).start
    samples = int(round(WINDOW / np.median(np.diff(a["t"]))))
    stop = QUICK_WINDOWS * samples + 1 if ctx.quick else split
    peer = fit_peer(arm, a["t"], a["q"], a["qd"], a["tau"], Windows(0, stop, samples),
                    QUICK_BUDGET if ctx.quick else BUDGET)
    scored = [nominal_and_identified(arm, a)[k] for k in ("nominal", "identified")]
    scored.append(score_mujoco("mujoco.sysid", peer.model, peer.bias, a, HOLDOUT,
                               peer.parameters, peer.seconds, "torquebench study sysid_peer"))
    results = {"log": str(LOG.relative_to(DATA.parent)), "holdout": HOLDOUT,
               "peer": peer_json(peer), "models": [s.to_json() for s in scored]}
    checks = [check("peer_bodies_consistent", bool(np.min(scored[2].min_eigenvalues)
                                                   >= -CONSISTENT_TOL),
                    f"smallest pseudo-inertia eigenvalue {np.min(scored[2].min_eigenvalues):.3g} "
                    "(the toolbox's log-Cholesky parameters keep it positive)")]
    return SectionResult(markdown(scored, peer, ctx.quick), results, checks,
                         [] if ctx.quick else targets(scored[1], scored[2]))


def nominal_and_identified(arm: Arm, a: dict) -> dict[str, Scored]:
    """The robot's file and `identify --robot panda` (its wall time), scored as `predict`
    scores them: the model's torque plus its offset, its exported MJCF rolled out."""
    held = held_slice(len(a["q"]), HOLDOUT)
    states = (a["q"], a["qd"], a["qdd"])
    start = time.perf_counter()
    _, regressor = arm_identification(arm, arm.dof, prior="nominal", measured=True)
    result = identify(*states, a["tau"], arm.library, HOLDOUT, regressor=regressor)
    seconds = time.perf_counter() - start
    rollout = rollout_figures(arm, result, a, HOLDOUT)
    torque = {"nominal": arm.nominal.torque(*(x[held] for x in states)),
              "identified": result.model.torque(*(x[held] for x in states))
              + result.model.offsets}
    params = np.asarray(result.physical["standard_parameters"], float)
    return {name: Scored(name if name == "nominal" else "identify (exported MJCF)",
                         rel_error(torque[name], a["tau"][held]), rollout[name]["windows"],
                         *((None, None) if name == "nominal" else
                           (np.asarray(result.physical["min_pseudo_eigenvalues"]),
                            params[::10])),
                         None if name == "nominal" else seconds, rollout[name]["command"])
            for name in ("nominal", "identified")}


def peer_json(peer: PeerFit) -> dict:
    return {"parameters": peer.count, "evaluations": peer.evaluations, "stopped": peer.stopped,
            "cost_start": peer.cost_start, "cost": peer.cost,
            "standard_parameters": peer.parameters.tolist(), "bias": peer.bias.tolist(),
            "timing": {"seconds": peer.seconds}}


def _window(s: Scored, seconds: float) -> dict:
    return next(w for w in s.rollout if abs(w["seconds"] - seconds) < 1e-9)


def targets(ours: Scored, peer: Scored) -> list[Target]:
    """The issue's targets on the real log: torque and 0.5 s rollout error at or below the
    peer's on every joint (joints where it is not: the gap), the peer's fit time."""
    q_ours, q_peer = _window(ours, 0.5)["q_rms"], _window(peer, 0.5)["q_rms"]
    rollout_worse = (len(ours.torque_error) if q_ours is None or q_peer is None
                     else int(np.sum(np.asarray(q_ours) > np.asarray(q_peer))))
    return [Target("joints where identify's held-out torque error is above mujoco.sysid's",
                   int(np.sum(ours.torque_error > peer.torque_error)), 0, "joints"),
            Target("joints where identify's exported MJCF's 0.5 s rollout q RMS is above "
                   "mujoco.sysid's (unrefined)", rollout_worse, 0, "joints")]


def markdown(scored: list[Scored], peer: PeerFit, quick: bool) -> str:
    dof = len(scored[0].torque_error)

    def joints(x, fmt="{:.3g}"):
        return " | ".join("-" if x is None else fmt.format(v) for v in
                          (x if x is not None else [None] * dof))
    lines = [f"Real Panda log (data/panda_gaz2019), last {HOLDOUT:.0%} held out. mujoco.sysid: "
             f"{peer.count} parameters, {peer.evaluations} rollouts of its windows, stopped: "
             f"{peer.stopped} after {peer.seconds:.0f} s, its cost {peer.cost_start:.4g} -> "
             f"{peer.cost:.4g}" + (" (quick: 2 windows, a few seconds)" if quick else "") + ".",
             "", "| model | what | " + " | ".join(f"joint {j + 1}" for j in range(dof))
             + " | fit (s) |", "|---|---|" + "---|" * (dof + 1)]
    for s in scored:
        fit = "-" if s.seconds is None else f"{s.seconds:.1f}"
        lines.append(f"| {s.name} | torque error | {joints(s.torque_error)} | {fit} |")
        for w in s.rollout:
            lines.append(f"| {s.name} | rollout {w['seconds']:g} s q RMS (rad), "
                         f"{w['diverged']}/{w['windows']} diverged | {joints(w['q_rms'])} | |")
        if s.masses is not None:
            lines.append(f"| {s.name} | body mass (kg), total {np.sum(s.masses):.2f} | "
                         f"{joints(s.masses, '{:.2f}')} | |")
    return "\n".join(lines)
