"""Bench section "identification": the robot's torque model learned from noisy data.

For any robot: independent draws at 5 % noise (`generate(robot, 4000, 0.05, seed)`, each its
own excitation and noise; the first 75 % trains), identified with every library the robot's
registry entry offers (the kinematic base atoms for any arm; the Lynxmotion also its
prior-knowledge and published libraries) and by the oracle on the same samples
(harness.identify.scoring). All are judged on two motions never fitted: a fresh
run of the project's excitation and a motion of another family (random sines).

Checks (must hold): Pinocchio's RNEA and MuJoCo's inverse dynamics agree on the judge motion
(two implementations of one model); noise-free data are identified exactly by the robot's
default library and by the oracle. Targets: the default library's error within 1.1 x the
oracle's at the median over joints and 1.6 x on every joint, on the motion of the other
family. Over many draws: the study identification_draws' targets (median <= 1.1 x and worst
draw-joint <= 2 x the oracle per joint) on its scored draws, the oracle on another noise draw
beside as a reference. The model of the default library on the first draw is handed to
planning.
"""

from __future__ import annotations

import numpy as np

from harness.data.generate import generate
from harness.identify.excitation import excitation_comparison
from harness.identify.excitation import markdown as excitation_markdown
from harness.identify.fits import arm_identification
from harness.identify.library_gap import library_gap
from harness.identify.library_gap import markdown as gap_markdown
from harness.identify.next_run import markdown as next_run_markdown
from harness.identify.next_run import (
    next_run,
    pair_against_first,
    rule_targets,
)
from harness.identify.scoring import (
    FLAT,
    HOLDOUT,
    NOISE,
    ORACLE,
    PRIOR,
    SAMPLES,
    closed_form_gap,
    fixed_fit,
    generated_motion,
    perturbed_prior_fit,
    ratio_summary,
    score_draw,
    sines_motion,
)
from harness.report.results import Context, Row, SectionResult, Target, check
from harness.robots.extras import extra as load_extra
from harness.studies import identification_draws as over_draws
from identification.identify import identify

# draws (seeds) per torque noise level; the paper's level, 5 %, gets the most. Seeds from
# 101 on: the identification's thresholds were chosen on seeds 1-10 (the earlier arm check)
# and the consistent fit's TIE on seeds 601-622 (study prior_tie), so the draws scored here
# were not used to choose them; each level has draws of its own
# (one draw rescaled would give the same ratios at every level wherever the selection holds)
LEVELS = {0.02: (201, 202, 203), NOISE: (101, 102, 103, 104, 105), 0.10: (301, 302, 303)}
QUICK_LEVELS = {NOISE: (101, 102)}
NEXT_RUNS, QUICK_NEXT_RUNS = (401, 402), (401,)  # seeds of the next-run experiment
# runs 1 + 2 against run 1: drawn once (numpy.random.default_rng().integers(10_000, size=2),
# 2026-12-07), no setting chosen on them; PAIR_DRAWS noise draws each (full bench only)
PAIR_SEEDS, PAIR_DRAWS = (3227, 2220), 8
FRESH_SEED = 1005
EXACT = 1e-6  # noise-free held-out relative error
AGREEMENT = 1e-9  # Pinocchio vs MuJoCo, relative to the largest torque
MEDIAN_TARGET, JOINT_TARGET = 1.1, 1.6  # x oracle on the other family's motion


