"""The robot's next motion: fit on one run, predict another, as on a real arm - simulated.

Two independent runs of one arm: `generate`'s excitation (fitted) and a motion of another
family (`sines_motion`, scored). Both carry what a real arm's log carries beyond the rigid
body: joint friction (per joint viscous, Coulomb and a Stribeck bump of magnitudes drawn as
fractions of the joint's torque spread, Coulomb a shifted tanh of a drawn width), a constant
sensor offset, and sensor noise (NOISE of each joint's torque std). The user's URDF is
wrong (perturbed_nominal). Scored on the second run against the torque its sensor reads
without the noise:

- nominal: the perturbed URDF's RNEA (its atoms: inertias, declared armature and damping);
- least squares + friction: rigid-body base atoms + viscous, Coulomb, offset (peers);
- identified: `identify --prior nominal` on the first run (`--validate` the second);
- consistent, no prior: `--prior flat`.

The rule a real arm's held-out run is judged by: on every joint that carries real load
(torque above RULE_RMS N m RMS, or LOAD_SHARE of the largest joint's on a small arm), the
identified model at or below both the nominal and least squares; at the median over joints,
at or below least squares.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.closeloop.one_log import rigid_library
from harness.data.generate import generate
from harness.identify.peers import joint_friction_columns, least_squares
from harness.identify.scoring import NOISE, SAMPLES, perturbed_nominal, sines_motion
from harness.report.results import distinct
from harness.robots.arm import Arm
from identification.identify import identify
from identification.metrics import rel_error
from identification.physical import joint_weights
from identification.regression.base import within_runs
from identification.regression.consistent import ConsistentRegressor

RULE_RMS = 2.0  # N m: joints that carry real torque
SAMPLE_RUN = 2000  # samples per run of several_runs
LOAD_SHARE = 0.25  # ... or, on a small arm, this share of its most loaded joint's RMS


def rule_threshold(rms: np.ndarray) -> float:
    """The torque RMS (N m) above which a joint carries real load: RULE_RMS, or on an arm
    whose joints all stay below it, LOAD_SHARE of its most loaded joint's (so that the rule
    always judges some joint)."""
    return float(min(RULE_RMS, LOAD_SHARE * np.max(rms)))
VISCOUS, COULOMB = (0.02, 0.08), (0.03, 0.12)  # of the joint's torque std, per rad/s and N m


def _friction(qd: np.ndarray, rng, spread: np.ndarray) -> tuple[dict, np.ndarray]:
    """A friction law per joint drawn once for the arm (a shape none of the fits' candidate
    laws has exactly), and its torque at qd."""
    dof = qd.shape[1]
    law = {"viscous": spread * rng.uniform(*VISCOUS, dof), "coulomb": spread * rng.uniform(*COULOMB, dof),
           "width": rng.uniform(0.005, 0.05, dof), "shift": rng.uniform(-0.02, 0.02, dof),
           "stribeck": spread * rng.uniform(0.0, 0.05, dof), "speed": rng.uniform(0.02, 0.2, dof),
           "offset": spread * rng.uniform(-0.05, 0.05, dof)}
    return law, law_torque(law, qd)


def law_torque(law: dict, qd: np.ndarray) -> np.ndarray:
    """Viscous + Coulomb (tanh of a given width, shifted) + a Stribeck bump + offset."""
    moving = np.tanh((qd + law["shift"]) / law["width"])
    return (law["viscous"] * qd + law["coulomb"] * moving + law["offset"]
            + law["stribeck"] * moving * np.exp(-((qd / law["speed"]) ** 2)))


@dataclass(frozen=True)
class Runs:
    """The two runs: the fitted one (first) and the scored one (second, `sines_motion`), the
    measured torques of both, the second's torque without noise, the perturbed nominal."""

    first: object
    second: object
    tau_first: np.ndarray
    tau_second: np.ndarray
    truth_second: np.ndarray
    nominal: np.ndarray


