"""Bench section: coupled and per-joint sparse identification vs the base-parameter oracle
and pysindy (paper Figs. 2-8, Tables III, IV).

Data: the default robot, `generate('lynxmotion', 4000, noise, seed=0)`, last 25 % held
out; a fresh excitation (seed 5) checks that the model predicts a trajectory it was not
trained on. The noise is drawn here from the clean torque with harness.data.sensors's
`torque_noise` (std = level x each joint's torque std, mean 0.2 std) and
`np.random.default_rng(seed)`. Each level gets its own draw (NOISE_SEEDS): seed 1 at
5 % is exactly the default data (generate(..., seed=0) draws its noise with seed 1),
1 % and 10 % use seeds 11 and 13, so the four rows are four experiments, not one draw
rescaled. Robustness: ROBUST_SEEDS, twenty independent draws at 5 % (ten in quick
mode; the first is the default data), each fitted by every method and by the oracle on
the same draw.

Methods: *per-joint* (the paper: each joint alone on the library features), *coupled*
(one Lagrangian of shared atoms; symmetric links, the default), *coupled general* (the
same without the symmetric-link assumption: sine companions and products of inertia),
*oracle* (two-step WLS on Pinocchio's base-parameter regressor: 16 dense base
parameters, the issue's reference; the truth is sparse in the atoms, so a sparse fit can
beat it: it is not an upper bound), *true support* (two-step WLS on exactly the true
atoms: what a perfect selector reaches on the draw; coupled / true support = 1 means the
selection cost nothing). Peers: pysindy STLSQ (threshold) and SSR (stopping point on its
elimination path), each swept and chosen on our validation blocks inside the training
part (identification.regression.peers); every reported time includes its sweep. Denoise then
regress: the coupled fit on the GCV-denoised training torque beside the raw one at every
noisy level (identification.identify's docstring summarizes the outcome). "True terms" are the
library features with a non-zero coefficient in the exact noise-free least-squares fit
of the library; "true atoms" likewise for the Lagrangian atoms.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from harness.data.generate import generate
from harness.data.sensors import torque_noise
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from identification.identify import identify
from identification.library.prior_knowledge import prior_knowledge_library
from identification.library.published import paper_library
from identification.metrics import rel_error
from identification.regression.coupled import AtomBasis, CoupledRegression, weighted_lstsq
from identification.regression.denoise import denoise
from identification.regression.oracle import fit_base_parameters
from identification.regression.peers import tune
from identification.table4 import CONSISTENT_DOUBLE_PENDULUM, SYSTEMS, fit_system

LEVELS = (0.0, 0.01, 0.05, 0.10)
QUICK_LEVELS = (0.0, 0.05)
NOISE_SEEDS = {0.0: 1, 0.01: 11, 0.05: 1, 0.10: 13}  # one independent draw per level
ROBUST_SEEDS = tuple(1 + 1000 * k for k in range(20))  # at 5 %: 1, 1001, ..., 19001
QUICK_ROBUST_SEEDS = ROBUST_SEEDS[:10]
HOLDOUT = 0.25
# (label, identify method, library key): the paper's method and the two atom sets
METHODS = (("per-joint", "per-joint", "symmetric"), ("coupled", "coupled", "symmetric"),
           ("coupled general", "coupled", "general"))
RATIO_LIMIT = 1.25


def noisy(clean, level: float, seed: int = 1):
    """clean with torque noise at `level` drawn by default_rng(seed); seed 1 gives the
    dataset generate(..., noise=level, seed=0) returns."""
    rng = np.random.default_rng(seed)
    return dataclasses.replace(clean, tau=clean.tau_clean + torque_noise(clean.tau_clean, level, 0.2, rng))


def _nonzero(design: np.ndarray, target: np.ndarray, names: list[str]) -> set[str]:
    coef = np.linalg.lstsq(design, target, rcond=None)[0]
    big = np.abs(coef) * np.linalg.norm(design, axis=0) > 1e-9 * np.linalg.norm(target)
    return {n for n, b in zip(names, big, strict=True) if b}


def true_terms(lib, d) -> list[set[str]]:
    """Per joint, the features with non-zero coefficient in the noise-free library fit."""
    theta = lib.evaluate(d.q, d.qd, d.qdd)
    return [_nonzero(theta, d.tau_clean[:, j], lib.names) for j in range(d.q.shape[1])]


def true_atoms(basis: AtomBasis, d) -> set[str]:
    design = basis.evaluate(d.q, d.qd, d.qdd)
    return _nonzero(design.reshape(-1, design.shape[-1]), d.tau_clean.reshape(-1), basis.names)


def n_train(n: int) -> int:
    """Training samples: the first 1 - HOLDOUT, as identify splits."""
    return int(round(n * (1 - HOLDOUT)))


def _pysindy(ctx: dict, d) -> dict:
    """pysindy STLSQ and SSR on the symmetric library, each joint's hyper-parameter swept and
    chosen on our validation blocks inside the training part (identification.regression.peers);
    seconds include the sweep, like identify's."""
    theta, names, truth = ctx["theta"], ctx["library"].names, ctx["truth"]["symmetric"]
    out, k = {}, n_train(len(d.tau))
    for name in ("STLSQ", "SSR"):
        fits = [tune(name, theta[:k], d.tau[:k, j]) for j in range(d.tau.shape[1])]
        coef = np.column_stack([f.coef for f in fits])
        kept = [{names[i] for i in np.flatnonzero(f.coef)} for f in fits]
        out[name] = {"seconds": sum(f.seconds for f in fits), "setting_name": fits[0].setting_name,
                     "setting": [f.setting for f in fits],
                     "rel": rel_error(theta[k:] @ coef, d.tau_clean[k:]).tolist(),
                     "terms": [len(s) for s in kept],
                     "recall": [len(s & t) / len(t) for s, t in zip(kept, truth, strict=True)],
                     "precision": [len(s & t) / max(len(s), 1) for s, t in zip(kept, truth, strict=True)]}
    return out