def run(ctx: Context) -> SectionResult:
    arm = ctx.arm
    fits = {name: fixed_fit(*arm_identification(arm, library=name))
            for name in arm.entry.libraries}
    default = arm.entry.libraries[0]
    baseline = arm.nominal
    fits[PRIOR] = perturbed_prior_fit(arm.library, baseline, arm.ellipsoids)
    fits[FLAT] = fixed_fit(*arm_identification(arm, prior="flat"))
    judges = [generated_motion(arm, SAMPLES, FRESH_SEED), sines_motion(arm, SAMPLES, FRESH_SEED)]
    clean = generate(arm, SAMPLES, 0.0, 1, "inverse")
    exact = identify(clean.q, clean.qd, clean.qdd, clean.tau, fits[default].library, HOLDOUT,
                     clean.tau_clean, fits[default].regressor(1))
    exact_oracle = score_draw(clean, {}, baseline, judges[:1])["oracle"]["fresh"]
    levels = QUICK_LEVELS if ctx.quick else LEVELS
    by_level = {level: [score_draw(generate(arm, SAMPLES, level, seed, "inverse"), fits,
                                   baseline, judges) for seed in seeds]
                for level, seeds in levels.items()}
    draws = by_level[NOISE]
    model = draws[0]["models"][default]
    gap = closed_form_gap(arm, judges[1])
    checks = [
        check("pinocchio_agrees_with_mujoco", gap <= AGREEMENT,
              f"max |RNEA - mj_inverse| / max |tau| = {gap:.1e} (bar {AGREEMENT:g})"),
        check(f"noise_free_exact_{default}", np.max(exact.heldout_rel_rmse) <= EXACT,
              f"held-out error {np.max(exact.heldout_rel_rmse):.1e} (bar {EXACT:g})"),
        check("noise_free_exact_oracle", max(exact_oracle) <= EXACT,
              f"fresh-motion error {max(exact_oracle):.1e} (bar {EXACT:g})"),
    ]
    bounded = [d[name]["plausible"] for d in sum(by_level.values(), []) for name in (PRIOR, FLAT)
               if "plausible" in d[name]]
    checks.append(check("consistent_fits_plausible", bounded and all(all(b) for b in bounded),
                        f"{sum(all(b) for b in bounded)} of {len(bounded)} consistent fits with "
                        "every body inside its link's ellipsoid"))
    summary = {f"{level:g}": {name: {judge: ratio_summary(d, name, judge)
                                     for judge in ("fresh", "sines")} for name in fits}
               for level, d in by_level.items()}
    targets = []
    for level, by_name in summary.items():
        for name in (default, PRIOR):
            worst = by_name[name]["sines"]
            targets += [
                Target(f"{name} / oracle error at {100 * float(level):g} % noise, median over "
                       "joints (worst draw, other excitation)", worst["worst_median"],
                       MEDIAN_TARGET, "x"),
                Target(f"{name} / oracle error at {100 * float(level):g} % noise, worst joint "
                       "(worst draw, other excitation)", worst["worst_joint"], JOINT_TARGET, "x")]
    targets += [
        Target(f"{default} identification CPU time, median over draws",
               float(np.median([d[default]["timing"]["cpu_s"] for d in draws])), 30.0, "s",
               timing=True),
        Target(f"{PRIOR} identification CPU time (LMI included), median over draws",
               float(np.median([d[PRIOR]["timing"]["cpu_s"] for d in draws])), 30.0, "s",
               timing=True)]
    runs = [next_run(arm, seed) for seed in (QUICK_NEXT_RUNS if ctx.quick else NEXT_RUNS)]
    targets += rule_targets(runs)
    pairs = [] if ctx.quick else [pair_against_first(arm, seed, PAIR_DRAWS) for seed in PAIR_SEEDS]
    if pairs:  # runs 1 + 2 against run 1 alone, on run 3, over draws of the noise
        targets.append(Target("runs 1 + 2 fitted together / run 1 alone, on run 3: worst joint's "
                              f"median over {PAIR_DRAWS} noise draws (worst of seeds "
                              f"{', '.join(map(str, PAIR_SEEDS))}, fresh)",
                              max(max(p["median_ratio"]) for p in pairs), 1.0, "x"))
    draws_study = _over_draws(arm, ctx.quick)
    targets += over_draws.study_targets(arm.reference, draws_study)
    excitation_targets, excitation = excitation_comparison(
        arm, fits[default], default, baseline, ctx.quick)
    targets += excitation_targets
    errors = np.median([d[default]["sines"] for d in draws], axis=0)
    oracle = np.median([d["oracle"]["sines"] for d in draws], axis=0)
    headline = [Row(f"Identified torque model ({default} library, {100 * NOISE:g} % noise, {SAMPLES} "
                    "samples): error on a motion of another excitation family, per joint "
                    f"(median over draws), against the oracle's ({ORACLE}: a fit that uses prior "
                    "knowledge can beat it, and that is not an error)",
                    ", ".join(f"{100 * e:.2f} %" for e in errors) + " (oracle "
                    + ", ".join(f"{100 * o:.2f} %" for o in oracle) + ")")]
    results = {"robot": arm.reference, "libraries": list(fits), "default_library": default,
               "samples": SAMPLES, "noise": NOISE, "closed_form_gap": gap,
               "noise_free_heldout": exact.heldout_rel_rmse.tolist(),
               "oracle_parameters": draws[0]["oracle_parameters"],
               "draws": {f"{level:g}": [{k: v for k, v in d.items() if k != "models"} for d in ds]
                         for level, ds in by_level.items()},
               "summary": summary, "next_run": runs, "pair_against_first": pairs,
               "excitation": excitation, "over_draws": draws_study}
    note = []
    if "paper" in fits and hasattr(exact.model, "features"):  # why the paper's rows miss
        gap = library_gap(fits["paper"].library, exact.model, fits[default].library, judges,
                          clean, int(round(len(clean.q) * (1 - HOLDOUT))))
        oracles = {j.name: np.median([d["oracle"][j.name] for d in draws], axis=0) for j in judges}
        results["paper_library_gap"], note = gap, ["", gap_markdown(gap, oracles, NOISE)]
    md = "\n".join([_markdown(results, fits), *note, "", *next_run_markdown(runs), "",
                    *_pairs_markdown(pairs),
                    *over_draws.markdown(draws_study, "Over many draws (`torquebench study "
                                         "identification_draws`, the default fit)"), "",
                    *excitation_markdown(excitation)])
    out = SectionResult(md, results, checks, targets, headline,
                        outputs={"model": model, "draws": draws})
    for extra in arm.entry.extras:
        out.extend(load_extra(extra).identification(ctx), extra)
    return out


