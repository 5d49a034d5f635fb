"""Identification figures: denoising (cf. Fig. 2), validation error against Lasso alpha
(Figs. 3-5) and the held-out fit (Figs. 6-8)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.paper.studies.paper_identification.study import n_train
from harness.report.figures import plt, save_figure
from identification.regression.denoise import denoise


def section_figures(fig_dir: Path, ctx: dict, c5: dict) -> list[Path]:
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
    save_figure(fig, figs[0], dpi=110, tight="bbox")
    _alpha_figure(figs[1], c5)
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    k = n_train(len(clean.q))
    pred = c5["fits"]["coupled"].model.torque(clean.q, clean.qd, clean.qdd)
    for j, ax in enumerate(axes):
        ax.plot(clean.t[k:], clean.tau_clean[k:, j], "k", lw=1, label="Pinocchio (clean)")
        ax.plot(clean.t[k:], pred[k:, j], "r--", lw=1, label="identified (coupled)")
        ax.set(ylabel=f"tau{j + 1} (N m)")
    axes[0].legend()
    axes[-1].set(xlabel="t (s), held-out part (cf. Figs. 6-8)")
    save_figure(fig, figs[2], dpi=110, tight="bbox")
    return figs


def _alpha_figure(path: Path, c5: dict) -> None:
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
    save_figure(fig, path, dpi=110)
