"""The bench's payload case: the arm carrying a load no model declares, closed on
its data by `closeloop --data`'s loop (harness.closeloop.runs.run_runs), scored against the
load the plant carries (its last body's inertia minus the arm's, never seen by the loop).

The load is a gripper-like body: LOAD_MASS kg for an 18 kg arm (scaled by the arm's mass),
its centre of mass LOAD_OFFSET m from the flange, with a rotational inertia. The data are
inverse dynamics at NOISE torque noise with generate's default sensor bias, on SEED.

With `load_friction` mu > 0 the wrist's joints (the last three) also carry dry friction that
grows with the load, mu |L_j| sat(qd_j / FRICTION_EPS), L the loaded plant's rigid-body torque
(Pinocchio on its MJCF): MuJoCo's joints have no such friction, so it is added to the
torque the simulator gives, as a real gearbox adds it to what the motor must supply.

The unloaded level: the declared model's RMS error (N m) on the same motion run by the arm
without the load (its own plant), under the loaded run's sensor noise in N m (a sensor's
noise does not grow with the load; generate's is a fraction of each joint's torque), drawn
anew (seed SEED + 1) and scored as the loaded run is; the loop's model on the loaded run is
held to it on the joints the load acts on (its torque at least LOAD_SHARE of the joint's).
In N m, not relative: the load raises the torque a relative error divides by.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.closeloop.arm_plants import LoadedVariant, write_arm_variant
from harness.closeloop.runs import run_runs
from harness.data.generate import generate
from harness.data.runs import Runs
from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from identification.closeloop.candidates.payload import describe
from identification.closeloop.closed.offsets import run_tail, scored_error

# the case's draws: drawn once on 2026-12-07 (random.SystemRandom().randrange(10_000)) and
# written here; no setting of the loop or of this case was chosen on them. The seed 8123 the
# case was developed on (its load-friction candidate, its quick sample count) scores nothing.
SEEDS = (6610, 6589, 3771)
SEED = SEEDS[0]  # the bench's draw
SAMPLES, NOISE = 3000, 0.05
REFERENCE_MASS = 18.0  # kg: the arm LOAD_MASS is sized for (a UR5 or a Panda)
LOAD_MASS = 2.7  # kg
LOAD_OFFSET = (0.03, -0.02, 0.08)  # m from the flange, in its body's frame
LOAD_INERTIA = (0.01, 0.012, 0.008)  # kg m^2, principal moments about its centre of mass
MASS_CHECK = 0.05  # the check: the payload named within 5 % of its mass
MASS_AIM, COM_AIM = 0.03, 0.01  # the targets: 3 % of the mass, 1 cm
UNLOADED_AIM = 1.3  # the target: the loaded run after the loop within 1.3x the unloaded level
LOAD_SHARE = 0.1  # a joint the load acts on: the load's torque RMS >= 10 % of the joint's
LOAD_FRICTION = 0.05  # N m per N m: the wrist's load friction of the friction case
FRICTION_EPS = 0.01  # rad/s: its linear zone


def loaded_variant(arm: Arm, name: str) -> LoadedVariant:
    """The gripper-like load on arm's flange: LOAD_MASS kg for an 18 kg arm, scaled by its
    mass (its inertia by the same factor), LOAD_OFFSET m from the flange."""
    model = arm.pinocchio
    scale = sum(model.inertias[j].mass for j in range(1, model.njoints)) / REFERENCE_MASS
    return LoadedVariant(payload=LOAD_MASS * scale, payload_offset=LOAD_OFFSET,
                         payload_inertia=tuple(scale * i for i in LOAD_INERTIA), name=name)


def payload_case(arm: Arm, directory: Path, load_friction: float = 0.0,
                 samples: int = SAMPLES, seed: int = SEED) -> dict:
    """The loaded plant of arm written under directory, its data (with load friction mu on the
    wrist when given), the loop's payload and its errors against the plant's load, and the
    loop's model against the unloaded level."""
    model = arm.pinocchio
    plant = Arm.of(write_arm_variant(arm, loaded_variant(arm, "payload"), Path(directory)))
    data = generate(plant, samples, NOISE, seed, "inverse", robot=arm)
    rigid = plant.nominal.torque(data.q, data.qd, data.qdd)
    wrist = np.zeros(arm.dof)
    wrist[max(arm.dof - 3, 0):] = load_friction
    added = wrist * np.abs(rigid) * np.clip(data.qd / FRICTION_EPS, -1.0, 1.0)
    arrays = {"q": data.q, "qd": data.qd, "qdd": data.qdd, "tau": data.tau + added,
              "tau_clean": data.tau_clean + added}
    loop = run_runs(Runs(arrays, (data.meta,), ("payload plant",), (len(data.q),)), arm)
    carrier = last_body(arm).joint or -1  # the body the loop puts a payload on
    extra = (plant.pinocchio.inertias[carrier].toDynamicParameters()
             - model.inertias[carrier].toDynamicParameters())
    true_mass, true_com, _ = describe(extra)
    effects = loop.to_json()["effects"]
    named = [e for e in effects if e["effect"] == "payload"]
    load = rigid - arm.nominal.torque(data.q, data.qd, data.qdd)
    acts = np.sqrt(np.mean(load**2, 0)) >= LOAD_SHARE * np.sqrt(np.mean(rigid**2, 0))
    unloaded = unloaded_level(arm, NOISE * data.tau_clean.std(axis=0), samples, seed)
    held = arrays["tau"][int(round(samples * 0.75)):]
    after = loop.error_after * np.sqrt(np.mean(held**2, axis=0))  # N m RMS
    out = {"robot": arm.label, "seed": seed, "samples": samples, "noise": NOISE,
           "load_friction": load_friction, "true_mass": float(true_mass),
           "true_com": [float(c) for c in true_com], "named": bool(named),
           "other_effects": [f"{e['effect']} j{e['joint']} {e['coefficient']:.4g}"
                             for e in effects if e["effect"] != "payload"],
           "error_before": loop.error_before.tolist(), "error_after": loop.error_after.tolist(),
           "after_rms": after.tolist(), "unloaded_rms": unloaded.tolist(),
           "load_acts_on": (np.flatnonzero(acts) + 1).tolist(),
           "after_over_unloaded": float(np.max(after[acts] / unloaded[acts]))}
    if named:
        mass, com = named[0]["mass"], np.asarray(named[0]["com"], float)
        out.update(mass=float(mass), com=com.tolist(),
                   mass_error=abs(mass - true_mass) / true_mass,
                   com_error_m=float(np.linalg.norm(com - true_com)))
    return out