def true_support(ctx: dict, d, key: str = "symmetric") -> np.ndarray:
    """Per-joint held-out error of two-step weighted least squares on exactly the true atoms
    (+ per-joint offsets): what a perfect selector would reach on this draw."""
    basis, k = ctx["bases"][key], n_train(len(d.q))
    cols = [basis.names.index(a) for a in sorted(ctx["atoms"][key])]
    design = basis.evaluate(d.q, d.qd, d.qdd)
    sigma = CoupledRegression().noise_sigma(design[:k], d.tau[:k], cols)
    coef = weighted_lstsq(design[:k], d.tau[:k], cols, sigma)[0]
    return rel_error(design[k:][:, :, cols] @ coef, d.tau_clean[k:])


def _scores(r, truth: list[set[str]], fresh) -> list[dict]:
    rows = []
    frel = None if fresh is None else rel_error(r.model.torque(fresh.q, fresh.qd, fresh.qdd), fresh.tau_clean)
    for j, jm in enumerate(r.model.joints):
        hit = len(set(jm.terms) & truth[j])
        rows.append({"rel": float(r.heldout_rel_rmse[j]), "mse": float(r.heldout_mse[j]),
                     "recall": hit / len(truth[j]), "precision": hit / max(len(jm.terms), 1),
                     "terms": len(jm.terms), "fresh": None if frel is None else float(frel[j])})
    return rows


def fit_methods(d, ctx: dict, fresh=None) -> dict:
    """Every method of METHODS on dataset d, scored; plus the oracle's per-joint error."""
    out: dict = {"fits": {}}
    for label, method, key in METHODS:
        lib = ctx["libraries"][key]
        r = identify(d.q, d.qd, d.qdd, d.tau, lib, HOLDOUT, d.tau_clean, method=method)
        out["fits"][label] = r
        out[label] = {"joints": _scores(r, ctx["truth"][key], fresh), "seconds": r.seconds,
                      "equations": r.model.equations(), "alpha": [f.alpha_ for f in r.regressions],
                      "pass_rate": [f.pass_rate_ for f in r.regressions]}
        if method == "coupled":
            lag, atoms = r.lagrangian(), ctx["atoms"][key]
            kept = set(lag["atoms"])
            out[label].update(lagrangian=lag, atom_recall=len(kept & atoms) / len(atoms),
                              atom_precision=len(kept & atoms) / max(len(kept), 1))
    k = n_train(len(d.q))
    ofit = fit_base_parameters(ctx["regressor"][:k], d.tau[:k])
    out["oracle"] = rel_error(ofit.predict(ctx["regressor"][k:]), d.tau_clean[k:]).tolist()
    out["oracle_parameters"] = len(ofit.columns)
    out["true_support"] = true_support(ctx, d).tolist()
    return out


def compare(level: float, ctx: dict, with_pysindy: bool = True, seed: int | None = None) -> dict:
    """All methods, the oracle (and pysindy) at one noise level; seed None: NOISE_SEEDS."""
    d = noisy(ctx["clean"], level, NOISE_SEEDS.get(level, 1) if seed is None else seed)
    out = fit_methods(d, ctx, ctx["fresh"])
    if with_pysindy:
        out["pysindy"] = _pysindy(ctx, d)
    out["data"] = d
    return out


def context() -> dict:
    """Default data (clean), fresh trajectory, both libraries, their truths and the regressor."""
    with threadpool_limits(limits=1, user_api="blas"):
        return _context()


def _context() -> dict:
    clean = generate("lynxmotion", 4000, 0.0, seed=0)
    fresh = generate("lynxmotion", 4000, 0.0, seed=5)
    libs = {"symmetric": prior_knowledge_library(3), "general": prior_knowledge_library(3, False)}
    bases = {k: AtomBasis.from_atoms(v.atoms, 3) for k, v in libs.items()}
    lib = libs["symmetric"]
    return {"clean": clean, "fresh": fresh, "library": lib, "libraries": libs, "basis": bases["symmetric"],
            "bases": bases,
            "regressor": PinocchioModel(load_pinocchio("lynxmotion")).regressor(clean.q, clean.qd, clean.qdd),
            "theta": lib.evaluate(clean.q, clean.qd, clean.qdd),
            "truth": {k: true_terms(v, clean) for k, v in libs.items()},
            "atoms": {k: true_atoms(b, clean) for k, b in bases.items()}}


