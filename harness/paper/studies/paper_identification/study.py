"""The identification study's data and fits: noisy draws of the default robot's torque, every
method fitted on the same draw (per-joint, coupled, coupled general, oracle, true support,
pysindy peers) and scored on the held-out part and on a fresh trajectory."""

from __future__ import annotations

import dataclasses

import numpy as np
from threadpoolctl import threadpool_limits

from harness.data.generate import generate
from harness.data.sensors import torque_noise
from harness.robots.arm import Arm
from identification.identify import identify
from identification.library.prior_knowledge import prior_knowledge_library
from identification.metrics import rel_error
from identification.regression.coupled import AtomBasis, CoupledRegression
from identification.regression.oracle import fit_base_parameters
from identification.regression.peers import tune
from identification.regression.weighted import weighted_lstsq

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


def scores(r, truth: list[set[str]], fresh) -> list[dict]:
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
        out[label] = {"joints": scores(r, ctx["truth"][key], fresh), "seconds": r.seconds,
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
    arm = Arm.of("lynxmotion")  # the paper's arm
    clean = generate(arm, 4000, 0.0, seed=0)
    fresh = generate(arm, 4000, 0.0, seed=5)
    libs = {"symmetric": prior_knowledge_library(3), "general": prior_knowledge_library(3, False)}
    bases = {k: AtomBasis.from_atoms(v.atoms, 3) for k, v in libs.items()}
    lib = libs["symmetric"]
    return {"clean": clean, "fresh": fresh, "library": lib, "libraries": libs, "basis": bases["symmetric"],
            "bases": bases,
            "regressor": arm.nominal.regressor(clean.q, clean.qd, clean.qdd),
            "theta": lib.evaluate(clean.q, clean.qd, clean.qdd),
            "truth": {k: true_terms(v, clean) for k, v in libs.items()},
            "atoms": {k: true_atoms(b, clean) for k, b in bases.items()}}
