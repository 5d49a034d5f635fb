"""What a feature library lacks on an arm, measured: why its fits miss the oracle.

On a motion, the least-squares projection of the clean torque on the library's columns is
the best any coefficients on that library can do there (`floor`, relative RMS error per
joint): no fit, whatever its data or noise, scores below it on that motion. The terms of an
exact model (the robot's default library identified on noise-free data, which the bench
checks is exact) that the library cannot represent are named with the share of their joint's
torque outside the library's span. A joint the library spans exactly (floor ~ 0) misses for
another reason: estimation on noisy data, given as the library's column count and its
columns' condition number on the motion.
"""

from __future__ import annotations

import numpy as np

from harness.data.generate import library_condition

SPANNED = 1e-9  # relative error below which the library holds a joint's torque exactly


def _basis(columns: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the columns' span (rank decided relative to the largest)."""
    u, s, _ = np.linalg.svd(columns / np.maximum(np.linalg.norm(columns, axis=0), 1e-300),
                            full_matrices=False)
    return u[:, s > 1e-10 * s[0]]


def _outside(basis: np.ndarray, x: np.ndarray) -> float:
    return float(np.linalg.norm(x - basis @ (basis.T @ x)))


def floor(library, motion) -> list[float]:
    """Per joint, the smallest relative RMS error any coefficients on library have on motion
    (its q, qd, qdd, tau_clean)."""
    basis = _basis(library.evaluate(motion.q, motion.qd, motion.qdd))
    tau = motion.tau_clean
    return [_outside(basis, tau[:, j]) / float(np.linalg.norm(tau[:, j]))
            for j in range(tau.shape[1])]


def missing_terms(library, exact_model, motion) -> list[dict]:
    """The exact model's terms library cannot represent on motion: joint (1-based), term,
    and the share of that joint's torque RMS outside library's span."""
    basis = _basis(library.evaluate(motion.q, motion.qd, motion.qdd))
    out = []
    for j, joint in enumerate(exact_model.joints):
        norm = float(np.linalg.norm(motion.tau_clean[:, j]))
        for feature, c, term in zip(exact_model.features(j), joint.coefficients, joint.terms,
                                    strict=True):
            share = _outside(basis, c * feature.evaluate(motion.q, motion.qd, motion.qdd)) / norm
            if share > SPANNED:
                out.append({"joint": j + 1, "term": term, "share": share})
    return out


def transfer(library, train, motion, rows: int | None = None) -> list[float]:
    """Per joint, the relative RMS error on motion of least squares on library's columns
    fitted to the clean torque of train's first rows (no noise: what the library itself
    carries over)."""
    part = slice(0, rows)
    X = library.evaluate(train.q[part], train.qd[part], train.qdd[part])
    coef = np.linalg.lstsq(X, train.tau_clean[part], rcond=None)[0]
    tau = motion.tau_clean
    error = library.evaluate(motion.q, motion.qd, motion.qdd) @ coef - tau
    return (np.linalg.norm(error, axis=0) / np.linalg.norm(tau, axis=0)).tolist()


def library_gap(library, exact_model, exact_library, motions: list, train,
                rows: int | None = None) -> dict:
    """floor and noise-free transfer (fitted on train's first rows) per judge motion, the terms library
    lacks (on the first motion) and both libraries' column counts and conditions there."""
    first = motions[0]
    states = (first.q, first.qd, first.qdd)
    return {"library": library.name, "floor": {m.name: floor(library, m) for m in motions},
            "noise_free_fit": {m.name: transfer(library, train, m, rows) for m in motions},
            "missing": missing_terms(library, exact_model, first),
            "columns": len(library.names), "condition": library_condition(library, *states).condition,
            "exact_library": exact_library.name, "exact_columns": len(exact_library.names),
            "exact_condition": library_condition(exact_library, *states).condition}


def markdown(gap: dict, oracle: dict[str, np.ndarray], noise: float) -> str:
    """The note under the identification table: why the library's rows miss the oracle."""
    fresh, name = gap["floor"], gap["library"]
    lacks = "; ".join(f"joint {m['joint']}: `{m['term']}` ({100 * m['share']:.2f} % of its torque "
                      "RMS)" for m in gap["missing"]) or "nothing"
    short = sorted({m["joint"] for m in gap["missing"]})
    bounds = "; ".join(
        f"on `{motion}`, joint {j}: {100 * values[j - 1]:.3f} %, "
        f"{values[j - 1] / oracle[motion][j - 1]:.0f}x the oracle's median error at "
        f"{100 * noise:g} % noise" for motion, values in fresh.items() for j in short)
    spanned = [j + 1 for j, v in enumerate(next(iter(fresh.values()))) if v <= SPANNED]
    carried = "; ".join(
        f"on `{motion}`, joint {j}: {100 * values[j - 1]:.2f} %, {values[j - 1] / oracle[motion][j - 1]:.0f}x"
        for motion, values in gap["noise_free_fit"].items() for j in short)
    text = (f"Why the `{name}` library's rows miss the oracle (harness.identify.library_gap, "
            f"measured on the judge motions' clean torque): its {gap['columns']} features lack "
            f"{lacks}, a term of the exact model (the {gap['exact_library']} library identified "
            "on noise-free data). No coefficients on it do better than its least-squares "
            f"projection on the judge motion itself: {bounds or 'no floor'}. Fitted without "
            "any noise on a draw's training part (least squares on all its columns), it errs "
            f"far more on the judges: {carried or 'nothing'} (against the same oracle): on the "
            "training motion other columns stand in for the missing term, and the stand-in does "
            "not hold on other motions.")
    if spanned:
        text += (f" Joints {', '.join(map(str, spanned))} it spans exactly (floor below "
                 f"{SPANNED:g}): there the gap is estimation on noisy data, {gap['columns']} "
                 f"columns of condition number {gap['condition']:.3g} on the motion against the "
                 f"{gap['exact_library']} library's {gap['exact_columns']} at "
                 f"{gap['exact_condition']:.3g}.")
    return text