TABLE_HEAD = ["| noise (seed) | joint | paper per-joint | coupled | coupled general "
              "| oracle: dense WLS, base params (reference, not a bound) "
              "| true support: WLS on the true atoms (perfect selector) "
              "| coupled / oracle (acceptance) | coupled / true support | general / oracle "
              "| pysindy STLSQ (tuned) | pysindy SSR (tuned) "
              "| recall / precision: per-joint, coupled, general "
              "| fresh traj. coupled (x held-out) |", "|---" * 14 + "|"]


def _ratio(x: float, oracle: float) -> str:
    return f"{x / oracle:.2f}" if oracle > 1e-12 else "-"


def table_rows(level: float, c: dict, seed: int | None = None) -> list[str]:
    rows, seed = [], NOISE_SEEDS.get(level, 1) if seed is None else seed
    for j in range(3):
        pj, cp, gn = (c[m]["joints"][j] for m, _, _ in METHODS)
        orc, tsp, ps = c["oracle"][j], c["true_support"][j], c.get("pysindy", {})
        peers = [f"{ps[k]['rel'][j]:.2e}" if k in ps else "-" for k in ("STLSQ", "SSR")]
        rp = ", ".join(f"{x['recall']:.2f} / {x['precision']:.2f}" for x in (pj, cp, gn))
        rows.append(f"| {100 * level:g} % ({seed}) | {j + 1} | {pj['rel']:.2e} | {cp['rel']:.2e} | "
                    f"{gn['rel']:.2e} | {orc:.2e} | {tsp:.2e} | {_ratio(cp['rel'], orc)} | "
                    f"{_ratio(cp['rel'], tsp)} | {_ratio(gn['rel'], orc)} | "
                    f"{peers[0]} | {peers[1]} | {rp} | {cp['fresh']:.2e} "
                    f"({cp['fresh'] / max(cp['rel'], 1e-300):.2f}) |")
    return rows


def robustness(ctx: dict, seeds=ROBUST_SEEDS, level: float = 0.05) -> dict:
    """Every method on independent noise draws at `level`: per draw and summarized."""
    draws = [fit_methods(noisy(ctx["clean"], level, s), ctx) for s in seeds]
    oracle = np.array([d["oracle"] for d in draws])
    support = np.array([d["true_support"] for d in draws])
    out: dict = {"level": level, "seeds": list(seeds), "oracle": oracle.tolist(),
                 "true_support": support.tolist(), "methods": {}}
    for label, _, _ in METHODS:
        rel = np.array([[j["rel"] for j in d[label]["joints"]] for d in draws])
        ratio = rel / oracle
        recall, precision = ([[j[k] for j in d[label]["joints"]] for d in draws]
                             for k in ("recall", "precision"))
        out["methods"][label] = {
            "rel": rel.tolist(), "ratio_median": np.median(ratio, 0).tolist(),
            "ratio_worst": ratio.max(0).tolist(), "worst_seed": [seeds[i] for i in ratio.argmax(0)],
            "rms_ratio": (np.sqrt((rel**2).mean(0)) / np.sqrt((oracle**2).mean(0))).tolist(),
            "rms_ratio_true_support": (np.sqrt((rel**2).mean(0))
                                       / np.sqrt((support**2).mean(0))).tolist(),
            "draws_within_limit": int(np.sum(np.all(ratio <= RATIO_LIMIT, axis=1))),
            "recall_min": np.min(recall, 0).tolist(), "precision_min": np.min(precision, 0).tolist(),
            "below_0.5pct": bool(np.all(rel <= 0.005)),
            "seconds_mean": float(np.mean([d[label]["seconds"] for d in draws]))}
        if "lagrangian" in draws[0][label]:
            out["methods"][label]["atoms"] = [d[label]["lagrangian"]["atoms"] for d in draws]
    return out


def robustness_markdown(rob: dict) -> list[str]:
    n, lv = len(rob["seeds"]), 100 * rob["level"]
    first = "; the first is the default data" if rob["level"] == 0.05 and rob["seeds"][0] == 1 else ""
    md = ["", f"Robustness: {n} independent noise draws at {lv:g} % (seeds "
          f"{', '.join(map(str, rob['seeds']))}{first}). Per joint: "
          "median and worst ratio of the held-out error to the oracle's on the same draw "
          "(seed of the worst), ratio of the RMS errors over the draws to the oracle's and to "
          "the true-support fit's (WLS on exactly the true atoms: the bar of a perfect "
          "selector; the dense oracle is a reference, not a bound), smallest recall / "
          f"precision of the true terms; draws with every joint within {RATIO_LIMIT} x the "
          "oracle.", "",
          "| method | joint | median / oracle | worst / oracle (seed) | RMS over draws / oracle's "
          "| RMS / true support's | min recall / min precision | draws within limit | fit s |",
          "|---|---|---|---|---|---|---|---|---|"]
    for label, m in rob["methods"].items():
        for j in range(len(m["ratio_median"])):
            md.append(f"| {label} | {j + 1} | {m['ratio_median'][j]:.2f} | {m['ratio_worst'][j]:.2f} "
                      f"({m['worst_seed'][j]}) | {m['rms_ratio'][j]:.2f} | "
                      f"{m['rms_ratio_true_support'][j]:.2f} | {m['recall_min'][j]:.2f} / "
                      f"{m['precision_min'][j]:.2f} | {m['draws_within_limit']}/{n} | "
                      f"{m['seconds_mean']:.2f} |")
    return md


