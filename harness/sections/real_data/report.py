"""The real-data section's text: every sentence built from the run's numbers."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _fmt(values, digits: int = 3) -> str:
    return ", ".join(f"{v:.{digits}f}" for v in values)


def _shape(t: dict) -> str:
    if t["effect"] == "coulomb":
        return f"lead {t['lead']:.3g} s, linear zone {t['eps']:.3g} rad/s"
    if t["effect"] == "sigmoid":
        return f"steepness {t['steepness']:.3g} s/rad, shift {t['shift']:+.3g} rad/s"
    return ""


def _data(meta: dict) -> str:
    d, s = meta["derivatives"], meta["raw_step_s"]
    return (f"Measured on a real Franka Emika Panda (Gaz et al., RA-L 2019; `data/panda_gaz2019`, "
            f"GPL-3.0): {meta['raw_samples']} samples over {meta['duration_s']:.1f} s, time steps "
            f"{1e3 * s['min']:.2f}–{1e3 * s['max']:.2f} ms (median {1e3 * s['median']:.2f} ms), "
            f"resampled to {meta['resampling']['rate_hz']:.0f} Hz; {', '.join(d['estimated'])} "
            f"estimated from {d['source']} by Savitzky–Golay (order {d['polyorder']}, window "
            f"{d['window_samples']} samples = {d['window_s']:.3f} s, chosen from the data: signal "
            f"band up to {max(d['band_edge_hz']):.2f} Hz); handed over at "
            f"{meta['resampling']['rate_out_hz']:.0f} Hz, {meta['samples']} samples "
            "(`torquebench ingest --csv data/panda_gaz2019/panda_gaz2019.csv.gz --robot panda "
            "--rate 100`). Fit on the first 75 % of the time, scored on the last 25 % against the "
            "measured torque: relative RMS ||tau - tau_hat|| / ||tau|| per joint.")


def _models_table(models, reference, nominal_ref, nominal_whole, ratio, same, loop) -> list[str]:
    r = loop.loop
    rows = [("nominal URDF (RNEA), held out", models["nominal"].heldout),
            ("nominal URDF, whole log", nominal_whole),
            ("nominal URDF, whole log (source README)", nominal_ref),
            ("least squares, same data", models["least_squares"].heldout),
            ("least squares (source README, window 51)", reference),
            ("identified (`identify --robot panda`)", models["identified"].heldout),
            ("identified / README least squares", ratio),
            ("identified / least squares on same data", same),
            ("rigid-body identification (closeloop before)", r.error_before),
            ("+ named effects (closeloop after)", r.error_after)]
    dof = len(reference)
    out = ["| model | " + " | ".join(f"joint {j + 1}" for j in range(dof)) + " |",
           "|---|" + "---|" * dof]
    out += [f"| {name} | " + " | ".join(f"{v:.3f}" for v in values) + " |" for name, values in rows]
    return out


def _loop(loop) -> list[str]:
    r, js = loop.loop, loop.to_json()
    out = ["Closing the loop (`torquebench closeloop --data panda_gaz2019.npz --robot panda`): the "
           "declared model is the rigid-body identification (the Panda's rigid-body base atoms, "
           "coupled sparse regression, a sensor offset per joint); its residual is traced per "
           "joint to candidates (viscous, Coulomb, Gaz et al.'s sigmoid friction, armature, "
           f"spring), each named only if it lowers its joint's validation error power by at "
           f"least the bar ({js['selection']['rule']}).", "",
           "| order | joint | effect | coefficient | shape |", "|---|---|---|---|---|"]
    for k, t in enumerate(js["effects"], 1):
        out.append(f"| {k} | {t['joint']} | {t['effect']} | {t['coefficient']:.4g} {t['unit']} | "
                   f"{_shape(t)} |")
    out += ["", f"Held-out error before [{_fmt(r.error_before)}], after [{_fmt(r.error_after)}]; "
            f"validation power the effects remove per joint [{_fmt(r.explained, 2)}]."]
    bad = list(r.unexplained_joints)
    if bad:
        out.append(f"Unexplained: joint(s) {', '.join(map(str, bad))} keep structure the named "
                   "effects do not remove (less than half of their residual's validation power); "
                   "no candidate in the dictionary accounts for it.")
    else:
        out.append("Every joint's residual structure is at least half removed by the named effects.")
    left = "; ".join(f"joint {j}: {e} ({why})" for j, e, _, why in r.not_named)
    out.append(f"Best candidate left per joint when selection stopped: {left}.")
    return out


def markdown(meta, models, reference, nominal_ref, nominal_whole, ratio, same, loop,
             acceptance, seconds, figures) -> str:
    med, worst = float(np.median(ratio)), float(np.max(ratio))
    ok = med <= 1.0 and worst <= 1.25
    md = [_data(meta), "", *_models_table(models, reference, nominal_ref, nominal_whole, ratio,
                                          same, loop), "",
          f"The identified model's error is {med:.2f}x the source README's least-squares "
          f"reference at the median over joints and {worst:.2f}x at worst (bars: 1 and 1.25): "
          f"{'met' if ok else 'NOT met'}. Against the same least squares recomputed on these "
          f"data (this window), the median ratio is {np.median(same):.2f} and the worst "
          f"{np.max(same):.2f}.", "", *_loop(loop), "",
          "Acceptance: " + ", ".join(f"{k} {'yes' if v else 'NO'}" for k, v in acceptance.items())
          + f". CPU time of the section {seconds:.1f} s.", ""]
    md += [f"![{Path(p).stem}](figures/{Path(p).name})" for p in figures]
    return "\n".join(md)
