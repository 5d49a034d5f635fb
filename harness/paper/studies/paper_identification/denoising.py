"""Denoising in the paper_identification study: the GCV-denoised torque against the clean one, and
the coupled fit on the denoised training torque beside the raw one (denoise then regress)."""

from __future__ import annotations

import numpy as np

from harness.paper.studies.paper_identification.study import HOLDOUT, n_train, scores
from identification.identify import identify
from identification.regression.denoise import denoise
from identification.regression.weighted import weighted_lstsq


def denoise_markdown(res: dict, ctx: dict, d5) -> list[str]:
    dn = denoise(d5.tau)
    before = np.mean((d5.tau - d5.tau_clean) ** 2, axis=0)
    after = np.mean((dn.signal - d5.tau_clean) ** 2, axis=0)
    res["denoise"] = {"mse_before": before.tolist(), "mse_after": after.tolist(),
                      "ratio": (before / after).tolist(), "weight": dn.weight.tolist()}
    return ["", "Denoising at 5 % (GCV-chosen weight; paper Fig. 2: 0.000196 -> 0.000109): noise MSE "
            + "; ".join(f"joint {j + 1}: {before[j]:.3e} -> {after[j]:.3e} ({before[j] / after[j]:.1f}x)"
                        for j in range(3))]


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
            row[label] = {"joints": scores(r, ctx["truth"][key], None),
                          "atoms": len(r.lagrangian()["atoms"]), "lag1": _lag1(resid).tolist(),
                          "z_rms": float(np.sqrt(np.mean(z**2))), "seconds": r.seconds}
        out[f"{level:g}"] = row
    return out


def denoise_regress_markdown(dtr: dict) -> list[str]:
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
