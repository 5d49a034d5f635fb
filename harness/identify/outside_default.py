"""The default identification on data made outside `identify`'s own path.

A robot's data along motions none of the project's code chose: sums of sines of another
spectrum than the bench's judge (`multisine`) and a random Fourier series of other harmonics
than `generate`'s (`fourier`: 6 harmonics of 0.1 Hz), simulated by MuJoCo's inverse dynamics,
with non-zero-mean Gaussian torque noise of 5 % and 10 % of each joint's torque std (BIAS of
it as offset); identified by `identify`'s defaults (arm_identification with no option: on the
Lynxmotion the coupled fit on the prior-knowledge library) on the first 75 %, and judged
against the oracle fitted on the same samples, on three fresh motions: the bench's sines
spectrum and a motion of each training family, none fitted on.

DEV_SEEDS and DEV_JUDGE found and bisected the issue; FRESH_SEEDS and FRESH_JUDGE were drawn
once (numpy.random.default_rng().integers(10_000), 2026-11-28) and no setting was chosen on
them. The same data scored by the `identify` CLI of any checkout:

    python harness/identify/outside_default.py write DIR [--fresh] [--excitation TRAJ.csv]
    PYTHONPATH=OTHER python harness/identify/outside_default.py score DIR   (OTHER's CLI)

--excitation: the draws along an `excite` file instead (its first 4000 samples, simulated and
noised here), to score the excitation another checkout designs.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

NOISES, BIAS = (0.05, 0.10), 0.2
FAMILIES = ("multisine", "fourier")
DEV_SEEDS, DEV_JUDGE = (9101, 9102, 9103, 9104), 9150  # found and bisected the issue
FRESH_SEEDS, FRESH_JUDGE = (9960, 7583, 9799, 7116, 7085, 2100), 6413  # drawn 2026-11-28
QUICK_SEEDS = (9101,)
JUDGES = ("sines", "multisine", "fourier")


def multisine_spectrum():
    """Another spectrum than the bench's judge (3-6 sines, 0.05-1 Hz, 85 % of the range) and
    the generalization study's: 4-8 sines, 0.1-1.5 Hz, 70 % of each joint's range."""
    from harness.identify.scoring import Spectrum

    return Spectrum(count=(4, 9), band=(0.1, 1.5), fill=0.7, stream=2718)


def motion(arm, family: str, seed: int, samples: int):
    """q, qd, qdd and the clean torque of one motion of family ('multisine', 'fourier',
    'sines': the bench's judge spectrum; a path: an `excite` CSV's first samples) at
    generate's sample rate."""
    from harness.data.generate import SAMPLE_RATE, inverse_torques
    from harness.identify.scoring import sines_motion
    from identification.excitation.fourier import random_excitation, within_velocity

    if family.endswith(".csv"):
        rows = np.loadtxt(family, delimiter=",", skiprows=1)[:samples]
        q, qd, qdd = np.split(rows[:, 1:], 3, axis=1)
        return q, qd, qdd, inverse_torques(arm.mujoco, q, qd, qdd)
    if family == "fourier":
        lower, upper = arm.position_limits
        rng = np.random.default_rng([seed, 577])
        exc = within_velocity(random_excitation(lower, upper, rng, harmonics=6, f0=0.1, fill=0.8),
                              arm.speed_bounds)
        q, qd, qdd = exc.evaluate(np.arange(samples) / SAMPLE_RATE)
        return q, qd, qdd, inverse_torques(arm.mujoco, q, qd, qdd)
    m = (sines_motion(arm, samples, seed) if family == "sines"
         else sines_motion(arm, samples, seed, spectrum=multisine_spectrum()))
    return m.q, m.qd, m.qdd, m.tau_clean


def datasets(arm, seeds, samples: int, families=FAMILIES, noises=NOISES):
    """Every (family, seed, noise) draw as a Dataset; the noise seeded by (seed, noise); a
    file's motion is the same for every seed."""
    from harness.data.dataset import Dataset
    from harness.data.generate import SAMPLE_RATE
    from harness.data.sensors import torque_noise

    out = []
    for family in families:
        for seed in seeds:
            q, qd, qdd, clean = motion(arm, family, seed, samples)
            for noise in noises:
                rng = np.random.default_rng([seed, round(100 * noise), 31])
                tau = clean + torque_noise(clean, noise, BIAS, rng)
                out.append(Dataset(np.arange(samples) / SAMPLE_RATE, q, qd, qdd, tau, clean,
                                   {"seed": seed, "noise": noise,
                                    "family": Path(family).stem if family.endswith(".csv")
                                    else family}))
    return out


def judges(arm, judge: int, samples: int):
    """The fresh motions every draw is judged on (seeds of judge's, none fitted on)."""
    from harness.identify.scoring import Motion

    return [Motion(name, *motion(arm, name, judge + k * 50000, samples))
            for k, name in enumerate(JUDGES)]


def family_and_noise(draw: dict) -> str:
    """summarize's group of a draw: 'family noise'."""
    return f"{draw['family']} {draw['noise']:g}"