def unloaded_level(arm: Arm, sigma: np.ndarray, samples: int = SAMPLES,
                   seed: int = SEED) -> np.ndarray:
    """(dof,) the declared model's RMS error per joint (N m) on the loaded case's motion run by
    the arm without the load, with Gaussian noise of std sigma (dof,) N m, its last quarter
    scored with the offset from the run's trained part (as the loaded run's)."""
    data = generate(arm, samples, 0.0, seed, "inverse", bias=0.0)
    noise = np.random.default_rng(seed + 1).normal(size=data.tau.shape) * sigma
    run = (data.q, data.qd, data.qdd, data.tau + noise)
    cut = int(round(samples * 0.75))
    relative = scored_error(arm.nominal, [run_tail(tuple(a[:cut] for a in run),
                                                   tuple(a[cut:] for a in run))])
    return relative * np.sqrt(np.mean(run[3][cut:] ** 2, axis=0))


def control_case(arm: Arm, directory: Path, samples: int = SAMPLES) -> list[str]:
    """The body-level effects (payload, rigid-body correction) the loop names on the arm's own
    plant, which carries no load: none is the answer."""
    plant = Arm.of(write_arm_variant(arm, LoadedVariant(name="control"), Path(directory)))
    data = generate(plant, samples, NOISE, SEED, "inverse", robot=arm)
    arrays = {"q": data.q, "qd": data.qd, "qdd": data.qdd, "tau": data.tau,
              "tau_clean": data.tau_clean}
    loop = run_runs(Runs(arrays, (data.meta,), ("control plant",), (len(data.q),)), arm)
    return [f"{e['effect']} {e['coefficient']:.4g}" for e in loop.to_json()["effects"]
            if e["effect"] in ("payload", "inertial")]


