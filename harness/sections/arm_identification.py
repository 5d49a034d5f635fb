"""Bench section: identification of any arm from the library generated from its kinematics.

For the bench's robot: independent draws at 5 % noise (`generate(robot, 4000, 0.05, seed)`,
each its own excitation and noise; the first 75 % trains), each identified with the base
atoms of the robot's kinematic chain (identification.library.kinematic; coupled sparse
regression) and by the oracle on the same training samples: two-step weighted least squares
on Pinocchio's joint-torque regressor reduced to base parameters, plus per-joint viscous
and armature columns (the truth's joint terms). Both are judged on one fresh trajectory
(`generate(robot, 4000, 0, FRESH_SEED)`) against its clean torque: relative RMS error per
joint. Noise-free data must be identified exactly. On the Lynxmotion the paper's
hand-derived prior-knowledge library is fitted on the same draws beside the generated one.
Times: library generation (once per robot), each identification, each oracle fit.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from harness.data.generate import generate
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import DEFAULT_ROBOT, load_pinocchio
from harness.robots.torque_models import robot_library
from identification.identify import identify
from identification.library.kinematic import KinematicLibrary
from identification.library.prior_knowledge import prior_knowledge_library
from identification.metrics import rel_error
from identification.regression.oracle import BaseParameterRegression

SAMPLES, NOISE, HOLDOUT, FRESH_SEED = 4000, 0.05, 0.25, 5
SEEDS, QUICK_SEEDS = tuple(range(1, 11)), (1, 2)
MEDIAN_LIMIT, JOINT_LIMIT = 1.2, 1.5  # x oracle: median over joints, every joint
EXACT = 1e-6  # noise-free held-out relative error


def oracle_design(baseline: PinocchioModel, q, qd, qdd) -> np.ndarray:
    """(n, dof, 10 nb + 2 dof): Pinocchio's regressor, then viscous (qd_j) and armature
    (qdd_j) columns acting on joint j alone."""
    n, dof = q.shape
    joint = np.zeros((n, dof, 2 * dof))
    idx = np.arange(dof)
    joint[:, idx, idx], joint[:, idx, dof + idx] = qd, qdd
    return np.concatenate([baseline.regressor(q, qd, qdd), joint], axis=2)


def _draw(robot: str, seed: int, libraries: dict, baseline: PinocchioModel, fresh) -> dict:
    data = generate(robot, SAMPLES, NOISE, seed, "inverse")
    n = int(round(SAMPLES * (1 - HOLDOUT)))
    out: dict = {"seed": seed}
    for name, library in libraries.items():
        cpu = time.process_time()  # one BLAS thread: CPU time is the load-free cost
        result = identify(data.q, data.qd, data.qdd, data.tau, library, HOLDOUT, data.tau_clean)
        cpu = time.process_time() - cpu
        out[name] = {"fresh": rel_error(result.model.torque(fresh.q, fresh.qd, fresh.qdd),
                                        fresh.tau_clean).tolist(), "seconds": result.seconds,
                     "cpu_seconds": cpu}
    start, cpu = time.perf_counter(), time.process_time()
    oracle = BaseParameterRegression().fit(oracle_design(baseline, data.q[:n], data.qd[:n],
                                                         data.qdd[:n]), data.tau[:n])
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    predicted = oracle.predict(oracle_design(baseline, fresh.q, fresh.qd, fresh.qdd))
    out["oracle"] = {"fresh": rel_error(predicted, fresh.tau_clean).tolist(), "seconds": seconds,
                     "cpu_seconds": cpu, "parameters": len(oracle.columns_)}
    return out


def _summary(draws: list[dict], method: str) -> dict:
    ratios = np.array([np.array(d[method]["fresh"]) / np.array(d["oracle"]["fresh"]) for d in draws])
    ok = [bool(np.median(r) <= MEDIAN_LIMIT and r.max() <= JOINT_LIMIT) for r in ratios]
    return {"median_ratio_per_draw": np.median(ratios, axis=1).tolist(),
            "max_ratio_per_draw": ratios.max(axis=1).tolist(),
            "median_ratio_per_joint": np.median(ratios, axis=0).tolist(),
            "draws_within": int(sum(ok)), "draws": len(draws),
            "seconds_median": float(np.median([d[method]["seconds"] for d in draws])),
            "cpu_seconds_median": float(np.median([d[method]["cpu_seconds"] for d in draws]))}


def run(out_dir: Path, quick: bool = False, robot: str = DEFAULT_ROBOT) -> dict:
    start = time.perf_counter()
    robot_library.cache_clear()
    tic = time.perf_counter()
    generated = robot_library(robot)
    generated.function  # noqa: B018 - the CasADi function is part of the generation time
    generation_s = time.perf_counter() - tic
    libraries: dict = {"kinematic": generated}
    if robot == DEFAULT_ROBOT:
        libraries["prior"] = prior_knowledge_library(3)
    baseline = PinocchioModel(load_pinocchio(robot))
    fresh = generate(robot, SAMPLES, 0.0, FRESH_SEED, "inverse")
    clean = generate(robot, SAMPLES, 0.0, 1, "inverse")
    exact = identify(clean.q, clean.qd, clean.qdd, clean.tau, generated, HOLDOUT, clean.tau_clean)
    draws = [_draw(robot, s, libraries, baseline, fresh) for s in (QUICK_SEEDS if quick else SEEDS)]
    summaries = {m: _summary(draws, m) for m in libraries}
    acceptance = {"noise_free_exact": bool(np.max(exact.heldout_rel_rmse) <= EXACT),
                  f"every_draw_median_{MEDIAN_LIMIT}x_joints_{JOINT_LIMIT}x_oracle":
                      summaries["kinematic"]["draws_within"] == len(draws)}
    results = {"robot": robot, "library_atoms": len(generated), "library_names": generated.names,
               "generation_s": generation_s, "noise_free_heldout": exact.heldout_rel_rmse.tolist(),
               "draws": draws, "summary": summaries, "acceptance": acceptance,
               "oracle_parameters": draws[0]["oracle"]["parameters"],
               "oracle_seconds_median": float(np.median([d["oracle"]["seconds"] for d in draws])),
               "oracle_cpu_seconds_median": float(np.median([d["oracle"]["cpu_seconds"]
                                                             for d in draws])),
               "seconds": time.perf_counter() - start}
    results["headline"] = _headline(results)
    return {"markdown": "\n".join(_markdown(results, generated)), "results": results, "figures": []}


def _headline(r: dict) -> dict:
    k = r["summary"]["kinematic"]
    return {"generated library: base atoms": r["library_atoms"],
            "draws within the oracle bars": f"{k['draws_within']} of {k['draws']}",
            "worst draw: median / max joint ratio to oracle":
                f"{max(k['median_ratio_per_draw']):.2f} / {max(k['max_ratio_per_draw']):.2f}",
            "identification s (median) / oracle s": f"{k['seconds_median']:.2f} / "
                                                    f"{r['oracle_seconds_median']:.2f}"}


def _markdown(r: dict, library: KinematicLibrary) -> list[str]:
    k = r["summary"]["kinematic"]
    md = [f"Robot `{r['robot']}` ({library.dof} joints): {r['library_atoms']} base atoms generated "
          f"from its kinematics in {r['generation_s']:.2f} s; the oracle fits "
          f"{r['oracle_parameters']} base parameters + offsets. {k['draws']} draws at "
          f"{NOISE:.0%} noise, {SAMPLES} samples; errors on a fresh trajectory against its clean "
          f"torque. Noise-free held-out error (max over joints): "
          f"{max(r['noise_free_heldout']):.1e} (bar {EXACT:g}).", "",
          "| method | joint | median ratio to oracle over draws | draws within bars | "
          "identification s (median): wall / CPU |", "|---|---|---|---|---|"]
    for method, s in r["summary"].items():
        for j, x in enumerate(s["median_ratio_per_joint"]):
            md.append(f"| {method} | {j + 1} | {x:.2f} | {s['draws_within']}/{s['draws']} | "
                      f"{s['seconds_median']:.2f} / {s['cpu_seconds_median']:.2f} |")
    md += ["", f"Bars per draw: median over joints <= {MEDIAN_LIMIT} x oracle, every joint <= "
           f"{JOINT_LIMIT} x. Worst draw: median {max(k['median_ratio_per_draw']):.2f}, joint "
           f"{max(k['max_ratio_per_draw']):.2f}. Oracle fit (median) "
           f"{r['oracle_seconds_median']:.2f} s wall, {r['oracle_cpu_seconds_median']:.2f} s CPU "
           "(wall times grow with the machine's load; CPU times do not)."]
    return md
