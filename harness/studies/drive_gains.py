"""Study `drive_gains`: drive gains identified with the dynamics (`identify --loaded
--load-mass`, harness.identify.drive_gains) on simulated logs of motor currents.

Per arm (UR5, Panda; quick: the UR5 on fewer samples): an unloaded and a loaded run made
in MuJoCo by `generate` (inverse dynamics along its own excitation, each run its seed, the
friction and armature the model declares, NOISE torque noise with generate's sensor bias),
the loaded plant carrying a gripper-like load on the flange (harness.closeloop.arm_plants);
the torque divided by distinct known GAINS gives the logged currents. Scored: each gain's
relative error, by the instrumental-variable solution identify uses and by plain weighted
least squares (the errors-in-variables bias the former removes).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from harness.closeloop.arm_plants import write_arm_variant
from harness.closeloop.payload_case import loaded_variant
from harness.closeloop.plants import Variant
from harness.data.generate import generate
from harness.identify.drive_gains import gain_runs
from harness.io import write_npz
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm
from identification.drive_gains import GAIN_BLOCKS, identify_drive_gains
from identification.errors import IdentificationError

# drawn once (numpy.random.default_rng().integers(10_000)) and written here; nothing in the
# method was chosen on it
SEED = 5309
SAMPLES, QUICK_SAMPLES, NOISE = 4000, 2000, 0.05
GAINS = (7.3, 11.0, 5.2, 2.9, 1.7, 0.9, 0.6)  # N m/A, joint 1.. (distinct, motor-like)
TARGET = 0.03  # every gain within 3 %
# the intervals' coverage: draws of a coupled plant (a spring on q2 + q3 the model lacks, its
# torque's RMS COUPLING of joint 2's torque's std on the unloaded run), seeds COVERAGE_SEED + 2 d,
# drawn once (numpy.random.default_rng().integers(10_000)); pairs of draws are two
# independent pairs of runs of one robot
COVERAGE_SEED, DRAWS, QUICK_DRAWS, COVERAGE_SAMPLES = 3795, 20, 6, 2000
COUPLING = 0.1
COVERAGE_TARGET = 17 / 20  # a 95 % interval covers the truth in at least 17 of 20 draws


def current_logs(arm: Arm, directory: Path, seed: int = SEED, samples: int = SAMPLES,
                 noise: float = NOISE, gains=None, coupling: float = 0.0) -> dict:
    """An unloaded and a loaded run of arm written as datasets of currents (key `current`,
    A, as `ingest --gains-unknown` writes them) under directory: their paths, the load's mass,
    the true gains and the load's true parameters (last joint's frame); coupling: the
    stiffness (N m/rad) of a spring on q2 + q3 in both plants, a term the gains' model lacks
    (its residual coloured, as a real log's)."""
    directory = Path(directory)
    loaded = loaded_variant(arm, "load")
    plant = Arm.of(write_arm_variant(arm, replace(loaded, coupling=coupling), directory))
    plain = (Arm.of(write_arm_variant(arm, Variant(coupling=coupling, name="coupled"), directory))
             if coupling else arm)
    gains = np.asarray(GAINS[:arm.dof] if gains is None else gains, float)
    paths = {}
    for name, (robot, run_seed) in {"unloaded": (plain, seed),
                                    "loaded": (plant, seed + 1)}.items():
        data = generate(robot, samples, noise, run_seed, "inverse", robot=arm)
        meta = {**data.meta, "plant": arm.reference, "robot": arm.reference,
                "robot_hash": arm.record["hash"], "simulated_plant": robot.label,
                "effort": {"logged": "motor current (A)", "current_gains": None,
                           "current": "simulated: torque / true gains, gains unknown to identify"}}
        paths[name] = directory / f"{name}.npz"
        write_npz(paths[name], t=data.t, q=data.q, qd=data.qd, qdd=data.qdd,
                  current=data.tau / gains, meta=np.array(json.dumps(meta)))
    load = (plant.pinocchio.inertias[-1].toDynamicParameters()
            - arm.pinocchio.inertias[-1].toDynamicParameters())
    return {**paths, "mass": float(load[0]), "gains": gains, "load": load}


def score(arm: Arm, directory: Path, seed: int = SEED, samples: int = SAMPLES) -> dict:
    """Each gain's relative error on arm's simulated logs, by identify's solution and by
    weighted least squares alone."""
    logs = current_logs(arm, directory, seed, samples)
    _, _, report = gain_runs([str(logs["unloaded"])], str(logs["loaded"]), logs["mass"],
                             arm.reference)
    runs = []
    for path in (logs["unloaded"], logs["loaded"]):
        with np.load(path) as d:
            runs.append((arm.nominal.regressor(d["q"], d["qd"], d["qdd"]), d["qd"], d["qdd"],
                         d["current"]))
    ls = identify_drive_gains(runs[0], runs[1], logs["mass"], instrumental=False)
    true = logs["gains"]
    return {"seed": seed, "samples": samples, "noise": NOISE, "load_mass_kg": logs["mass"],
            "true_gains": true.tolist(), "gains": report["gains"],
            "error": (np.asarray(report["gains"]) / true - 1).tolist(),
            "standard_error": (np.asarray(report["standard_error"]) / true).tolist(),
            "least_squares_error": (ls.gains / true - 1).tolist()}


def coverage(arm: Arm, directory: Path, draws: int = DRAWS, seed: int = COVERAGE_SEED,
             samples: int = COVERAGE_SAMPLES) -> dict:
    """Over draws of arm's coupled plants (the model lacks the coupling: a coloured residual),
    how often each gain's printed 95 % interval covers the truth, against the white-noise
    standard error's 1.96 sigma; pairs of draws: whether their gains agree within their
    intervals (|K_a - K_b| <= h_a + h_b)."""
    rows = []
    for d in range(draws):
        plain = generate(arm, samples, 0.0, seed + 2 * d, "inverse", robot=arm)
        # the spring's torque -k (q2 + q3) (its rest at 0): its RMS on the run COUPLING of
        # joint 2's torque's std
        stiffness = (COUPLING * np.std(plain.tau[:, 1])
                     / np.sqrt(np.mean((plain.q[:, 1] + plain.q[:, 2]) ** 2)))
        logs = current_logs(arm, Path(directory) / f"draw{d}", seed + 2 * d, samples,
                            coupling=stiffness)
        try:
            _, _, report = gain_runs([str(logs["unloaded"])], str(logs["loaded"]), logs["mass"],
                                     arm.reference)
        except IdentificationError as e:  # no gain identified: nothing covered
            rows.append({"seed": seed + 2 * d, "failed": str(e), "coupling_Nm_per_rad": stiffness,
                         **{k: [False] * arm.dof for k in ("covered", "white_covered")}})
            continue
        gains, half = np.asarray(report["gains"]), np.asarray(report["interval_95"])
        error = np.abs(gains - logs["gains"])
        rows.append({"seed": seed + 2 * d, "error": (error / logs["gains"]).tolist(),
                     "interval": (half / logs["gains"]).tolist(),
                     "white": (np.asarray(report["standard_error"]) / logs["gains"]).tolist(),
                     "covered": (error <= half).tolist(),
                     "white_covered": (error <= 1.96 * np.asarray(report["standard_error"])).tolist(),
                     "body": report["load"]["body"], "gains": gains.tolist(),
                     "half_width": half.tolist(),
                     "coupling_Nm_per_rad": stiffness})
    covered = np.array([r["covered"] for r in rows])
    white = np.array([r["white_covered"] for r in rows])
    whole = len(rows) // 2 * 2  # an odd last draw has no pair
    pairs = [np.abs(np.subtract(a["gains"], b["gains"])) <= np.add(a["half_width"], b["half_width"])
             if "gains" in a and "gains" in b else np.zeros(arm.dof, bool)
             for a, b in zip(rows[:whole:2], rows[1:whole:2], strict=True)]
    fitted = [r for r in rows if "gains" in r]
    return {"draws": rows, "coupling_share": COUPLING,
            "covered_per_joint": covered.sum(axis=0).tolist(),
            "white_covered_per_joint": white.sum(axis=0).tolist(),
            "pairs_agree_per_joint": np.sum(pairs, axis=0).tolist(), "pairs": len(pairs),
            "failed": len(rows) - len(fitted),
            "median_interval": np.median([r["interval"] for r in fitted], axis=0).tolist(),
            "median_error": np.median([r["error"] for r in fitted], axis=0).tolist()}


def run(ctx: Context) -> SectionResult:
    names = ["ur5"] if ctx.quick else ["ur5", "panda"]
    samples = QUICK_SAMPLES if ctx.quick else SAMPLES
    results = {name: score(Arm.of(name), ctx.out_dir / "drive_gains" / name, SEED, samples)
               for name in names}
    md = [f"Unloaded and loaded runs of {samples} samples each (seed {SEED}, {NOISE:.0%} torque "
          "noise), currents = torque / known gains; `identify --loaded --load-mass` against "
          "the truth. Relative error per joint (%):", "",
          "| robot | solution | " + " | ".join(f"K{j + 1}" for j in range(7)) + " |",
          "|---|---|" + "---|" * 7]
    for name, r in results.items():
        for label, key in (("identify (IV)", "error"), ("least squares", "least_squares_error")):
            cells = [f"{100 * e:+.2f}" for e in r[key]] + [""] * (7 - len(r[key]))
            md.append(f"| {name} | {label} | " + " | ".join(cells) + " |")
    worst = max(abs(e) for r in results.values() for e in r["error"])
    checks = [check("gains_within_target", worst <= TARGET,
                    f"worst gain error {100 * worst:.2f} % (target {100 * TARGET:g} %)")]
    targets = [Target("drive gains: worst relative error over joints and arms", worst, TARGET, "")]
    draws = QUICK_DRAWS if ctx.quick else DRAWS
    covers = {name: coverage(Arm.of(name), ctx.out_dir / "drive_gains" / f"{name}_coverage",
                             draws) for name in names}
    md += ["", f"Intervals that cover the next run: {draws} draws of each arm's plants with a "
           f"spring on q2 + q3 the model lacks (its torque's std {COUPLING:.0%} of joint 2's; "
           f"seeds {COVERAGE_SEED} + 2 d, drawn once, nothing chosen on them), "
           f"{COVERAGE_SAMPLES} samples a run. Draws whose gain lies inside the printed 95 % "
           f"interval (jackknife, {GAIN_BLOCKS} blocks a run), inside the white-noise 1.96 "
           "sigma, and pairs of draws (two independent pairs of runs) whose gains agree within "
           "their intervals; median interval and error (%):", "",
           "| robot | measure | " + " | ".join(f"K{j + 1}" for j in range(7)) + " |",
           "|---|---|" + "---|" * 7]
    for name, c in covers.items():
        pad = [""] * (7 - len(c["covered_per_joint"]))
        for label, cells in (
                (f"covered by the interval (of {draws})", c["covered_per_joint"]),
                (f"covered by 1.96 white sigma (of {draws})", c["white_covered_per_joint"]),
                (f"pairs agreeing (of {c['pairs']})", c["pairs_agree_per_joint"]),
                ("median half-width (%)", [f"{100 * x:.1f}" for x in c["median_interval"]]),
                ("median error (%)", [f"{100 * x:.1f}" for x in c["median_error"]])):
            md.append(f"| {name} | {label} | " + " | ".join(map(str, [*cells, *pad])) + " |")
    worst_cover = min(min(c["covered_per_joint"]) / draws for c in covers.values())
    worst_pairs = min(min(c["pairs_agree_per_joint"]) / max(c["pairs"], 1)
                      for c in covers.values())
    targets += [Target("drive gains: the 95 % interval covers the truth, worst joint "
                       "(fraction of draws)", worst_cover, COVERAGE_TARGET, "",
                       lower_is_better=False, note=f"{draws} draws a robot, seed {COVERAGE_SEED}"),
                Target("drive gains: two pairs of runs agree within their intervals, worst "
                       "joint (fraction of pairs)", worst_pairs, COVERAGE_TARGET, "",
                       lower_is_better=False, note=f"seed {COVERAGE_SEED}")]
    results["coverage"] = covers
    return SectionResult("\n".join(md), results, checks, targets)