def two_runs(arm: Arm, seed: int, samples: int = SAMPLES, noise: float = NOISE) -> Runs:
    rng = np.random.default_rng([seed, 6007])
    first, second = generate(arm, samples, 0.0, seed, "inverse"), sines_motion(arm, samples, seed)
    spread = first.tau_clean.std(axis=0)
    law, friction = _friction(first.qd, rng, spread)
    tau_first = first.tau_clean + friction + noise * spread * rng.normal(size=first.q.shape)
    truth = second.tau_clean + law_torque(law, second.qd)
    tau_second = truth + noise * spread * rng.normal(size=second.q.shape)
    nominal = perturbed_nominal(arm.nominal, seed)
    return Runs(first, second, tau_first, tau_second, truth, nominal)


@dataclass(frozen=True)
class Run:
    """One run of a series: its motion, its measured torque, its torque without the noise."""

    motion: object
    tau: np.ndarray
    truth: np.ndarray


def several_runs(arm: Arm, seed: int, count: int = 3, samples: int = SAMPLE_RUN,
                 noise: float = NOISE) -> tuple[list[Run], np.ndarray]:
    """`count` runs of one arm (one friction law and sensor offset, as two_runs draws them)
    on different excitations: the project's excitation at seeds seed, seed + 1, ... for all
    but the last, random sines (another family) for the last; and the perturbed nominal."""
    rng = np.random.default_rng([seed, 6011])
    motions = [generate(arm, samples, 0.0, seed + k, "inverse") for k in range(count - 1)]
    motions.append(sines_motion(arm, samples, seed))
    spread = motions[0].tau_clean.std(axis=0)
    law, _ = _friction(motions[0].qd, rng, spread)
    runs = []
    for m in motions:
        truth = m.tau_clean + law_torque(law, m.qd)
        runs.append(Run(m, truth + noise * spread * rng.normal(size=m.q.shape), truth))
    return runs, perturbed_nominal(arm.nominal, seed)


def fit_runs(arm: Arm, runs: list[Run], nominal: np.ndarray, which):
    """`identify --prior nominal` (holdout 0, the arm's ellipsoids) on the runs `which`,
    each labelled (an offset each; with several, the weight chosen by leaving one out)."""
    states = [np.concatenate([getattr(runs[k].motion, a) for k in which]) for a in ("q", "qd", "qdd")]
    labels = np.concatenate([np.full(len(runs[k].tau), k) for k in which])
    return identify(*states, np.concatenate([runs[k].tau for k in which]), arm.library, 0.0,
                    regressor=ConsistentRegressor(nominal, ellipsoids=arm.ellipsoids), runs=labels)


def error_on(fit, run: Run) -> np.ndarray:
    """A fit's relative RMS error per joint on a run, against its torque without the noise."""
    m, model = run.motion, fit.model
    return rel_error(model.torque(m.q, m.qd, m.qdd) + model.offsets, run.truth)


def _designs(arm: Arm, runs: list[Run]) -> list[np.ndarray]:
    """Each run's least squares columns: rigid-body base atoms, viscous and Coulomb per joint."""
    rigid = rigid_library(arm)
    return [np.concatenate([rigid.evaluate(r.motion.q, r.motion.qd, r.motion.qdd),
                            joint_friction_columns(r.motion.qd)[:, :, :2 * arm.dof]], axis=2)
            for r in runs]


def least_squares_on_runs(arm: Arm, runs: list[Run], which, designs=None) -> np.ndarray:
    """Least squares + friction (rigid-body base atoms, viscous and Coulomb per joint) on the
    runs `which`, each with its own offset, each joint's residual weighed by its noise as the
    consistent fit weighs it: its relative RMS error per joint on the last run (the model's
    offset the runs' mean, as the consistent fit's). designs: each run's columns, if known."""
    designs = _designs(arm, runs) if designs is None else designs
    X = np.concatenate([designs[k] for k in which])
    tau = np.concatenate([runs[k].tau for k in which])
    labels = np.concatenate([np.full(len(runs[k].tau), k) for k in which])
    Xc, tc = within_runs(X, labels), within_runs(tau, labels)
    scale = joint_weights(Xc, tc)
    coef = np.linalg.lstsq((Xc / scale[None, :, None]).reshape(-1, X.shape[2]),
                           (tc / scale).ravel(), rcond=None)[0]
    offset = np.mean(tau - X @ coef, axis=0)
    return rel_error(designs[-1] @ coef + offset, runs[-1].truth)