def summarize(draws: list[dict], fit: str = "default", reference: str = "oracle",
              group=family_and_noise) -> dict:
    """Per group (by default 'family noise'): the ratio of fit's judge errors to reference's
    per joint, its median over draws and judges, the worst over them, and the median and
    worst of all; fit's relative error per joint, median over draws and judges; and fit's
    largest error per joint over draws and judges over the reference's largest (a worst case
    against a worst case: the worst ratio falls where the reference's own error was lucky)."""
    groups: dict[str, list] = {}
    for d in draws:
        groups.setdefault(group(d), []).append(
            [[np.array(d[fit][j]) / np.array(d[reference][j]), d[fit][j], d[reference][j]]
             for j in JUDGES])
    out = {}
    for key, both in groups.items():
        both = np.array(both)  # draws, judges, (ratio, fit's error, reference's), dof
        r, errors, reference_errors = both[:, :, 0], both[:, :, 1], both[:, :, 2]
        out[key] = {"median_per_joint": np.median(r, axis=(0, 1)).tolist(),
                    "error_median_per_joint": np.median(errors, axis=(0, 1)).tolist(),
                    "worst_per_joint": r.max(axis=(0, 1)).tolist(),
                    "largest_error_ratio_per_joint": (errors.max(axis=(0, 1))
                                                      / reference_errors.max(axis=(0, 1))).tolist(),
                    "median": float(np.median(r)), "worst": float(r.max())}
    return out


def outside_default(arm, seeds=DEV_SEEDS, judge: int = DEV_JUDGE, samples: int = 4000) -> dict:
    """The default identification on every draw of datasets(seeds), scored on judges(judge)
    against the oracle (harness.identify.scoring.score_draw); summarize's figures."""
    from harness.identify.fits import arm_identification
    from harness.identify.scoring import fixed_fit, score_draw

    fits = {"default": fixed_fit(*arm_identification(arm))}
    motions = judges(arm, judge, samples)
    draws = []
    for data in datasets(arm, seeds, samples):
        d = score_draw(data, fits, arm.nominal, motions)
        draws.append({"family": data.meta["family"], "noise": data.meta["noise"], "seed": d["seed"],
                      "default": {j: d["default"][j] for j in JUDGES},
                      "oracle": {j: d["oracle"][j] for j in JUDGES}})
    return {"robot": arm.reference, "seeds": list(seeds), "judge": judge,
            "summary": summarize(draws), "draws": draws}


def markdown(result: dict) -> list[str]:
    """One row per family and noise."""
    md = ["| data | noise | ratio to the oracle per joint: median (worst) over draws and judges |"
          " median / worst |", "|---|---|---|---|"]
    for key, s in result["summary"].items():
        family, noise = key.split()
        joints = ", ".join(f"{m:.2f} ({w:.2f})" for m, w in zip(s["median_per_joint"],
                                                                 s["worst_per_joint"], strict=True))
        md.append(f"| {family} | {float(noise):.0%} | {joints} | {s['median']:.2f} / "
                  f"{s['worst']:.2f} |")
    return md


def write(folder: str, fresh: bool = False, robot: str = "lynxmotion",
          excitation: str | None = None) -> None:
    """The draws, the judges (npz, the dataset contract) and the oracle's judge errors."""
    from harness.identify.scoring import HOLDOUT, oracle_design, oracle_fit
    from harness.robots.arm import Arm
    from identification.metrics import rel_error

    arm, out = Arm.of(robot), Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    seeds, judge = (FRESH_SEEDS, FRESH_JUDGE) if fresh else (DEV_SEEDS, DEV_JUDGE)
    motions = judges(arm, judge, 4000)
    for m in motions:
        np.savez(out / f"judge_{m.name}.npz", q=m.q, qd=m.qd, qdd=m.qdd, tau=m.tau_clean,
                 tau_clean=m.tau_clean)
    index = []
    for data in datasets(arm, seeds, 4000, (excitation,) if excitation else FAMILIES):
        name = f"{data.meta['family']}_{data.meta['seed']}_{round(100 * data.meta['noise'])}"
        np.savez(out / f"{name}.npz", **{k: v for k, v in data.arrays().items()})
        oracle, _ = oracle_fit(arm.nominal, data, int(round(len(data.q) * (1 - HOLDOUT))))
        index.append({**data.meta, "name": name, "oracle": {
            m.name: rel_error(oracle.predict(oracle_design(arm.nominal, m.q, m.qd, m.qdd)),
                              m.tau_clean).tolist() for m in motions}})
    (out / "index.json").write_text(json.dumps({"robot": robot, "draws": index}, indent=1))


def score(folder: str) -> dict:
    """Each draw identified and predicted by the `identify` and `predict` CLI on sys.path (no
    option but the robot), scored on the judges; summarize's figures."""
    import contextlib
    import io

    from harness.cli import main

    out = Path(folder)
    index = json.loads((out / "index.json").read_text())
    draws = []
    for d in index["draws"]:
        model, pred = out / "model.json", out / "predicted.npz"
        errors = {}
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["identify", "--data", str(out / f"{d['name']}.npz"), "--robot",
                         index["robot"], "--out", str(model)]) == 0
            for j in JUDGES:
                judge = out / f"judge_{j}.npz"
                assert main(["predict", "--model", str(model), "--data", str(judge), "--robot",
                             index["robot"], "--out", str(pred)]) == 0
                tau, clean = np.load(pred)["tau"], np.load(judge)["tau_clean"]
                errors[j] = (np.linalg.norm(tau - clean, axis=0)
                             / np.linalg.norm(clean, axis=0)).tolist()
        draws.append({**d, "default": errors})
    return summarize(draws)


if __name__ == "__main__":  # run as a file, so that another checkout's CLI can score
    mode, folder = sys.argv[1], sys.argv[2]
    if mode == "write":
        file = sys.argv[sys.argv.index("--excitation") + 1] if "--excitation" in sys.argv else None
        write(folder, "--fresh" in sys.argv, excitation=file)
    else:
        print(json.dumps(score(folder), indent=1))
