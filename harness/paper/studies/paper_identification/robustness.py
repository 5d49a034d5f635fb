"""Robustness at 5 %: every method on independent noise draws, the acceptance checks against
the oracle, and the error each method is expected to reach from its design and the noise."""

from __future__ import annotations

import numpy as np

from harness.paper.studies.paper_identification.study import (
    METHODS,
    RATIO_LIMIT,
    ROBUST_SEEDS,
    fit_methods,
    n_train,
    noisy,
    true_atoms,
)
from identification.library.prior_knowledge import prior_knowledge_library
from identification.regression.coupled import AtomBasis
from identification.regression.oracle import fit_base_parameters


def robustness(ctx: dict, seeds=ROBUST_SEEDS, level: float = 0.05) -> dict:
    """Every method on independent noise draws at `level`: per draw and summarized."""
    draws = [fit_methods(noisy(ctx["clean"], level, s), ctx) for s in seeds]
    oracle = np.array([d["oracle"] for d in draws])
    support = np.array([d["true_support"] for d in draws])
    out: dict = {"level": level, "seeds": list(seeds), "oracle": oracle.tolist(),
                 "true_support": support.tolist(), "methods": {},
                 # the bar met by WLS on exactly the true atoms: what a perfect selector reaches
                 "true_support_draws_within_limit": int(np.sum(np.all(
                     support <= RATIO_LIMIT * oracle, axis=1)))}
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
            out["methods"][label]["draws_true_atoms_exactly"] = int(sum(
                d[label]["atom_recall"] == 1 and d[label]["atom_precision"] == 1 for d in draws))
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
    """Checks on the default (coupled) method at 5 % (default data), and over draws."""
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


def why_joint3(expected: dict, rob: dict) -> list[str]:
    """What the run shows about joint 3 against the oracle: selection over the
    draws, and the expected errors of the true terms of each atom set."""
    cp = rob["methods"]["coupled"]
    recall, precision = float(np.min(cp["recall_min"])), float(np.min(cp["precision_min"]))
    selection = ("not selection (every draw keeps exactly the true atoms)" if recall == precision
                 == 1.0 else f"selection on some draws (smallest recall {recall:.2f}, precision "
                 f"{precision:.2f})")
    rows = "; ".join(f"{k}: {', '.join(f'{x:.2e}' for x in v)}" for k, v in expected.items())
    oracle = next(v for k, v in expected.items() if k.startswith("oracle"))
    tied = next(v for k, v in expected.items() if k.startswith("tied"))
    below = all(t < o for t, o in zip(tied, oracle, strict=True))
    agree = all(x < 1 for x in cp["rms_ratio"]) == below
    return ["", f"Why joint 3 trailed the oracle: {selection}. The earlier 15-atom "
            "set wrote the chain in joint rates, so joint 3 carried coefficients no rigid arm "
            "has: qd3^2 free of qd2*qd3 (a rotor), qd2^2 cos q3 free of qd2*qd3 cos q3, and the "
            "base's reach product free of the chain's. Expected held-out error at 5 % of "
            f"weighted least squares on the true terms, true noise std, per joint: {rows}. "
            f"With the tied atoms every joint is {'below' if below else 'not below'} the oracle "
            "in expectation; the RMS ratios over the draws above "
            f"{'agree' if agree else 'disagree'} ({', '.join(f'{x:.2f}' for x in cp['rms_ratio'])})."]


def default_choice(rob: dict, library_size: int, tolerance: float = 0.05) -> list[str]:
    """The symmetric vs the general atoms over the draws: the measured difference."""
    cp, gn = rob["methods"]["coupled"], rob["methods"]["coupled general"]
    same = sum(set(a) == set(b) for a, b in zip(cp["atoms"], gn["atoms"], strict=True))
    fmt = lambda v: ", ".join(f"{x:.2f}" for x in v)  # noqa: E731
    change = max(abs(g / c - 1) for g, c in zip(gn["rms_ratio"], cp["rms_ratio"], strict=True))
    verdict = (f"on this arm the assumption changes the RMS error by at most {100 * change:.1f} "
               f"% on any joint (below {100 * tolerance:g} %: nothing measurable)"
               if change < tolerance else f"on this arm the assumption changes the RMS error "
               f"by up to {100 * change:.1f} % on a joint")
    return ["", "Default: the symmetric atoms. The symmetric-link assumption (centre of mass on "
            "the link axis, Iyy = Izz) is prior knowledge the oracle does not get (it fits every "
            "inertia component); the general atoms are the like-for-like comparison. Over the "
            f"draws the general fit keeps the same atoms as the symmetric one on {same}/"
            f"{len(rob['seeds'])} draws, RMS error ratio to the oracle {fmt(gn['rms_ratio'])} "
            f"(general) vs {fmt(cp['rms_ratio'])} (symmetric) per joint: {verdict}. The "
            f"symmetric set stays the default because its {library_size}-feature library is also "
            "the per-joint method's and the one the closed loop and planner were validated with; "
            "for an arm whose links are not symmetric use "
            "`prior_knowledge_library(3, symmetric_links=False)` (`torquebench identify "
            "--library prior-general`)."]


def robust_note(rob: dict) -> list[str]:
    cp = rob["methods"]["coupled"]
    worst = int(np.argmax(cp["ratio_worst"]))
    k = rob["seeds"].index(cp["worst_seed"][worst])
    rel, orc = cp["rel"][k][worst], rob["oracle"][k][worst]
    typical = float(np.median(np.array(rob["oracle"])[:, worst]))
    n, exact, perfect = len(rob["seeds"]), cp["draws_true_atoms_exactly"], \
        rob["true_support_draws_within_limit"]
    cause = (" On every draw the coupled fit kept exactly the true atoms, so its misses are the "
             "perfect selector's own: a better support cannot lift the count; the bar asks "
             "for a draw-by-draw ratio that an unbiased fit on the true atoms misses by chance "
             "(docs/history-2026-11.md: a removed script estimated that chance)."
             if exact == n else "")
    return ["", f"Draws within {RATIO_LIMIT} x the oracle on every joint: coupled "
            f"{cp['draws_within_limit']} of {n} (exactly the true atoms kept on {exact} of {n}); "
            f"weighted least squares on exactly the true atoms (a perfect selector) {perfect} of "
            f"{n}.{cause}",
            "", f"Worst single draw (coupled): joint {worst + 1}, seed {rob['seeds'][k]}: "
            f"{rel:.2e} vs oracle {orc:.2e} (the oracle's median on this joint over the draws is "
            f"{typical:.2e}). A per-draw ratio of two estimators' errors is heavy-tailed even "
            "when both are unbiased: the two fits share the noise but not the parameter "
            "directions it excites, so on a draw where the oracle's error happens to be small "
            "the ratio is large. Hence the median and RMS ratios, and the draw count."]
