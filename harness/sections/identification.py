"""Bench section: coupled and per-joint sparse identification vs the base-parameter oracle
and pysindy (paper Figs. 2-8, Tables III, IV).

Data: the default robot, `generate('lynxmotion', 4000, noise, seed=0)` (the noise
is re-drawn here from the same clean torque with the same generator and seed,
so the arrays are identical), last 25 % held out; a fresh excitation (seed 5)
checks that the model predicts a trajectory it was not trained on. "True
terms" are the library features with a non-zero coefficient in the exact
noise-free least-squares fit of the library; "true atoms" likewise for the
coupled regression's Lagrangian atoms.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from harness.datagen import generate
from harness.measurement import torque_noise
from harness.pinocchio_baseline import PinocchioModel
from harness.robots import load_pinocchio
from identification import denoise, identify, paper_library, prior_knowledge_library
from identification.coupled import AtomBasis
from identification.oracle import fit_base_parameters
from identification.table4 import CONSISTENT_DOUBLE_PENDULUM, SYSTEMS, fit_system

LEVELS = (0.0, 0.01, 0.05, 0.10)
QUICK_LEVELS = (0.0, 0.05)
HOLDOUT = 0.25
METHODS = ("per-joint", "coupled")


def noisy(clean, level: float, seed: int = 1):
    """The dataset generate(..., noise=level, seed=0) returns, from its clean torque."""
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


def _rel(pred, truth):
    return np.linalg.norm(pred - truth, axis=0) / np.linalg.norm(truth, axis=0)


def n_train(n: int) -> int:
    """Training samples: the first 1 - HOLDOUT, as identify splits."""
    return int(round(n * (1 - HOLDOUT)))


def _pysindy(theta, tau, truth_tau) -> dict:
    import pysindy as ps

    out, k = {}, n_train(len(tau))
    for name, opt in (("STLSQ", ps.STLSQ(threshold=1e-3, alpha=0.0, normalize_columns=True)),
                      ("SSR", ps.SSR(alpha=0.0, normalize_columns=True))):
        start = time.perf_counter()
        coef = np.column_stack([opt.fit(theta[:k], tau[:k, j]).coef_.ravel()
                                for j in range(tau.shape[1])])
        out[name] = {"seconds": time.perf_counter() - start,
                     "rel": _rel(theta[k:] @ coef, truth_tau[k:]).tolist(),
                     "terms": [int(np.sum(coef[:, j] != 0)) for j in range(tau.shape[1])]}
    return out


def _scores(r, truth: list[set[str]], fresh) -> list[dict]:
    frel = _rel(r.model.torque(fresh.q, fresh.qd, fresh.qdd), fresh.tau_clean)
    rows = []
    for j, jm in enumerate(r.model.joints):
        hit = len(set(jm.terms) & truth[j])
        rows.append({"rel": float(r.heldout_rel_rmse[j]), "mse": float(r.heldout_mse[j]),
                     "recall": hit / len(truth[j]), "precision": hit / max(len(jm.terms), 1),
                     "terms": len(jm.terms), "fresh": float(frel[j])})
    return rows


def compare(level: float, ctx: dict, with_pysindy: bool = True, seed: int = 1) -> dict:
    """Per-joint, coupled, oracle (and pysindy) at one noise level; seed 1 draws the noise of
    the default data."""
    d = noisy(ctx["clean"], level, seed)
    out: dict = {"fits": {}}
    for method in METHODS:
        r = identify(d.q, d.qd, d.qdd, d.tau, ctx["library"], HOLDOUT, d.tau_clean, method=method)
        out["fits"][method] = r
        out[method] = {"joints": _scores(r, ctx["truth"], ctx["fresh"]), "seconds": r.seconds,
                       "equations": r.model.equations(), "alpha": [f.alpha_ for f in r.regressions],
                       "pass_rate": [f.pass_rate_ for f in r.regressions]}
    coupled = out["fits"]["coupled"]
    kept = set(coupled.lagrangian()["atoms"])
    out["coupled"]["lagrangian"] = coupled.lagrangian()
    out["coupled"]["atom_recall"] = len(kept & ctx["atoms"]) / len(ctx["atoms"])
    out["coupled"]["atom_precision"] = len(kept & ctx["atoms"]) / max(len(kept), 1)
    k = n_train(len(d.q))
    ofit = fit_base_parameters(ctx["regressor"][:k], d.tau[:k])
    out["oracle"] = _rel(ofit.predict(ctx["regressor"][k:]), d.tau_clean[k:]).tolist()
    out["oracle_parameters"] = len(ofit.columns)
    if with_pysindy:
        out["pysindy"] = _pysindy(ctx["theta"], d.tau, d.tau_clean)
    out["data"] = d
    return out


def context() -> dict:
    clean = generate("lynxmotion", 4000, 0.0, seed=0)
    fresh = generate("lynxmotion", 4000, 0.0, seed=5)
    lib = prior_knowledge_library(3)
    basis = AtomBasis.from_atoms(lib.atoms, 3)
    return {"clean": clean, "fresh": fresh, "library": lib, "basis": basis,
            "regressor": PinocchioModel(load_pinocchio("lynxmotion")).regressor(clean.q, clean.qd, clean.qdd),
            "theta": lib.evaluate(clean.q, clean.qd, clean.qdd), "truth": true_terms(lib, clean),
            "atoms": true_atoms(basis, clean)}


TABLE_HEAD = ["| noise | joint | paper per-joint | coupled | oracle | coupled / oracle | pysindy STLSQ "
              "| pysindy SSR | recall / precision per-joint | recall / precision coupled "
              "| fresh traj. coupled (x held-out) |", "|---|---|---|---|---|---|---|---|---|---|---|"]


def table_rows(level: float, c: dict) -> list[str]:
    rows = []
    for j in range(3):
        pj, cp, orc = c["per-joint"]["joints"][j], c["coupled"]["joints"][j], c["oracle"][j]
        ps = c.get("pysindy", {})
        peers = [f"{ps[k]['rel'][j]:.2e}" if k in ps else "-" for k in ("STLSQ", "SSR")]
        ratio = f"{cp['rel'] / orc:.2f}" if orc > 1e-12 else "-"
        rows.append(f"| {100 * level:g} % | {j + 1} | {pj['rel']:.2e} | {cp['rel']:.2e} | {orc:.2e} | "
                    f"{ratio} | {peers[0]} | {peers[1]} | {pj['recall']:.2f} / {pj['precision']:.2f} | "
                    f"{cp['recall']:.2f} / {cp['precision']:.2f} | {cp['fresh']:.2e} "
                    f"({cp['fresh'] / max(cp['rel'], 1e-300):.2f}) |")
    return rows


def acceptance(c5: dict, c0: dict) -> dict:
    """Issue #3 checks on the default (coupled) method."""
    j5, j0 = c5["coupled"]["joints"], c0["coupled"]["joints"]
    rel = np.array([j["rel"] for j in j5])
    return {
        "noise_free_exact": bool(all(j["rel"] <= 1e-8 and j["recall"] == 1 and j["precision"] == 1
                                     for j in j0)),
        "ratio_to_oracle": (rel / np.array(c5["oracle"])).tolist(),
        "within_1.25x_oracle": bool(np.all(rel <= 1.25 * np.array(c5["oracle"]))),
        "below_0.5pct": bool(np.all(rel <= 0.005)),
        "recall_100": bool(all(j["recall"] == 1 for j in j5)),
        "precision_90": bool(all(j["precision"] >= 0.9 for j in j5)),
        "fresh_within_1.5x": bool(all(j["fresh"] <= 1.5 * j["rel"] for j in j5)),
    }


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