def acceptance(c5: dict, c0: dict, rob: dict | None = None) -> dict:
    """Issue #3 checks on the default (coupled) method at 5 % (default data), and over draws."""
    j5, j0 = c5["coupled"]["joints"], c0["coupled"]["joints"]
    rel = np.array([j["rel"] for j in j5])
    out = {
        "noise_free_exact": bool(all(j["rel"] <= 1e-8 and j["recall"] == 1 and j["precision"] == 1
                                     for j in j0)),
        "ratio_to_oracle": (rel / np.array(c5["oracle"])).tolist(),
        "ratio_to_true_support": (rel / np.array(c5["true_support"])).tolist(),
        "within_1.25x_oracle": bool(np.all(rel <= RATIO_LIMIT * np.array(c5["oracle"]))),
        "below_0.5pct": bool(np.all(rel <= 0.005)),
        "recall_100": bool(all(j["recall"] == 1 for j in j5)),
        "precision_90": bool(all(j["precision"] >= 0.9 for j in j5)),
        "fresh_within_1.5x": bool(all(j["fresh"] <= 1.5 * j["rel"] for j in j5)),
    }
    if rob is not None:
        m = rob["methods"]["coupled"]
        out.update({"every_draw_within_1.25x_oracle": m["draws_within_limit"] == len(rob["seeds"]),
                    "median_draw_within_1.25x_oracle": bool(max(m["ratio_median"]) <= RATIO_LIMIT),
                    "every_draw_below_0.5pct": m["below_0.5pct"],
                    "every_draw_recall_100": bool(min(m["recall_min"]) == 1),
                    "every_draw_precision_90": bool(min(m["precision_min"]) >= 0.9)})
    return out


def _figures(fig_dir: Path, ctx: dict, c5: dict) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    clean, d = ctx["clean"], c5["data"]
    figs = [fig_dir / "identification_denoise.png", fig_dir / "identification_alpha.png",
            fig_dir / "identification_fit.png"]
    dn = denoise(d.tau)
    fig, ax = plt.subplots(figsize=(8, 3))
    ax.plot(clean.t[:800], d.tau[:800, 0], lw=0.5, label="measured")
    ax.plot(clean.t[:800], dn.signal[:800, 0], lw=1, label="denoised")
    ax.plot(clean.t[:800], clean.tau_clean[:800, 0], "k--", lw=0.8, label="clean")
    ax.set(xlabel="t (s)", ylabel="tau1 (N m)", title="Denoising at 5 % noise (cf. Fig. 2)")
    ax.legend()
    fig.savefig(figs[0], dpi=110, bbox_inches="tight")
    _alpha_figure(plt, figs[1], c5)
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    k = n_train(len(clean.q))
    pred = c5["fits"]["coupled"].model.torque(clean.q, clean.qd, clean.qdd)
    for j, ax in enumerate(axes):
        ax.plot(clean.t[k:], clean.tau_clean[k:, j], "k", lw=1, label="Pinocchio (clean)")
        ax.plot(clean.t[k:], pred[k:, j], "r--", lw=1, label="identified (coupled)")
        ax.set(ylabel=f"tau{j + 1} (N m)")
    axes[0].legend()
    axes[-1].set(xlabel="t (s), held-out part (cf. Figs. 6-8)")
    fig.savefig(figs[2], dpi=110, bbox_inches="tight")
    plt.close("all")
    return figs


