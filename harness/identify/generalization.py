"""Identification on data not made by the project's excitation, judged on a fresh motion.

The outside-style check: a robot's data along a sum of random sines of another
spectrum than the bench's judge (`OUTSIDE`: faster, up to 2 Hz, a narrower sweep, another
seed stream), 5 % torque noise with a sensor bias (of each joint's torque std, or one sensor
noise in N m on every joint: NOISE_MODELS), 4000 samples; the consistent fit given a
URDF whose inertias are off by up to 30 % and centres of mass by 2 cm (perturbed_nominal),
the consistent fit without a prior, and the robot's sparse default, all against the oracle
fitted on the same samples; judged on a fresh run of `generate`'s own excitation (a family
none of them was fitted on) and on a motion of the bench's sines spectrum.
"""

from __future__ import annotations

import numpy as np

from harness.data.dataset import Dataset
from harness.data.generate import SAMPLE_RATE
from harness.data.sensors import torque_noise
from harness.identify.fits import arm_identification
from harness.identify.scoring import (
    FLAT,
    NOISE,
    PRIOR,
    SAMPLES,
    Spectrum,
    fixed_fit,
    generated_motion,
    perturbed_prior_fit,
    ratio_summary,
    score_draw,
    sines_motion,
)
from harness.robots.arm import Arm

OUTSIDE = Spectrum(count=(3, 7), band=(0.2, 2.0), fill=0.5, stream=104729)
BIAS = 0.2  # sensor offset, x the noise std (generate's default)
SEEDS, QUICK_SEEDS = (701, 702, 703), (701,)  # seeds no bench section scores
SENSOR_SEEDS = tuple(range(711, 717))  # the sensor noise's draws: its loss was found on 5701-5702
JUDGE_SEED = 1707  # the fresh motions' seed (the bench's is 1005)
SPARSE = "sparse default"


NOISE_MODELS = {"torque": "noise x each joint's torque std",
                "sensor": "one sensor noise in N m on every joint: noise x the joints' mean "
                          "torque std"}


def outside_dataset(arm: Arm, seed: int, samples: int = SAMPLES, noise: float = NOISE,
                    noise_model: str = "torque") -> Dataset:
    """Noisy torque (NOISE_MODELS: a std per joint, plus BIAS of it as an offset) along a
    motion of the OUTSIDE spectrum."""
    m = sines_motion(arm, samples, seed, spectrum=OUTSIDE)
    rng = np.random.default_rng([seed, 31])
    tau = m.tau_clean + torque_noise(m.tau_clean, noise, BIAS, rng,
                                     one_sensor=noise_model == "sensor")
    return Dataset(np.arange(samples) / SAMPLE_RATE, m.q, m.qd, m.qdd, tau, m.tau_clean,
                   {"seed": seed, "noise": noise, "noise_model": noise_model,
                    "excitation": "outside sines"})


def generalization(arm: Arm, seeds=SEEDS, noise_model: str = "torque") -> dict:
    """Per fit and judge motion, the ratio summary to the oracle over the draws (seeds, data
    of NOISE_MODELS' noise_model), and the draws' per-joint errors."""
    baseline = arm.nominal
    fits = {SPARSE: fixed_fit(*arm_identification(arm)),
            PRIOR: perturbed_prior_fit(arm.library, baseline, arm.ellipsoids),
            FLAT: fixed_fit(*arm_identification(arm, prior="flat"))}
    judges = [generated_motion(arm, SAMPLES, JUDGE_SEED), sines_motion(arm, SAMPLES, JUDGE_SEED)]
    draws = [score_draw(outside_dataset(arm, seed, noise_model=noise_model), fits, baseline, judges)
             for seed in seeds]
    return {"robot": arm.reference, "seeds": list(seeds), "noise_model": noise_model,
            "summary": {name: {m.name: ratio_summary(draws, name, m.name) for m in judges}
                        for name in fits},
            "draws": [{k: v for k, v in d.items() if k != "models"} for d in draws]}


def markdown(results: list[dict]) -> list[str]:
    """One table row per robot, fit and judge motion."""
    md = ["| robot | noise | fit | judge | ratio to the oracle per joint (median over draws) | "
          "worst draw: median / worst joint |", "|---|---|---|---|---|---|"]
    for r in results:
        for name, by_judge in r["summary"].items():
            for judge, s in by_judge.items():
                md.append(f"| {r['robot'].rsplit('/', 1)[-1]} | {r['noise_model']} | {name} | {judge} | "
                          + ", ".join(f"{x:.2f}" for x in s["median_ratio_per_joint"])
                          + f" | {s['worst_median']:.2f} / {s['worst_joint']:.2f} |")
    return md