def payload_arms(arm: Arm) -> list[tuple[Arm, float]]:
    """The bench's payload cases: the bench's arm, and a 6-joint arm (the arm itself if it has
    6 or more joints, else the UR5) with the load friction on its wrist."""
    six = arm if arm.dof >= 6 else Arm.of("ur5")
    return [(arm, 0.0)] + ([] if six is arm else [(six, 0.0)]) + [(six, LOAD_FRICTION)]


def _case(p: dict) -> str:
    return p["robot"] + (f", load friction {p['load_friction']:g} on the wrist"
                         if p["load_friction"] else "")


def payload_checks(p: dict) -> list:
    """The case's checks: the load named within 5 %, every joint better after than before."""
    from harness.report.results import check

    key = f"payload.{p['robot']}" + ("_load_friction" if p["load_friction"] else "")
    return [check(f"{key}.named_within_5_percent", p["named"] and p["mass_error"] <= MASS_CHECK,
                  f"a {p['true_mass']:.4g} kg load on the last body named "
                  + (f"{p['mass']:.4g} kg" if p["named"] else "not at all")),
            check(f"{key}.better_on_every_joint",
                  all(a < b for a, b in zip(p["error_after"], p["error_before"], strict=True)),
                  "held-out error after < before on every joint")]


def payload_targets(p: dict) -> list:
    """The case's targets: mass within 3 %, centre of mass within 1 cm, and the loaded run
    within 1.3x the unloaded level on the joints the load acts on."""
    from harness.report.results import Target

    named, case = p["named"], f"{_case(p)}, seed {p['seed']}"  # not named: no figure (missed)
    return [Target(f"payload mass error ({case})", 100 * p["mass_error"] if named else None,
                   100 * MASS_AIM, "%"),
            Target(f"payload centre-of-mass error ({case})",
                   100 * p["com_error_m"] if named else None, 100 * COM_AIM, "cm"),
            Target(f"loaded run after the loop / the declared model on the same motion unloaded "
                   f"(RMS error in N m), worst joint the load acts on ({case})",
                   p["after_over_unloaded"], UNLOADED_AIM, "x")]


def payload_markdown(p: dict) -> str:
    """The payload case in a sentence."""
    named = (f"named {p['mass']:.4g} kg ({100 * p['mass_error']:.2f} %), centre of mass "
             f"({', '.join(f'{c:.3f}' for c in p['com'])}) m ({100 * p['com_error_m']:.2f} cm "
             "off)" if p["named"] else "no payload named")
    return (f"Payload case, {_case(p)} (`closeloop --data` on the arm carrying a load no model "
            f"declares: {p['true_mass']:.4g} kg at ({', '.join(f'{c:.3f}' for c in p['true_com'])})"
            f" m in the last link's frame; inverse dynamics, {100 * p['noise']:g} % noise, seed "
            f"{p['seed']}, drawn once): {named}; other effects named: "
            f"{', '.join(p['other_effects']) or 'none'}; held-out error before "
            f"[{', '.join(f'{x:.3f}' for x in p['error_before'])}], after "
            f"[{', '.join(f'{x:.3f}' for x in p['error_after'])}] (relative); in N m RMS after "
            f"[{', '.join(f'{x:.3g}' for x in p['after_rms'])}], the declared model on the same "
            f"motion unloaded [{', '.join(f'{x:.3g}' for x in p['unloaded_rms'])}]: after / "
            f"unloaded {p['after_over_unloaded']:.3g}x at worst on joints "
            f"{', '.join(map(str, p['load_acts_on']))} (the load acts on them).")