def run(out_dir: Path, quick: bool = False) -> dict:
    """Report section: markdown, results, figure paths, and the 5 % coupled model."""
    fig_dir = Path(out_dir) / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    ctx = context()
    lib = ctx["library"]
    levels = QUICK_LEVELS if quick else LEVELS
    comps = {lv: compare(lv, ctx, with_pysindy=not quick or lv == 0.05) for lv in levels}
    c5, c0 = comps[0.05], comps[0.0]
    res: dict = {"library": lib.name, "library_size": len(lib), "atoms": len(ctx["basis"].atoms),
                 "true_atoms": sorted(ctx["atoms"]), "quick": quick, "levels": {},
                 "acceptance_5pct": acceptance(c5, c0)}
    md = ["## Identification (paper II.A-F, Tables III-IV)", "",
          f"Library `{lib.name}` ({len(lib)} features) derived from {len(ctx['basis'].atoms)} "
          "Lagrangian atoms (1-DOF, planar and spatial 2-DOF structures). Default data: "
          "`generate('lynxmotion', 4000, noise, seed=0)`, 200 Hz, last 25 % held out, noise "
          "0-10 % of each joint's torque std with mean 0.2 sigma. Relative RMS error vs the clean "
          "torque on the held-out part. *paper per-joint*: each joint regressed alone (Lasso + "
          "proportional filter + refit, the paper's method); *coupled*: one Lagrangian, atom "
          "coefficients shared by all joints, rows weighted by 1/noise std (default of "
          "`torquebench identify`); *oracle*: two-step WLS on Pinocchio's base-parameter "
          f"regressor ({c5['oracle_parameters']} parameters); pysindy on the same library. "
          "Fresh trajectory: another excitation (seed 5), ratio to the held-out error in brackets.",
          "", *TABLE_HEAD]
    for lv, c in comps.items():
        md += table_rows(lv, c)
        res["levels"][f"{lv:g}"] = {
            "joints": [{**cp, "oracle": c["oracle"][j], "per_joint_rel": c["per-joint"]["joints"][j]["rel"]}
                       for j, cp in enumerate(c["coupled"]["joints"])],
            **{k: c[k] for k in ("oracle", "pysindy") if k in c},
            "per-joint": c["per-joint"], "coupled": c["coupled"]}
    acc = res["acceptance_5pct"]
    lagr = c5["coupled"]["lagrangian"]
    md += ["", "At 5 %: coupled / oracle = " + ", ".join(f"{x:.2f}" for x in acc["ratio_to_oracle"])
           + "; checks: " + ", ".join(f"{k} {'yes' if v else 'NO'}" for k, v in acc.items()
                                      if isinstance(v, bool)),
           f"Atoms kept at 5 %: {len(lagr['atoms'])} of {lagr['candidate_atoms']} (true: "
           f"{len(ctx['atoms'])}; atom recall {c5['coupled']['atom_recall']:.2f}, precision "
           f"{c5['coupled']['atom_precision']:.2f}); base atoms by QR: {lagr['base_atoms']} of "
           f"{lagr['candidate_atoms']}, folded: {lagr['folded_atoms'] or 'none'}.",
           "", "Speed at 5 % (all three joints): coupled "
           f"{c5['coupled']['seconds']:.2f} s, per-joint {c5['per-joint']['seconds']:.2f} s; pysindy "
           + ", ".join(f"{k} {v['seconds']:.3f} s ({v['terms']} terms)" for k, v in c5["pysindy"].items()),
           "", "Identified at 5 % (coupled):", "", "```", *c5["fits"]["coupled"].model.equations(),
           "L = " + " + ".join(f"{c:.6g}*{a}" for a, c in
                               zip(lagr["atoms"], lagr["coefficients"], strict=True)),
           "```"]
    d5 = c5["data"]
    if not quick:
        paper = identify(d5.q, d5.qd, d5.qdd, d5.tau, paper_library(), 0.25, d5.tau_clean)
        res["paper_library_5pct_rel"] = paper.heldout_rel_rmse.tolist()
        md += ["", f"Published 75-feature library at 5 % (per joint): rel err "
               f"{paper.heldout_rel_rmse.round(5).tolist()}; it does not span joint 1 of a full-inertia arm."]
    dn = denoise(d5.tau)
    before = np.mean((d5.tau - d5.tau_clean) ** 2, axis=0)
    after = np.mean((dn.signal - d5.tau_clean) ** 2, axis=0)
    res["denoise"] = {"mse_before": before.tolist(), "mse_after": after.tolist(),
                      "ratio": (before / after).tolist(), "weight": dn.weight.tolist()}
    md += ["", "Denoising at 5 % (GCV-chosen weight; paper Fig. 2: 0.000196 -> 0.000109): noise MSE "
           + "; ".join(f"joint {j + 1}: {before[j]:.3e} -> {after[j]:.3e} ({before[j] / after[j]:.1f}x)"
                       for j in range(3))]
    figs = _figures(fig_dir, ctx, c5)
    systems = SYSTEMS + (CONSISTENT_DOUBLE_PENDULUM,)
    fits = [fit_system(s) for s in (systems if not quick else systems[1:2])]
    res["table4"] = {f.system: {"max_coef_error": f.max_error, "heldout_rel_rmse": list(f.heldout_rel_rmse),
                                "method": f.method, "extra_terms": [list(e) for e in f.extra_terms],
                                "coefficients": [dataclasses.asdict(c) for c in f.coefficients],
                                "lagrangian_residual": list(f.lagrangian_residual)} for f in fits}
    md += _table4_markdown(fits)
    return {"markdown": "\n".join(md), "results": res, "figures": [str(p) for p in figs],
            "model": c5["fits"]["coupled"].model}
