"""Study `sysid_peer`: mujoco.sysid (harness.identify.rollout_fit) beside the project's
`identify`, and `identify --refine rollout` (harness.identify.refine), on logs each
fitted on its first part and judged on its last HOLDOUT (harness.studies.sysid_peer.scoring):
torque error per joint, rollout error at 0.1 and 0.5 s, each body's physical consistency and
mass, the fit's wall time.

- the shipped real Panda log (data/panda_gaz2019), ingested as the bench's real-data section
  ingests it;
- a simulated UR5 plant with a ground truth (harness.studies.sysid_peer.plant), its bodies'
  true masses beside the fitted ones, on each of the plant's draws (plant.DRAWS), the worst
  case across them judged (harness.studies.sysid_peer.draws).

The peer is the toolbox's fit of the robot's file on 0.5 s rollout windows tiling the fitted
part, stopped after PEER_ROLLOUTS rollouts of a window (a budget the same on every machine;
its wall time is reported); the refinement starts from the identified model's exported MJCF
and stops after REFINE_ROLLOUTS. The project's own figures are what `identify` and `predict
--rollout 0.1,0.5 --rollout-holdout 0.25` give on the same log (docs/identification.md).

Quick form (the smoke test): the Panda log alone, two windows, QUICK_ROLLOUTS each fit.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from data import DATA
from harness.bench.real_data.rollout import rollout_figures
from harness.data.ingest import ingest
from harness.identify.fits import arm_identification
from harness.identify.refine import WINDOW, refine_rollout
from harness.identify.rollout_fit import RolloutFit, Windows, fit_peer
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm
from harness.studies.sysid_peer.draws import draw_figures, draws_markdown, draws_targets
from harness.studies.sysid_peer.plant import DRAWS, plant_log
from harness.studies.sysid_peer.scoring import (
    Scored,
    constant_velocity,
    held_slice,
    joints_worse,
    score_mujoco,
)
from identification.closeloop.closed.offsets import held_out_offset
from identification.identify import identify
from identification.metrics import rel_error
from identification.model import model_payload
from identification.physical import CONSISTENT_TOL

LOG = DATA / "panda_gaz2019" / "panda_gaz2019.csv.gz"
RATE = 100.0  # Hz, as the real-data section hands the log over
HOLDOUT = 0.25
PEER_ROLLOUTS = 2000  # ~20 finite-difference Jacobians of 98 columns; about 300 s here on the
# Panda log (the peer ran 373 s on a 6-joint arm)
REFINE_ROLLOUTS = 400  # ~4 Jacobians: about what identify --refine rollout's 60 s allows here
QUICK_ROLLOUTS, QUICK_WINDOWS = 110, 2
HELD = {"kind": "last_fraction", "fraction": HOLDOUT}
COMMANDS = {"panda": ("torquebench ingest --csv data/panda_gaz2019/panda_gaz2019.csv.gz "
                      "--robot panda --rate 100 --out panda.npz; torquebench identify --data "
                      "panda.npz --robot panda --refine rollout --out model.json"),
            "ur5": "torquebench study sysid_peer"}


def run(ctx: Context) -> SectionResult:
    with tempfile.TemporaryDirectory() as folder:
        cases = [("panda", "real Panda log (data/panda_gaz2019)", _panda, None)]
        if not ctx.quick:
            cases += [(_draw_name(k, seeds), f"simulated UR5 plant (bodies x [0.8, 1.2], "
                       f"friction), seeds {seeds[0]}, {seeds[1]}",
                       lambda seeds=seeds: _plant(Path(folder), seeds), seeds)
                      for k, seeds in enumerate(DRAWS)]
        md, results, checks, goals, draws = [], {}, [], [], []
        for name, words, load, seeds in cases:
            arrays, arm, truth = load()
            scored, fits = case(arm, arrays, ctx.quick)
            still = constant_velocity(arrays, HOLDOUT)
            results[name] = {"peer": fits[0].to_json(), "refined": fits[1],
                             "models": [s.to_json() for s in scored],
                             "constant_velocity": still,
                             "truth_masses": None if truth is None
                             else truth[:10 * arm.dof:10].tolist()}
            md += [f"### {words}", "", *markdown(scored, fits, truth, ctx.quick, still), ""]
            checks += [check(f"{name}: {s.name}: bodies physically consistent",
                                 bool(np.min(s.min_eigenvalues) >= -CONSISTENT_TOL),
                                 f"smallest pseudo-inertia eigenvalue "
                                 f"{np.min(s.min_eigenvalues):.3g}") for s in scored[2:]]
            if not ctx.quick and name in ("panda", "ur5"):
                goals += targets(name, *scored[1:])
            if seeds is not None:
                draws.append(draw_figures(seeds, *scored[1:], still))
        if draws:
            results["ur5_draws"] = draws
            md += [f"### the UR5 plant on {len(draws)} draws", "", *draws_markdown(draws), ""]
            goals += draws_targets(draws)
    results["commands"] = COMMANDS
    return SectionResult("\n".join(md).rstrip(), results, checks, goals)


def _draw_name(k: int, seeds: tuple[int, int]) -> str:
    """The results' key of plant draw k: 'ur5' for the first (the study's one plant before
    more were drawn), 'ur5_<perturbation seed>_<data seed>' for the others."""
    return "ur5" if k == 0 else f"ur5_{seeds[0]}_{seeds[1]}"


def _plant(folder: Path, seeds: tuple[int, int]) -> tuple[dict, Arm, np.ndarray]:
    arrays, truth, robot = plant_log(folder, seeds)
    return arrays, robot, truth


def _panda() -> tuple[dict, Arm, None]:
    arm = Arm.of("panda")
    return ingest(LOG, arm, RATE, None).arrays, arm, None


def case(arm: Arm, a: dict, quick: bool) -> tuple[list[Scored], tuple]:
    """The four models on one log: the robot's file, identify, the peer, the refinement."""
    split = held_slice(len(a["q"]), HOLDOUT).start
    samples = int(round(WINDOW / np.median(np.diff(np.ravel(a["t"])))))
    stop = QUICK_WINDOWS * samples + 1 if quick else split
    budget = QUICK_ROLLOUTS if quick else PEER_ROLLOUTS
    peer = fit_peer(arm, a["t"], a["q"], a["qd"], a["tau"], [Windows(0, stop, samples)],
                    np.inf, budget)
    scored, result = nominal_and_identified(arm, a)
    scored.append(score_mujoco("mujoco.sysid", peer.model, peer.bias, a, HOLDOUT,
                               peer.parameters, peer.seconds, "torquebench study sysid_peer"))
    refined, record = refine_rollout(model_payload(result, arm.record, HELD, "tau"), arm,
                                     a["t"], a["q"], a["qd"], a["tau"], [(0, stop)],
                                     _offset(result), np.inf, None,
                                     QUICK_ROLLOUTS if quick else REFINE_ROLLOUTS)
    scored.append(score_mujoco("identify --refine rollout", refined.model, refined.bias, a,
                               HOLDOUT, refined.parameters, refined.seconds + scored[1].seconds,
                               "identify --refine rollout"))
    return scored, (peer, record, refined)