def _alpha_figure(plt, path: Path, c5: dict) -> None:
    """Figs. 3-5: validation error vs Lasso alpha, one panel per joint, both methods."""
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.2))
    per_joint, coupled = c5["fits"]["per-joint"].regressions, c5["fits"]["coupled"].regressions[0]
    sigma2 = coupled.sigma_**2
    for j, ax in enumerate(axes):
        best: dict[float, float] = {}
        for c in per_joint[j].candidates_:
            best[c.alpha] = min(best.get(c.alpha, np.inf), c.validation_mse)
        a = sorted(best)
        ax.loglog(a, [best[x] / sigma2[j] for x in a], ".-", label="per-joint (paper)")
        ax.axvline(per_joint[j].alpha_, color="C0", lw=0.8, ls=":")
        alphas = [p[0] for p in coupled.path_]
        ax.loglog(alphas, [p[1][j] for p in coupled.path_], ".-", label="coupled")
        ax.axvline(coupled.alpha_, color="C1", lw=0.8, ls=":")
        ax.set(xlabel="Lasso alpha (standardized)", ylabel="validation MSE / noise var.",
               title=f"tau{j + 1} (cf. Fig. {3 + j})")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _table4_markdown(fits) -> list[str]:
    md = ["", "Table IV at 5 % noise (4000 samples, 60 s multi-sine; +/- = standard error of "
          "the refit; libraries derived from each structure's atoms where known):", "",
          "| system | method | eq. | term | true | paper identified | ours +/- s.e. | error |",
          "|---|---|---|---|---|---|---|---|"]
    for f in fits:
        for c in f.coefficients:
            paper = "-" if c.paper is None else f"{c.paper:g}"
            md.append(f"| {f.system} | {f.method} | {c.joint} | {c.term} | {c.true:g} | {paper} | "
                      f"{c.ours:.4f} +/- {c.stderr:.4f} | {100 * c.error:.2f} % |")
        extra = "; ".join(f"eq. {j + 1}: {', '.join(e) or 'none'}" for j, e in enumerate(f.extra_terms))
        md.append(f"| {f.system} | | | extra terms | | | {extra} | |")
    lag = {f.system: f.lagrangian_residual for f in fits if f.lagrangian_residual}
    md += ["", "Lagrangian consistency (relative residual of the noise-free torque fitted by one "
           "Lagrangian of the structure's atoms): " + "; ".join(
               f"{k}: {', '.join(f'{x:.1e}' for x in v)}" for k, v in lag.items())
           + ". The printed double pendulum is not a Lagrangian system (eq. 1 has "
           "theta1-dot^2 sin where physics has theta2-dot^2, and its coupling coefficient 2 "
           "disagrees with eq. 2's 1); it is kept as printed and fitted *jointwise*: each "
           "equation is F-tested for a Lagrangian form on its own; eq. 2 passes and is fitted by "
           "its atoms (its two coupling terms share one coefficient), eq. 1 fails and is fitted "
           "on the library features, the paper's method. Eq. 2 "
           "is the pendulum m1 = 2.5, m2 = 0.5 kg, l1 = 1, l2 = 2 m; the consistent pair "
           "(eq. 1 = 3 th1'' + th2'' cos + th2'^2 sin + 29.4 sin th1) is fitted by the "
           "coupled regression, which shares m2 l1 l2 across its four terms."]
    return md


def _level_result(c: dict) -> dict:
    return {"joints": [{**cp, "oracle": c["oracle"][j], "true_support": c["true_support"][j],
                        "per_joint_rel": c["per-joint"]["joints"][j]["rel"],
                        "general_rel": c["coupled general"]["joints"][j]["rel"]}
                       for j, cp in enumerate(c["coupled"]["joints"])],
            **{k: c[k] for k in ("oracle", "true_support", "pysindy") if k in c},
            **{label: c[label] for label, _, _ in METHODS}}


def _intro(ctx: dict, c5: dict) -> list[str]:
    lib, gen = ctx["libraries"]["symmetric"], ctx["libraries"]["general"]
    nb, ng = len(ctx["bases"]["symmetric"].atoms), len(ctx["bases"]["general"].atoms)
    return ["## Identification (paper II.A-F, Tables III-IV)", "",
            f"Libraries derived from Lagrangian atoms of the 1-DOF, planar and spatial 2-DOF "
            f"structures: `{lib.name}` ({len(lib)} features, {nb} atoms, symmetric links: centre "
            f"of mass on the link axis, Iyy = Izz) and `{gen.name}` ({len(gen)} features, {ng} "
            "atoms, general inertia tensors: spans every rigid-body torque of this arm, "
            "tests/test_identification_atoms.py). Both write the chain as rigid links plus "
            "rotors (w_a^2, qd_j^2) and tie each rigid link pair's "
            "relative-angle terms into one coefficient (prior_knowledge.link_pair_atoms). "
            "Data: `generate('lynxmotion', 4000, noise, seed=0)`, 200 Hz, last 25 % held out, "
            "noise std = level x each joint's torque std with mean 0.2 std, one independent "
            "draw per level (seed in brackets; 5 % is the default data). Relative RMS error vs "
            "the clean torque on the held-out part. *paper per-joint*: each joint regressed "
            "alone on the symmetric library's features (Lasso + proportional filter + refit); "
            "*coupled*: one Lagrangian, atom coefficients shared by all joints, rows weighted "
            "by 1/noise std (default of `torquebench identify`); *coupled general*: the same "
            "on the general atoms; *oracle*: two-step WLS on Pinocchio's base-parameter "
            f"regressor ({c5['oracle_parameters']} parameters; it knows the link lengths and "
            "that there is no rotor inertia, the atoms know neither); pysindy on the symmetric "
            "library. Fresh trajectory: another excitation (seed 5), ratio to the held-out "
            "error in brackets.", "", *TABLE_HEAD]


def expected_error(design: np.ndarray, cols, sigma: np.ndarray, k: int,
                   tau_clean: np.ndarray) -> np.ndarray:
    """Per joint, the expected held-out relative RMS error of weighted least squares on
    design[:, :, cols] + per-joint offsets, fitted on the first k samples, when the model
    is exact and the noise white with std sigma (N m): sqrt(trace(H cov H^T)) / ||tau||."""
    n, dof = tau_clean.shape
    x = np.concatenate([design[:k][:, :, cols], np.broadcast_to(np.eye(dof), (k, dof, dof))], axis=2)
    xw = (x / sigma[None, :, None]).reshape(k * dof, -1)
    cov = np.linalg.inv(xw.T @ xw)[: len(cols), : len(cols)]
    return np.array([np.sqrt(np.einsum("ia,ab,ib->", h, cov, h)) / np.linalg.norm(tau_clean[k:, j])
                     for j, h in enumerate(design[k:][:, :, cols].transpose(1, 0, 2))])


