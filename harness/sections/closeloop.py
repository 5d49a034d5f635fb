"""Bench section: close the loop on measured data from plants with undeclared effects.

Plants (models/lynxmotion/): `lynxmotion_friction.xml` (the bench's closeloop plant),
`lynxmotion_payload.xml`, `lynxmotion_coupled.xml` (an effect outside the dictionary)
and `lynxmotion.xml` itself as the control. Each: measured data (5 % torque noise,
zero sensor bias), effects traced and added for both declared models (Pinocchio, and
the model identified on the same training data), held-out error before/after against
the clean measured torque.
"""

from __future__ import annotations

from pathlib import Path

from harness.closeloop import CloseLoopRun, run_closeloop
from harness.closeloop_acceptance import checks, coefficient_errors, floor_criteria
from harness.closeloop_figures import error_figure, residual_figure
from harness.closeloop_plants import DECLARED_MJCF

PLANTS = {"friction": "lynxmotion_friction.xml", "payload": "lynxmotion_payload.xml",
          "coupled (outside dictionary)": "lynxmotion_coupled.xml", "control": "lynxmotion.xml"}


def _fmt(values) -> str:
    return "-" if values is None else ", ".join(f"{v:.2e}" for v in values)


def _verdict(run: CloseLoopRun) -> str:
    ok = checks(run)
    verdict = "pass" if all(ok.values()) else "FAIL: " + ", ".join(k for k, v in ok.items() if not v)
    met = [k for k, v in floor_criteria(run).items() if v]
    return f"{verdict}; within 1.5x of: {', '.join(met) or 'neither'}"


def _row(name: str, run: CloseLoopRun) -> str:
    truth = [f"{t.effect} j{t.joint} {t.coefficient:.4g}" for t in run.truth]
    truth = ", ".join(truth + (["outside the dictionary"] if run.outside_dictionary else [])) or "-"
    named = ", ".join(f"{t.effect} j{t.joint} {t.coefficient:.4g}" for t in run.result.terms)
    absorbed = f" (absorbed: {', '.join(run.absorbed)})" if run.absorbed else ""
    return (f"| {name} | {run.declared} | {truth} | {named or '-'}{absorbed} | "
            f"{_fmt(run.result.error_before)} | {_fmt(run.result.error_after)} | "
            f"{_fmt(run.noise_floor)} | {_fmt(run.truth_error)} | "
            f"{str(run.result.unexplained).lower()} | {_verdict(run)} |")


def _table(runs: dict[str, CloseLoopRun]) -> list[str]:
    lines = ["| plant | declared | plant effects | named effects | error before | error after | "
             "noise floor | truth error | unexplained | acceptance |", "|---" * 10 + "|"]
    for name, run in runs.items():
        lines += [_row(name, r) for r in (run, *run.others)]
    return lines


def _results(run: CloseLoopRun) -> dict:
    res = {**run.to_json(), "checks": checks(run), "floor_criteria": floor_criteria(run),
           "coefficient_errors": coefficient_errors(run)}
    res.pop("diagnostics", None)
    return res


def run(out_dir: Path, quick: bool = False) -> dict:
    """Run every plant with both declared models; markdown, results and figures."""
    out_dir = Path(out_dir)
    figures_dir = out_dir / "figures"
    figures_dir.mkdir(parents=True, exist_ok=True)
    samples = 3000 if quick else 4000
    runs = {name: run_closeloop(DECLARED_MJCF.parent / f, samples=samples, compare=True)
            for name, f in PLANTS.items()}
    figures = [error_figure(runs, figures_dir / "closeloop_errors.png")]
    for name in ("friction", "payload"):
        fig = residual_figure(runs[name], figures_dir / f"closeloop_residual_{name}.png")
        if fig is not None:
            figures.append(fig)
    results = {name: {r.declared: _results(r) for r in (run, *run.others)}
               for name, run in runs.items()}
    md = [
        f"Measured data ({samples} samples at 200 Hz, 5 % torque noise, zero sensor bias, "
        "Savitzky-Golay qd/qdd). Each plant is closed twice on the same data: declared model = "
        "Pinocchio on lynxmotion.urdf, and = the sparse model identified (prior-knowledge "
        "library) on the same training part, whose kept terms are refitted jointly with the "
        "effects by least squares (effects its terms span exactly are `absorbed`: it carries "
        "them already). Errors: held-out (last 25 %) relative RMS against the clean measured "
        "torque, per joint. Noise floor: the plant's true effect set refitted on the same "
        "training data (the acceptance bar, 1.5x); truth error: the true effects at the "
        "plant's own coefficients and friction shape, reported beside it (`within 1.5x of` "
        "says which of the two each row meets).", "",
        *_table(runs), "",
        "Effects are selected by forward selection with BIC over viscous, Coulomb, armature, "
        "offset and spring per joint plus an end-effector payload. The Coulomb candidate is "
        "MuJoCo's regularized dry friction, f clip((qd + lead qdd) / eps, -1, 1) (derived in "
        "identification/effects.py), with lead and eps estimated from the data. "
        "`unexplained` = a joint's residual after the refit is not white (Ljung-Box) and "
        "carries structure above 0.25 noise sigma.", "",
        *[f"![{p.stem}](figures/{p.name})" for p in figures],
    ]
    return {"markdown": "\n".join(md), "results": results, "figures": [str(p) for p in figures]}