def _offset(result) -> np.ndarray:
    """The sensor offset `predict` scores a run the model was not trained on with."""
    return held_out_offset(result.model, np.asarray(result.sensor_offsets()["new_run"], float))


def nominal_and_identified(arm: Arm, a: dict) -> tuple[list[Scored], object]:
    """The robot's file and `identify` (its wall time), scored as `predict` scores them: the
    model's torque plus its offset, its exported MJCF rolled out; and the identification."""
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
    return [Scored(name if name == "nominal" else "identify (exported MJCF)",
                   rel_error(torque[name], a["tau"][held]), rollout[name]["windows"],
                   *((None, arm.nominal.atom_parameters()[:10 * arm.dof:10])
                     if name == "nominal" else
                     (np.asarray(result.physical["min_pseudo_eigenvalues"]), params[::10])),
                   None if name == "nominal" else seconds, rollout[name]["command"])
            for name in ("nominal", "identified")], result


def targets(name: str, ours: Scored, peer: Scored, refined: Scored) -> list[Target]:
    """Torque and 0.5 s rollout error at or below the peer's on every joint (the joints where
    not: the gap), the refinement's wall time on the Panda."""
    note = ("development data: the refinement's region (rollout_model.NEAR) was set after the "
            "toolbox's wide bounds failed on this log" if name == "panda"
            else "plant drawn once (seeds in harness.studies.sysid_peer.plant); the region was "
            "set on the Panda log, not on this plant")
    out = [Target(f"{name}: joints where identify's held-out torque error is above "
                  "mujoco.sysid's", int(np.sum(ours.torque_error > peer.torque_error)), 0,
                  "joints", note=note),
           Target(f"{name}: joints where identify --refine rollout's held-out torque error is "
                  "above mujoco.sysid's", int(np.sum(refined.torque_error > peer.torque_error)),
                  0, "joints", note=note),
           Target(f"{name}: joints where identify --refine rollout's 0.5 s rollout q RMS is "
                  "above mujoco.sysid's", joints_worse(refined, peer, 0.5), 0, "joints", note=note),
           Target(f"{name}: joints where identify's exported MJCF (unrefined) rolls out worse "
                  "than mujoco.sysid at 0.5 s", joints_worse(ours, peer, 0.5), 0, "joints", note=note)]
    if name == "panda":
        out.append(Target("panda: identify + its refinement, wall time (REFINE_ROLLOUTS "
                          "rollouts)", refined.seconds, 60.0, "s", timing=True))
    return out