def expected_errors(ctx: dict, level: float = 0.05) -> dict:
    """expected_error of the true terms of each atom set and of the oracle, true noise std."""
    clean = ctx["clean"]
    k, sigma = n_train(len(clean.q)), level * clean.tau_clean.std(axis=0)
    untied = AtomBasis.from_atoms(prior_knowledge_library(3, rigid_links=False).atoms, 3)
    out = {}
    for label, basis in (("15 untied atoms", untied), ("tied atoms", ctx["bases"]["symmetric"])):
        truth = true_atoms(basis, clean)
        cols = [basis.names.index(a) for a in sorted(truth)]
        design = basis.evaluate(clean.q, clean.qd, clean.qdd)
        out[f"{label} ({len(cols)} true)"] = expected_error(design, cols, sigma, k, clean.tau_clean)
    cols = fit_base_parameters(ctx["regressor"][:k], clean.tau_clean[:k]).columns
    out[f"oracle ({len(cols)})"] = expected_error(ctx["regressor"], cols, sigma, k, clean.tau_clean)
    return {key: v.tolist() for key, v in out.items()}


def _why_joint3(expected: dict) -> list[str]:
    rows = "; ".join(f"{k}: {', '.join(f'{x:.2e}' for x in v)}" for k, v in expected.items())
    return ["", "Why joint 3 trailed the oracle (issue #3): not selection (every draw keeps "
            "exactly the true atoms), not the weights (the true noise std gives the same "
            "errors), not the offsets. The earlier 15-atom set wrote the chain in joint rates, "
            "so joint 3 carried coefficients no rigid arm has: qd3^2 free of qd2*qd3 (a rotor), "
            "qd2^2 cos q3 free of qd2*qd3 cos q3, and the base's reach product free of the "
            "chain's. Expected held-out error at 5 % of weighted least squares on the true "
            f"terms, true noise std, per joint: {rows}. Rigid links plus a rotor atom that "
            "the selection drops when there is no armature put every joint below the oracle "
            "in expectation; the RMS ratios over the draws above agree."]


def _default_choice(rob: dict) -> list[str]:
    cp, gn = rob["methods"]["coupled"], rob["methods"]["coupled general"]
    same = sum(set(a) == set(b) for a, b in zip(cp["atoms"], gn["atoms"], strict=True))
    fmt = lambda v: ", ".join(f"{x:.2f}" for x in v)  # noqa: E731
    return ["", "Default: the symmetric atoms. The symmetric-link assumption (centre of mass on "
            "the link axis, Iyy = Izz) is prior knowledge the oracle does not get (it fits every "
            "inertia component); the general atoms are the like-for-like comparison. Over the "
            f"draws the general fit keeps the same atoms as the symmetric one on {same}/"
            f"{len(rob['seeds'])} draws, RMS error ratio to the oracle {fmt(gn['rms_ratio'])} "
            f"(general) vs {fmt(cp['rms_ratio'])} (symmetric) per joint: on this arm the "
            "assumption buys nothing measurable. The symmetric set stays the default because "
            "its 26-feature library is also the per-joint method's and the one the closed loop "
            "and planner were validated with; for an arm whose links are not symmetric use "
            "`prior_knowledge_library(3, symmetric_links=False)` (`torquebench identify "
            "--library prior-general`)."]


def _robust_note(rob: dict) -> list[str]:
    cp = rob["methods"]["coupled"]
    worst = int(np.argmax(cp["ratio_worst"]))
    k = rob["seeds"].index(cp["worst_seed"][worst])
    rel, orc = cp["rel"][k][worst], rob["oracle"][k][worst]
    typical = float(np.median(np.array(rob["oracle"])[:, worst]))
    return ["", f"Worst single draw (coupled): joint {worst + 1}, seed {rob['seeds'][k]}: "
            f"{rel:.2e} vs oracle {orc:.2e} (the oracle's median on this joint over the draws is "
            f"{typical:.2e}). A per-draw ratio of two estimators' errors is heavy-tailed even "
            "when both are unbiased: the two fits share the noise but not the parameter "
            "directions it excites, so on a draw where the oracle's error happens to be small "
            "the ratio is large. Hence the median and RMS ratios, and the draw count."]


def run(out_dir: Path, quick: bool = False) -> dict:
    """Report section: markdown, results, figure paths, and the 5 % coupled model."""
    with threadpool_limits(limits=1, user_api="blas"):  # small dense algebra: one thread is faster
        return _run(out_dir, quick)


