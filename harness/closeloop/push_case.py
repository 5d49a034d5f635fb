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

Scored: a push is found when an event overlaps it; its delay is the event's start minus the
push's, its onset error how far that start lies outside [the push's start, the first instant
its joint torque reached the detection's threshold] (onset_error); an event overlapping no push
is false; a push whose joint torque never reaches the
detection's threshold on any joint is `below threshold` (the physics hides it, not the
detector). The loaded plant's load and viscous friction named with the pushes against the
same named without them, and the loop on the pushed runs without looking for events (what the
loop did before events) beside it.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from harness.closeloop.arm_plants import LoadedVariant, write_arm_variant
from harness.closeloop.payload_case import loaded_variant
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
ONSET = 0.03  # s: the onset aim
AGREE = 0.05  # the load and the friction named with the pushes within 5 % of without


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


def onset_error(found: float, start: float, visible: float) -> float:
    """How far (s) an event's onset found lies outside [start, visible]: from a push's start
    to the first instant its joint torque reached the detection's threshold (its end where
    it never did). Before the start it is early (negative); within, no detector could tell
    the moment better (a push's joint torque may stay under the noise for a while after it
    starts, as the arm turns it toward the force), so 0; after, it is late by the time since
    the push became visible."""
    return min(found - start, 0.0) + max(found - visible, 0.0)


def score_events(pushes, found, external: np.ndarray, t: np.ndarray,
                 stops: np.ndarray | None = None) -> dict:
    """A run's events (identification.closeloop.events.Events) against its pushes and their
    true joint torque external (n, dof) N m at times t; stops (n, dof) N m: the torque of the
    plant's joint stops (MuJoCo's constraint force): an event no push overlaps where a stop
    reached the threshold is the world too (a push drove the joint onto its stop), counted
    apart, not as false."""
    found_pushes, delays, below, latency, onset = [], [], [], [], []
    for push in pushes:
        inside = np.flatnonzero((t >= push.start) & (t <= push.start + push.duration))
        seen = np.max(np.abs(external[inside]) / found.threshold, axis=1) >= 1.0
        hit = [e for e in found.events
               if e.start <= push.start + push.duration and e.end >= push.start]
        found_pushes.append(bool(hit))
        below.append(not seen.any())
        delays.append(hit[0].start - push.start if hit else None)
        latency.append(hit[0].start - t[inside[np.argmax(seen)]] if hit and seen.any() else None)
        visible = t[inside[np.argmax(seen)]] if seen.any() else push.start + push.duration
        onset.append(None if not hit else onset_error(hit[0].start, push.start, visible))
    unpushed = [e for e in found.events if not any(
        e.start <= p.start + p.duration and e.end >= p.start for p in pushes)]

    def at_stop(e) -> bool:
        if stops is None:
            return False
        inside = (t >= e.start) & (t <= e.end)
        return bool(inside.any() and np.any(np.abs(stops[inside]) >= found.threshold))
    false = [e for e in unpushed if not at_stop(e)]
    return {"pushes": [p.to_json() for p in pushes], "found": found_pushes, "delay": delays,
            "delay_from_threshold": latency, "onset_error": onset, "below_threshold": below,
            "false_events": len(false), "events_at_stops": len(unpushed) - len(false),
            "events": [e.to_json() for e in found.events]}


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


def summary(cases: list[dict]) -> dict:
    """Detection rate, false events per minute, onset delays, and the load and friction named
    with the pushes against without (with and without looking for events), over cases."""
    runs = [r for c in cases for p in c["plants"].values() for r in p["runs"]]
    found = [f for r in runs for f in r["found"]]
    visible = [f for r in runs for f, b in zip(r["found"], r["below_threshold"], strict=True)
               if not b]
    delays = [d for r in runs for d in r["delay"] if d is not None]
    latency = [d for r in runs for d in r["delay_from_threshold"] if d is not None]
    onsets = [d for r in runs for d in r["onset_error"] if d is not None]
    minutes = sum(p["minutes"] for c in cases for p in c["plants"].values())
    false = sum(r["false_events"] for r in runs)
    stops = sum(r["events_at_stops"] for r in runs)
    quiet_false = sum(p["false_events_without_pushes"] for c in cases for p in c["plants"].values())

    def drift(key: str, which: str) -> list[float | None]:
        out = []
        for c in cases:
            p = c["plants"]["loaded"]
            a, b = p[which][key], p["without_pushes"][key]
            out.append(None if a is None or b is None else abs(a - b) / abs(b))
        return out

    worse = [(c["robot"], c["seed"], name, j + 1)
             for c in cases for name, p in c["plants"].items()
             for j, (a, b) in enumerate(zip(p["pushed"]["error_after"],
                                            p["pushed"]["error_before"], strict=True)) if a > b]
    return {"pushes": len(found), "found": sum(found), "above_threshold": len(visible),
            "found_above_threshold": sum(visible),
            "false_events": false, "false_per_minute": false / minutes if minutes else 0.0,
            "events_at_stops": stops,
            "false_events_without_pushes": quiet_false,
            "false_per_minute_without_pushes": quiet_false / minutes if minutes else 0.0,
            "false_per_minute_all": (false + quiet_false) / (2 * minutes) if minutes else 0.0,
            "delay_median": float(np.median(delays)) if delays else None,
            "delay_max_abs": float(np.max(np.abs(delays))) if delays else None,
            "delay_from_threshold_max_abs": float(np.max(np.abs(latency))) if latency else None,
            "onset_error_max_abs": float(np.max(np.abs(onsets))) if onsets else None,
            "onset_within": sum(abs(d) <= ONSET for d in onsets), "onsets": len(onsets),
            "mass_drift": drift("mass", "pushed"), "viscous_drift": drift("viscous_2", "pushed"),
            "mass_drift_without_events": drift("mass", "pushed_without_events"),
            "viscous_drift_without_events": drift("viscous_2", "pushed_without_events"),
            "worse_joints": worse}