def markdown(scored: list[Scored], fits: tuple, truth, quick: bool, still: list[dict]
             ) -> list[str]:
    dof = len(scored[0].torque_error)
    peer, _, refined = fits

    def joints(x, fmt="{:.3g}"):
        return " | ".join("-" if v is None else fmt.format(v)
                          for v in (x if x is not None else [None] * dof))

    def fit_words(f: RolloutFit) -> str:
        return (f"{f.count} parameters, {f.windows} windows, {f.evaluations} rollouts of a "
                f"window, stopped: {f.stopped}, {f.seconds:.0f} s, its cost {f.cost_start:.4g} "
                f"-> {f.cost:.4g}")
    lines = [f"Last {HOLDOUT:.0%} held out. mujoco.sysid: {fit_words(peer)}. identify --refine "
             f"rollout (from the exported MJCF): {fit_words(refined)}"
             + (" (quick: two windows)" if quick else "") + ".", "",
             "| model | what | " + " | ".join(f"joint {j + 1}" for j in range(dof))
             + " | fit (s) |", "|---|---|" + "---|" * (dof + 1)]
    if truth is not None:
        masses = truth[:10 * dof:10]
        lines.append(f"| plant (truth) | body mass (kg), total {np.sum(masses):.2f} | "
                     f"{joints(masses, '{:.2f}')} | |")
    for s in scored:
        fit = "-" if s.seconds is None else f"{s.seconds:.1f}"
        lines.append(f"| {s.name} | torque error | {joints(s.torque_error)} | {fit} |")
        for w in s.rollout:
            lines.append(f"| {s.name} | rollout {w['seconds']:g} s q RMS (rad), "
                         f"{w['diverged']}/{w['windows']} diverged | {joints(w['q_rms'])} | |")
        lines.append(f"| {s.name} | body mass (kg), total {np.sum(s.masses):.2f} | "
                     f"{joints(s.masses, '{:.2f}')} | |")
    for w in still:
        lines.append(f"| no model: q0 + qd0 t | rollout {w['seconds']:g} s q RMS (rad) | "
                     f"{joints(w['q_rms'])} | |")
    return lines