def runs_against_single(arm: Arm, seed: int) -> dict:
    """Three runs (several_runs): runs 1 + 2 fitted together and each alone, all scored on
    run 3; per joint the ratio of the pair's error to the best single run's, and
    the same ratio for least squares + friction on the same runs (least_squares_on_runs):
    where both miss, the noise draw decides, not the consistent fit's choices
    (docs/identification.md, 'Several runs against the best single run')."""
    runs, nominal = several_runs(arm, seed)
    single = [fit_runs(arm, runs, nominal, [k]) for k in (0, 1)]
    both = fit_runs(arm, runs, nominal, [0, 1])
    best = np.minimum(*(error_on(f, runs[2]) for f in single))
    designs = _designs(arm, runs)
    peer = least_squares_on_runs(arm, runs, [0, 1], designs) / np.minimum(
        *(least_squares_on_runs(arm, runs, [k], designs) for k in (0, 1)))
    return {"seed": seed, "ratio": (error_on(both, runs[2]) / best).tolist(),
            "least_squares_ratio": peer.tolist(),
            "lambda": both.physical["lambda"], "single_lambdas": [f.physical["lambda"] for f in single],
            "chosen_on": both.physical["validation"]["chosen_on"]}


def least_squares_draws(arm: Arm, seed: int, draws: int = 200, samples: int = SAMPLE_RUN,
                        noise: float = NOISE) -> np.ndarray:
    """(draws, dof): runs_against_single's ratio for least squares + friction on the same three
    motions and friction as several_runs(arm, seed), each draw of the sensor noise fresh
    (numpy's generator seeded [seed, 6013]): how often the pair misses the best single run
    when only the noise changes (docs/identification.md, 'Several runs against the best
    single run')."""
    runs, _ = several_runs(arm, seed, samples=samples, noise=noise)
    designs, out = _designs(arm, runs), []
    for drawn in noise_draws(runs, np.random.default_rng([seed, 6013]), draws, noise):
        single = [least_squares_on_runs(arm, drawn, [k], designs) for k in (0, 1)]
        out.append(least_squares_on_runs(arm, drawn, [0, 1], designs) / np.minimum(*single))
    return np.array(out)


def noise_draws(runs: list[Run], rng, draws: int, noise: float = NOISE):
    """The runs again `draws` times, each with a fresh draw of the sensor noise (the motions,
    the friction and the offset kept): noise x the first run's clean torque std per joint."""
    spread = runs[0].motion.tau_clean.std(axis=0)
    for _ in range(draws):
        yield [Run(r.motion, r.truth + noise * spread * rng.normal(size=r.tau.shape), r.truth)
               for r in runs]


def pair_against_first(arm: Arm, seed: int, draws: int) -> dict:
    """Runs 1 + 2 fitted together against run 1 alone (`identify --prior nominal`, as
    fit_runs), both scored on run 3, over `draws` draws of the noise (several_runs(arm, seed)'s
    motions, friction and perturbed URDF; numpy's generator seeded [seed, 6017]): per draw
    and joint the pair's error over run 1's, and the median over draws per joint. Run 1 is
    named before run 3 is seen, so no choice after the fact enters (the best single run per
    joint did); least squares + friction on the same draws beside it."""
    runs, nominal = several_runs(arm, seed)
    designs, ratios, peer = _designs(arm, runs), [], []
    for drawn in noise_draws(runs, np.random.default_rng([seed, 6017]), draws):
        first = error_on(fit_runs(arm, drawn, nominal, [0]), drawn[2])
        ratios.append(error_on(fit_runs(arm, drawn, nominal, [0, 1]), drawn[2]) / first)
        peer.append(least_squares_on_runs(arm, drawn, [0, 1], designs)
                    / least_squares_on_runs(arm, drawn, [0], designs))
    return {"seed": seed, "draws": draws, "ratio": np.array(ratios).tolist(),
            "median_ratio": np.median(ratios, axis=0).tolist(),
            "least_squares_median_ratio": np.median(peer, axis=0).tolist()}


