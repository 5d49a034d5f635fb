"""The world pushing a robot: plants of any arm pushed at known times, alone and
beside a load and a joint effect, closed by `closeloop --data`'s loop
(harness.closeloop.runs.run_runs) and scored against the pushes, which the loop never sees.

A draw (its seed) gives each run PUSHES pushes (harness.data.pushes): a body moved by joint
2 or later, a start in the run's own slot, a duration in DURATION s, a force of a uniform
direction and a magnitude in FORCE x the arm's weight. Each run is made twice with the same
seed, pushed and not (the same motion, sensor noise and estimates but for the pushes), on two
plants: the arm as declared and the arm carrying the payload case's load
(harness.closeloop.payload_case) with viscous friction on joint 2 (the bench's, sized by the
arm's mass). A third plant is the arm as declared held still at the middle of its joint ranges, pushed
(the issue's real arm was so). Measured data: MuJoCo forward simulation tracking generate's
excitation (or the held pose), NOISE torque noise (a fraction of each joint's torque spread;
at the held pose, where the torque hardly moves, the moving arm's same-seed noise in N m),
states estimated from the encoder. Two runs train, the third is held out.

Scored by harness.closeloop.push_scores against the pushes (found, onset, false events), and
the loaded plant's load and viscous friction named with the pushes against the same named
without them, and the loop on the pushed runs without looking for events (what the loop did
before events) beside it.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from harness.closeloop.arm_plants import LoadedVariant, write_arm_variant
from harness.closeloop.payload_case import loaded_variant
from harness.closeloop.push_scores import score_events
from harness.closeloop.runs import run_runs
from harness.data.excitation_file import Trajectory
from harness.data.generate import generate
from harness.data.pushes import Push
from harness.data.runs import Runs
from harness.robots.arm import Arm

SAMPLES, NOISE = 4000, 0.05  # 20 s at 200 Hz a run
RUNS = 3  # two train, the last is held out
PUSHES = 3  # a run
DURATION = (0.2, 1.0)  # s
FORCE = (0.15, 0.5)  # x the arm's weight (N)
EDGE = 1.5  # s kept free at each end of a run
REFERENCE_MASS = 18.0  # kg: the arm VISCOUS is sized for, as the bench's effects
VISCOUS = 0.8  # N m s/rad on joint 2


def arm_mass(arm: Arm) -> float:
    return float(sum(body.mass for body in arm.pinocchio.inertias))


def draw_pushes(arm: Arm, rng: np.random.Generator, duration: float) -> tuple[Push, ...]:
    """PUSHES pushes over a run of duration s, one a slot (module docstring)."""
    model = arm.mujoco
    bodies = sorted({int(b) for b in model.dof_bodyid[1:]})
    weight = arm_mass(arm) * 9.81
    slot = (duration - 2 * EDGE) / PUSHES
    out = []
    for k in range(PUSHES):
        length = float(rng.uniform(*DURATION))
        start = EDGE + k * slot + float(rng.uniform(0.0, max(slot - length - 0.5, 0.0)))
        direction = rng.normal(size=3)
        force = direction / np.linalg.norm(direction) * rng.uniform(*FORCE) * weight
        body = model.body(int(rng.choice(bodies))).name
        out.append(Push(body, round(start, 3), round(length, 3),
                        tuple(round(float(f), 3) for f in force)))
    return tuple(out)


def _named(loop) -> dict:
    """The load's mass and joint 2's viscous friction a loop named (None where not)."""
    effects = loop.to_json()["effects"]
    mass = next((e["mass"] for e in effects if e["effect"] == "payload"), None)
    viscous = next((e["coefficient"] for e in effects
                    if e["effect"] == "viscous" and e["joint"] == 2), None)
    return {"mass": mass, "viscous_2": viscous,
            "effects": [f"{e['effect']} j{e['joint']} {e['coefficient']:.4g}" for e in effects],
            "error_before": loop.error_before.tolist(), "error_after": loop.error_after.tolist()}


def held_pose(arm: Arm, samples: int) -> Trajectory:
    """The arm held still at the middle of its joint ranges (the issue's pushed arm was held
    in a static pose), samples at 200 Hz."""
    lo, hi = arm.position_limits
    pose = np.where(np.isfinite(lo) & np.isfinite(hi), (lo + hi) / 2, 0.0)
    t = np.arange(samples) / 200.0
    still = np.zeros((samples, arm.dof))
    return Trajectory(t, still + pose, still, still)


def _sensed(data, sigma: np.ndarray, seed: int):
    """data with Gaussian torque noise of std sigma (dof,) N m (the moving arm's sensor)."""
    noise = np.random.default_rng(seed + 7).normal(size=data.tau.shape) * sigma
    return replace(data, tau=data.tau_clean + noise, meta={**data.meta, "noise_nm": sigma.tolist()})


def _runs(datasets, name: str) -> Runs:
    arrays = {k: np.concatenate([getattr(d, k) for d in datasets])
              for k in ("q", "qd", "qdd", "tau", "tau_clean")}
    return Runs(arrays, tuple(d.meta for d in datasets),
                tuple(f"{name} run {i + 1}" for i in range(len(datasets))),
                tuple(len(d.q) for d in datasets), tuple(d.t for d in datasets))


def push_case(arm: Arm, seed: int, directory: Path, samples: int = SAMPLES,
              figure: Path | None = None) -> dict:
    """One draw on arm: the declared and the loaded plants, pushed and not, closed and scored
    (module docstring); figure: where to draw the loaded plant's first run's events."""
    rng = np.random.default_rng(seed)
    scale = arm_mass(arm) / REFERENCE_MASS
    load = loaded_variant(arm, "pushed_load")
    loaded = LoadedVariant((("viscous", 2, VISCOUS * scale),), payload=load.payload,
                           payload_offset=load.payload_offset,
                           payload_inertia=load.payload_inertia, name="pushed_load")
    declared = Arm.of(write_arm_variant(arm, LoadedVariant(name="pushed"), Path(directory)))
    plants = {"declared": declared, "loaded": Arm.of(write_arm_variant(arm, loaded,
                                                                       Path(directory))),
              "held": declared}
    out: dict = {"robot": arm.label, "seed": seed, "samples": samples, "noise": NOISE,
                 "true_mass": load.payload, "true_viscous_2": VISCOUS * scale, "plants": {}}
    sigmas: dict[int, np.ndarray] = {}  # the moving declared arm's sensor noise, per run
    for name, plant in plants.items():
        pushed, calm = [], []
        for i in range(RUNS):
            pushes = draw_pushes(plant, rng, samples / 200.0)
            run_seed = seed * 10 + i
            if name == "held":  # the moving arm's sensor noise, in N m
                motion, noise = held_pose(arm, samples), 0.0
            else:
                motion, noise = None, NOISE
            pair = [generate(plant, samples, noise, run_seed, "measured", 0.0, robot=arm,
                             pushes=p, excitation=motion) for p in (pushes, ())]
            if name == "held":
                pair = [_sensed(d, sigmas[i], run_seed) for d in pair]
            elif name == "declared":
                sigmas[i] = NOISE * pair[1].tau_clean.std(axis=0)
            pushed.append((pair[0], pushes))
            calm.append(pair[1])
        train = _runs([d for d, _ in pushed[:-1]], "pushed")
        held = _runs([pushed[-1][0]], "pushed")
        loop = run_runs(train, arm, validate=held)
        scores = [score_events(p, ev, d.truth["tau_external"], d.t, d.truth["tau_constraint"])
                  for (d, p), ev in zip(pushed, loop.found, strict=True)]
        quiet = run_runs(_runs(calm[:-1], "calm"), arm, validate=_runs(calm[-1:], "calm"))
        blind = run_runs(train, arm, validate=held, detect=False)
        if figure is not None and name == "loaded":
            from harness.closeloop.figures import events_figure

            drawn = events_figure(
                loop.found[0], Path(figure), pushed[0][1],
                f"{arm.label}, seed {seed}, loaded plant, run 1: the observer's estimate less "
                "the persistent effects; events shaded, pushes dashed, thresholds dotted")
            out["figure"] = Path(drawn).name  # its name: the same results wherever written
        out["plants"][name] = {
            "runs": scores, "pushed": _named(loop), "without_pushes": _named(quiet),
            "pushed_without_events": _named(blind),
            "false_events_without_pushes": sum(len(ev.events) for ev in quiet.found),
            "minutes": RUNS * samples / 200.0 / 60.0}
    return out