def _over_draws(arm, quick: bool) -> dict:
    """The study identification_draws' default fit on this arm (its data, judges and oracle)
    on the study's scored draws (FRESH_SEEDS, FRESH_JUDGE, every noise level; quick: one seed
    at 5 %), the twin oracle beside: the bench's targets over many draws are the study's."""
    return over_draws.study(arm, {"default": over_draws.named_fit(arm, {})},
                            over_draws.FRESH_SEEDS[:1] if quick else over_draws.FRESH_SEEDS,
                            over_draws.FRESH_JUDGE, (NOISE,) if quick else over_draws.NOISES)


def _pairs_markdown(pairs: list[dict]) -> list[str]:
    """Runs 1 + 2 against run 1 alone, per seed: the median ratio per joint."""
    return [f"Runs 1 + 2 fitted together against run 1 alone, on run 3 (`identify --prior "
            f"nominal`; seed {p['seed']}, median over {p['draws']} noise draws, per joint): "
            + ", ".join(f"{r:.3f}" for r in p["median_ratio"]) + "; least squares + friction: "
            + ", ".join(f"{r:.3f}" for r in p["least_squares_median_ratio"]) + "." for p in pairs] \
        + ([""] if pairs else [])


def _markdown(r: dict, fits: dict) -> str:
    counts = ", ".join(f"{len(d)} at {100 * float(level):g} %" for level, d in r["draws"].items())
    md = [f"Robot `{r['robot']}`: draws at each torque noise level ({counts}; noise std = level "
          f"x each joint's torque std), {SAMPLES} samples each (first {100 * (1 - HOLDOUT):g} % "
          "trains). Errors: relative RMS "
          "against the clean torque on two motions never fitted: `fresh` (the project's "
          "excitation, another seed) and `sines` (another family: random sines per joint). "
          f"The oracle ({ORACLE}) fits {r['oracle_parameters']} base parameters + joint terms "
          "on the same samples; a ratio below 1 is a fit whose prior knowledge (sparsity, the "
          "consistency constraints, a nominal model) beat it, not an error.", "",
          "| noise | library | features | motion | ratio to the oracle per joint (median over "
          "draws) | worst draw: median / worst joint |", "|---|---|---|---|---|---|"]
    for level, by_name in r["summary"].items():
        for name, by_judge in by_name.items():
            for judge, s in by_judge.items():
                md.append(f"| {100 * float(level):g} % | {name} | {fits[name].parameters} | {judge} | "
                          + ", ".join(f"{x:.2f}" for x in s["median_ratio_per_joint"])
                          + f" | {s['worst_median']:.2f} / {s['worst_joint']:.2f} |")
    return "\n".join(md)