def _worst(values) -> float | None:
    """The largest drift, None (missed) when any effect went unnamed."""
    return None if not values or any(v is None for v in values) else 100 * max(values)


def push_targets(s: dict, where: str) -> list:
    """The issue's aims on the summary s of cases named by where."""
    from harness.report.results import Target

    return [Target(f"pushes found, of those whose joint torque reached the threshold "
                   f"({where}; {s['found']} of all {s['pushes']})", s["found_above_threshold"],
                   s["above_threshold"], "pushes", lower_is_better=False),
            Target(f"false events per minute, pushed and calm runs ({where})",
                   s["false_per_minute_all"], 0.0, "/min"),
            Target(f"largest onset error of a found push: before its start or after its joint "
                   f"torque first reached the threshold ({where}; {s['onset_within']} of "
                   f"{s['onsets']} within {1e3 * ONSET:.0f} ms)",
                   None if s["onset_error_max_abs"] is None else 1e3 * s["onset_error_max_abs"],
                   1e3 * ONSET, "ms",
                   note=("from the push's start alone: "
                         + ("-" if s["delay_max_abs"] is None
                            else f"{1e3 * s['delay_max_abs']:.0f} ms") + "; from the first "
                         "threshold crossing alone: "
                         + ("-" if s["delay_from_threshold_max_abs"] is None
                            else f"{1e3 * s['delay_from_threshold_max_abs']:.0f} ms")
                         + " (each counts what the physics hides or an early detection)")),
            Target(f"load's mass named with the pushes against without, worst draw ({where})",
                   _worst(s["mass_drift"]), 100 * AGREE, "%"),
            Target(f"joint 2's viscous friction named with the pushes against without, worst "
                   f"draw ({where})", _worst(s["viscous_drift"]), 100 * AGREE, "%")]


def push_markdown(cases: list[dict], s: dict) -> str:
    """The cases in a table and the summary in a paragraph."""
    def fig(v, scale=100, unit="%"):
        return "not named" if v is None else f"{scale * v:.2f} {unit}"

    md = ["| arm | seed | plant | pushes found | onset from the push's start (ms) | false events "
          "| named with pushes | without pushes | pushed, no events looked for |",
          "|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for name, p in c["plants"].items():
            found = sum(sum(r["found"]) for r in p["runs"])
            total = sum(len(r["found"]) for r in p["runs"])
            hidden = sum(sum(r["below_threshold"]) for r in p["runs"])
            delays = ", ".join(f"{1e3 * d:+.0f}" for r in p["runs"] for d in r["delay"]
                               if d is not None)
            false = sum(r["false_events"] for r in p["runs"])
            md.append(f"| {c['robot']} | {c['seed']} | {name} | {found} of {total} ({hidden} "
                      f"below the threshold) | {delays} | "
                      f"{false} (calm runs: {p['false_events_without_pushes']}) | "
                      + " | ".join(", ".join(p[k]["effects"]) or "none"
                                   for k in ("pushed", "without_pushes", "pushed_without_events"))
                      + " |")
    md += ["", f"Over {len(cases)} draws: {s['found']} of {s['pushes']} pushes found "
           f"({s['found_above_threshold']} of the {s['above_threshold']} whose joint torque "
           f"reached the threshold); {s['false_events']} false events on pushed runs (and "
           f"{s['events_at_stops']} where no push acted but a push had driven a joint onto its "
           "stop, whose torque reached the threshold: the world too, not counted false) and "
           f"{s['false_events_without_pushes']} on the same runs unpushed; onset from the push's "
           f"start median {fig(s['delay_median'], 1e3, 'ms')}, largest "
           f"{fig(s['delay_max_abs'], 1e3, 'ms')}; outside [start, first threshold crossing] "
           f"largest {fig(s['onset_error_max_abs'], 1e3, 'ms')}; "
           "the load's mass with the pushes against without: "
           + ", ".join(fig(v) for v in s["mass_drift"]) + " (without looking for events: "
           + ", ".join(fig(v) for v in s["mass_drift_without_events"]) + "); joint 2's viscous "
           "friction: " + ", ".join(fig(v) for v in s["viscous_drift"]) + " (without: "
           + ", ".join(fig(v) for v in s["viscous_drift_without_events"]) + "). Joints whose "
           "held-out error after the loop is above before: "
           + (", ".join(f"{r} seed {sd} {n} joint {j}" for r, sd, n, j in s["worse_joints"])
              or "none") + "."]
    return "\n".join(md)