def _run(out_dir: Path, quick: bool) -> dict:
    fig_dir = Path(out_dir) / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    ctx = context()
    levels = QUICK_LEVELS if quick else LEVELS
    comps = {lv: compare(lv, ctx, with_pysindy=lv == 0.05) for lv in levels}
    c5, c0 = comps[0.05], comps[0.0]
    rob = robustness(ctx, QUICK_ROBUST_SEEDS if quick else ROBUST_SEEDS)
    res: dict = {"library": ctx["library"].name, "library_size": len(ctx["library"]),
                 "atoms": len(ctx["basis"].atoms), "true_atoms": sorted(ctx["atoms"]["symmetric"]),
                 "general_atoms": len(ctx["bases"]["general"].atoms), "quick": quick,
                 "noise_seeds": {f"{lv:g}": NOISE_SEEDS[lv] for lv in levels}, "levels": {},
                 "robustness_5pct": rob, "acceptance_5pct": acceptance(c5, c0, rob)}
    md = _intro(ctx, c5)
    for lv, c in comps.items():
        md += table_rows(lv, c)
        res["levels"][f"{lv:g}"] = _level_result(c)
    acc = res["acceptance_5pct"]
    md += ["", "At 5 % (default data): coupled / oracle = " + ", ".join(
        f"{x:.2f}" for x in acc["ratio_to_oracle"]) + " (the issue's acceptance ratio; below 1 "
        "because the oracle fits 16 dense base parameters while the truth is sparse in the "
        "atoms, so the oracle is a reference, not an upper bound); coupled / true support = "
        + ", ".join(f"{x:.2f}" for x in acc["ratio_to_true_support"]) + " (1 = as good as a "
        "perfect selector); checks: " + ", ".join(
        f"{k} {'yes' if v else 'NO'}" for k, v in acc.items() if isinstance(v, bool))]
    res["expected_5pct"] = expected_errors(ctx)
    md += robustness_markdown(rob) + _robust_note(rob) + _why_joint3(res["expected_5pct"])
    md += _default_choice(rob)
    md += _atoms_markdown(ctx, c5)
    md += _peers_markdown(c5)
    lagr = c5["coupled"]["lagrangian"]
    md += ["", "Identified at 5 % (coupled):", "", "```", *c5["fits"]["coupled"].model.equations(),
           "L = " + " + ".join(f"{c:.6g}*{a}" for a, c in
                               zip(lagr["atoms"], lagr["coefficients"], strict=True)), "```"]
    d5 = c5["data"]
    if not quick:
        paper = identify(d5.q, d5.qd, d5.qdd, d5.tau, paper_library(), 0.25, d5.tau_clean)
        res["paper_library_5pct_rel"] = paper.heldout_rel_rmse.tolist()
        md += ["", f"Published 75-feature library at 5 % (per joint): rel err "
               f"{paper.heldout_rel_rmse.round(5).tolist()}; it does not span joint 1 of a full-inertia arm."]
    md += _denoise_markdown(res, ctx, d5)
    res["denoise_then_regress"] = denoise_then_regress(ctx, comps)
    md += _denoise_regress_markdown(res["denoise_then_regress"])
    figs = _figures(fig_dir, ctx, c5)
    systems = SYSTEMS + (CONSISTENT_DOUBLE_PENDULUM,)
    fits = [fit_system(s) for s in (systems if not quick else systems[1:2])]
    res["table4"] = {f.system: {"max_coef_error": f.max_error, "heldout_rel_rmse": list(f.heldout_rel_rmse),
                                "method": f.method, "extra_terms": [list(e) for e in f.extra_terms],
                                "coefficients": [dataclasses.asdict(c) for c in f.coefficients],
                                "lagrangian_residual": list(f.lagrangian_residual)} for f in fits}
    md += _table4_markdown(fits)
    res["seconds"] = time.perf_counter() - start
    md += ["", f"Section time: {res['seconds']:.1f} s{' (quick)' if quick else ''}."]
    return {"markdown": "\n".join(md), "results": res, "figures": [str(p) for p in figs],
            "model": c5["fits"]["coupled"].model}


def _atoms_markdown(ctx: dict, c5: dict) -> list[str]:
    md = [""]
    for label, key in (("coupled", "symmetric"), ("coupled general", "general")):
        c, truth = c5[label], ctx["atoms"][key]
        lagr = c["lagrangian"]
        md.append(f"Atoms kept at 5 % ({label}): {len(lagr['atoms'])} of {lagr['candidate_atoms']} "
                  f"(true: {len(truth)}; atom recall {c['atom_recall']:.2f}, precision "
                  f"{c['atom_precision']:.2f}); base atoms by QR: {lagr['base_atoms']}, folded: "
                  f"{lagr['folded_atoms'] or 'none'}.")
    return md


def _denoise_markdown(res: dict, ctx: dict, d5) -> list[str]:
    dn = denoise(d5.tau)
    before = np.mean((d5.tau - d5.tau_clean) ** 2, axis=0)
    after = np.mean((dn.signal - d5.tau_clean) ** 2, axis=0)
    res["denoise"] = {"mse_before": before.tolist(), "mse_after": after.tolist(),
                      "ratio": (before / after).tolist(), "weight": dn.weight.tolist()}
    return ["", "Denoising at 5 % (GCV-chosen weight; paper Fig. 2: 0.000196 -> 0.000109): noise MSE "
            + "; ".join(f"joint {j + 1}: {before[j]:.3e} -> {after[j]:.3e} ({before[j] / after[j]:.1f}x)"
                        for j in range(3))]