def next_run(arm: Arm, seed: int, samples: int = SAMPLES, noise: float = NOISE) -> dict:
    """Every model's relative RMS error per joint on the second run, the joints' torque RMS,
    and the rule's outcome."""
    runs, library = two_runs(arm, seed, samples, noise), arm.library
    first, second = runs.first, runs.second
    states = [np.r_[x, y] for x, y in ((first.q, second.q), (first.qd, second.qd),
                                       (first.qdd, second.qdd))]
    tau, n = np.r_[runs.tau_first, runs.tau_second], len(first.q)
    out = {"nominal": library.evaluate_every(second.q, second.qd, second.qdd) @ runs.nominal,
           "least_squares": least_squares(arm, *states, tau, n)[n:]}
    for name, prior in (("identified", runs.nominal), ("consistent_flat", None)):
        fit = identify(*states, tau, library, len(second.q) / len(tau),
                       regressor=ConsistentRegressor(prior))
        out[name] = fit.model.torque(second.q, second.qd, second.qdd) + fit.model.offsets
    errors = {k: rel_error(v, runs.truth_second) for k, v in out.items()}
    rms = np.sqrt(np.mean(runs.truth_second**2, axis=0))
    carried = rms > rule_threshold(rms)
    ours = errors["identified"]
    holds = (ours <= errors["nominal"]) & (ours <= errors["least_squares"])
    return {"seed": seed, "errors": {k: v.tolist() for k, v in errors.items()},
            "torque_rms": rms.tolist(),
            # *_from_1: joints numbered from 1, as the report's tables number them; the
            # older rule_joints and rule_holds_on index them from 0 (docs/bench.md)
            "rule_joints_from_1": (np.flatnonzero(carried) + 1).tolist(),
            "rule_holds_on_from_1": (np.flatnonzero(carried & holds) + 1).tolist(),
            "rule_joints": np.flatnonzero(carried).tolist(),
            "rule_holds_on": np.flatnonzero(carried & holds).tolist(),
            "median_ratio_to_least_squares": float(np.median(ours / errors["least_squares"]))}


def rule_targets(runs: list[dict]) -> list:
    """The rule's targets over runs: the joints carrying real torque where the identified
    model is at or below both peers (of how many, counted over the runs: a joint once per
    seed), and the worst run's median ratio to least squares."""
    from harness.report.results import Target

    carried = sum(len(r["rule_joints"]) for r in runs)
    held = sum(len(r["rule_holds_on"]) for r in runs)
    over = (f", counted over {len(runs)} seeds ({', '.join(str(r['seed']) for r in runs)}): a "
            "joint once per seed" if len(runs) > 1 else "")
    return [Target(f"next run: joints carrying load (above {RULE_RMS:g} N m RMS, or "
                   f"{LOAD_SHARE:.0%} of the most loaded joint's) where identified (perturbed "
                   "URDF prior) is at or below both the nominal and least squares + friction"
                   + over, held, carried, "joints", lower_is_better=False),
            Target("next run: identified / least squares + friction, median over joints (worst "
                   "run)", max(r["median_ratio_to_least_squares"] for r in runs), 1.0, "x")]


def markdown(runs: list[dict]) -> list[str]:
    names = list(runs[0]["errors"])
    out = ["Next run (harness.identify.next_run): fitted on one run of the project's "
           "excitation with friction, a sensor offset and noise added, the URDF perturbed; "
           "scored on a run of another family (random sines) against its torque without the "
           "noise. Relative RMS error per joint (joints numbered from 1; digits enough to tell "
           "the models apart on each joint):", "",
           "| seed | " + " | ".join(names) + " | joints carrying load | rule holds on |",
           "|---|" + "---|" * (len(names) + 2)]
    for r in runs:
        per_joint = zip(*(r["errors"][n] for n in names), strict=True)
        texts = list(zip(*(distinct(errors) for errors in per_joint), strict=True))
        out.append(f"| {r['seed']} | " + " | ".join(", ".join(t) for t in texts)
                   + f" | {r['rule_joints_from_1']} | {r['rule_holds_on_from_1']} |")
    return out