def _peers_markdown(c5: dict) -> list[str]:
    """Speed and the tuned pysindy peers beside ours at 5 %, sweeps included in every time."""
    md = ["", "Speed and peers at 5 % (all three joints; every time includes its method's "
          "hyper-parameter sweep and selection: ours 30 Lasso alphas x 4 pass rates + pruning; "
          "pysindy's swept on the same validation blocks inside the training part, same "
          "sparsest-within-one-paired-s.e. rule, then refit on the training part): " + ", ".join(
              f"{label} {c5[label]['seconds']:.2f} s" for label, _, _ in METHODS) + ".", "",
          "| peer | selected per joint | held-out rel. error per joint | terms | recall / precision "
          "| s (3 joints, sweep incl.) |", "|---|---|---|---|---|---|"]
    for k, v in c5["pysindy"].items():
        md.append(f"| pysindy {k} | {v['setting_name']} " + ", ".join(f"{x:.3g}" for x in v["setting"])
                  + " | " + ", ".join(f"{x:.2e}" for x in v["rel"]) + f" | {v['terms']} | "
                  + ", ".join(f"{r:.2f} / {p:.2f}" for r, p in zip(v["recall"], v["precision"], strict=True))
                  + f" | {v['seconds']:.2f} |")
    cp = c5["coupled"]["joints"]
    md.append("| ours, coupled | alpha, pass rate " + f"{c5['coupled']['alpha'][0]:.3g}, "
              f"{c5['coupled']['pass_rate'][0]:g} | " + ", ".join(f"{j['rel']:.2e}" for j in cp)
              + f" | {[j['terms'] for j in cp]} | " + ", ".join(
                  f"{j['recall']:.2f} / {j['precision']:.2f}" for j in cp)
              + f" | {c5['coupled']['seconds']:.2f} |")
    return md


def _lag1(resid: np.ndarray) -> np.ndarray:
    r = resid - resid.mean(axis=0)
    return np.sum(r[1:] * r[:-1], axis=0) / np.sum(r * r, axis=0)


def denoise_then_regress(ctx: dict, comps: dict) -> dict:
    """The paper's pipeline (denoise the measured torque, then regress) vs ours (regress on the
    raw torque), same data, same coupled fit, at every noisy level in comps. Only the training
    part is denoised (GCV weight). Per joint: held-out error vs the clean torque, recall /
    precision, lag-1 autocorrelation of the training residual, and the RMS over the true atoms
    of (coefficient - truth) / reported standard error (about 1 when the s.e. is honest)."""
    basis, key = ctx["bases"]["symmetric"], "symmetric"
    true_cols = [basis.names.index(a) for a in sorted(ctx["atoms"][key])]
    design = basis.evaluate(ctx["clean"].q, ctx["clean"].qd, ctx["clean"].qdd)
    truth = np.zeros(len(basis.names))
    truth[true_cols] = weighted_lstsq(design, ctx["clean"].tau_clean, true_cols, np.ones(3))[0]
    out = {}
    for level, c in comps.items():
        if level == 0:
            continue
        d, k = c["data"], n_train(len(c["data"].q))
        target = d.tau.copy()
        target[:k] = denoise(d.tau[:k]).signal
        dn = identify(d.q, d.qd, d.qdd, target, ctx["libraries"][key], HOLDOUT, d.tau_clean,
                      method="coupled")
        row = {}
        for label, r, y in (("raw", c["fits"]["coupled"], d.tau), ("denoised", dn, target)):
            reg = r.regressions[0]
            resid = y[:k] - r.model.torque(d.q[:k], d.qd[:k], d.qdd[:k]) - reg.offsets_
            shared = [a for a in true_cols if reg.support_[a]]
            z = (reg.coef_[shared] - truth[shared]) / reg.stderr_[shared]
            row[label] = {"joints": _scores(r, ctx["truth"][key], None),
                          "atoms": len(r.lagrangian()["atoms"]), "lag1": _lag1(resid).tolist(),
                          "z_rms": float(np.sqrt(np.mean(z**2))), "seconds": r.seconds}
        out[f"{level:g}"] = row
    return out


def _denoise_regress_markdown(dtr: dict) -> list[str]:
    md = ["", "Denoise then regress (the paper's pipeline) vs regress on the raw torque "
          "(`torquebench identify`), coupled fit, same draw per level, training part denoised "
          "by GCV Tikhonov. Per joint: held-out relative error vs the clean torque; recall / "
          "precision of the true terms; lag-1 autocorrelation of the training residual; "
          "z RMS = RMS over the true atoms of (estimate - truth) / the fit's reported standard "
          "error (about 1 if the reported uncertainty is honest).", "",
          "| noise | target | held-out rel. error | recall / precision | atoms kept "
          "| residual lag-1 autocorr. | z RMS |", "|---|---|---|---|---|---|---|"]
    for level, row in dtr.items():
        for label, r in row.items():
            js = r["joints"]
            md.append(f"| {100 * float(level):g} % | {label} | " + ", ".join(f"{j['rel']:.2e}" for j in js)
                      + " | " + ", ".join(f"{j['recall']:.2f} / {j['precision']:.2f}" for j in js)
                      + f" | {r['atoms']} | " + ", ".join(f"{x:.2f}" for x in r["lag1"])
                      + f" | {r['z_rms']:.2f} |")
    return md
