"""Study `closeloop_plants`: close the loop on measured data from the Lynxmotion's
hand-written plants with undeclared effects (the bench's closeloop section writes its plants
from any arm's model; these are the paper arm's own files).

Plants (models/lynxmotion/): `lynxmotion_friction.xml` (the bench's closeloop plant),
`lynxmotion_payload.xml`, `lynxmotion_coupled.xml` (an effect outside the dictionary)
and `lynxmotion.xml` itself as the control. Each: measured data (5 % torque noise,
zero sensor bias), effects traced and added for both declared models (Pinocchio, and
the model identified on the same training data), held-out error before/after against
the clean measured torque.

Beside them, the same data through `closeloop --data`'s selection (validated on blocks of the
one run, identification.closeloop.selection.runs; Pinocchio declared): whether one selection
could serve the plant path too. What it names against the plant's truth is reported, not
scored; the plant path keeps its own selection while the two disagree.
"""

from __future__ import annotations

from pathlib import Path

from harness.closeloop.acceptance import (
    FLOOR_FACTOR,
    IMPROVEMENT,
    NOISE_BAR,
    absorbed_joints,
    checks,
    coefficient_errors,
    reference_ratios,
)
from harness.closeloop.figures import error_figure, residual_figure
from harness.closeloop.plant import CloseLoopRun, run_closeloop
from harness.closeloop.plants import DECLARED_MJCF
from harness.closeloop.runs import run_runs
from harness.data.generate import SAMPLE_RATE
from harness.data.runs import Runs
from harness.report.results import Context, SectionResult, check
from harness.robots.arm import Arm
from identification.closeloop.selection.plant import UNEXPLAINED_SIZE

NOISE = 0.05  # torque noise std / torque std of the measured data
HOLDOUT = 0.25  # last fraction of the samples, held out for the errors

PLANTS = {"friction": "lynxmotion_friction.xml", "payload": "lynxmotion_payload.xml",
          "coupled (outside dictionary)": "lynxmotion_coupled.xml", "control": "lynxmotion.xml"}


def _fmt(values, spec: str = ".2e") -> str:
    return "-" if values is None else ", ".join(f"{v:{spec}}" for v in values)


def _verdict(run: CloseLoopRun) -> str:
    """Pass/fail, naming the bar checked on held-out errors and the joints it covers."""
    ok = checks(run)
    verdict = "pass" if all(ok.values()) else "FAIL: " + ", ".join(k for k, v in ok.items() if not v)
    ratios = reference_ratios(run).get("noise_floor")
    parts = [verdict]
    if ratios is not None:
        parts.append(f"noise bar after / noise floor {_fmt(ratios, '.2f')} (<= {FLOOR_FACTOR:g})")
    absorbed = absorbed_joints(run)
    if absorbed:
        parts.append(f"joints {', '.join(str(j + 1) for j in absorbed)}: effects absorbed by the "
                     "declared model, checked after <= before (not 1/5)")
    if run.result.fallback:
        parts.append(f"declared model kept on joint(s) {', '.join(map(str, run.result.fallback))}")
    return "; ".join(parts)


def _candidates(run: CloseLoopRun) -> str:
    return ", ".join(f"{c.term.effect} j{c.term.joint}" for c in run.result.candidates) or "-"


def _row(name: str, run: CloseLoopRun) -> str:
    truth = [f"{t.effect} j{t.joint} {t.coefficient:.4g}" for t in run.truth]
    truth = ", ".join(truth + (["outside the dictionary"] if run.outside_dictionary else [])) or "-"
    named = ", ".join(f"{t.effect} j{t.joint} {t.coefficient:.4g}" for t in run.result.terms)
    absorbed = f" (absorbed: {', '.join(run.absorbed)})" if run.absorbed else ""
    r = run.result
    return (f"| {name} | {run.declared} | {truth} | {named or '-'}{absorbed} | {_candidates(run)} | "
            f"{_fmt(r.error_before)} | {_fmt(r.error_after)} | {_fmt(r.error_after_measured)} | "
            f"{_fmt(run.truth_error_measured)} | {_fmt(run.noise_floor)} | "
            f"{_fmt(run.truth_error)} | {str(r.unexplained).lower()} | {_verdict(run)} |")


def _table(runs: dict[str, CloseLoopRun]) -> list[str]:
    head = ("plant", "declared", "plant effects", "named effects", "rejected candidates",
            "error before", "error after", "after vs measured", "truth vs measured",
            "noise floor", "truth error", "unexplained", f"acceptance (bar: {NOISE_BAR})")
    lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for name, run in runs.items():
        lines += [_row(name, r) for r in (run, *run.others)]
    return lines


def _results(run: CloseLoopRun) -> dict:
    res = {**run.to_json(), "checks": checks(run), "reference_ratios": reference_ratios(run),
           "noise_bar": NOISE_BAR, "absorbed_joints": [j + 1 for j in absorbed_joints(run)],
           "coefficient_errors": coefficient_errors(run)}
    res.pop("diagnostics", None)
    return res


def run(ctx: Context) -> SectionResult:
    """Run every plant with both declared models; markdown, results, checks and figures."""
    out_dir, quick = Path(ctx.out_dir), ctx.quick
    figures_dir = out_dir / "figures"
    figures_dir.mkdir(parents=True, exist_ok=True)
    samples = 3000 if quick else 4000
    arm = Arm.of("lynxmotion")  # the plants are the paper arm's own files, whatever ctx.arm
    runs = {name: run_closeloop(Arm.of(DECLARED_MJCF.parent / f), arm, samples=samples,
                                noise=NOISE, holdout=HOLDOUT, compare=True)
            for name, f in PLANTS.items()}
    figures = [error_figure(runs, figures_dir / "closeloop_errors.png")]
    for name in ("friction", "payload"):
        fig = residual_figure(runs[name], figures_dir / f"closeloop_residual_{name}.png")
        if fig is not None:
            figures.append(fig)
    results = {name: {r.declared: _results(r) for r in (run, *run.others)}
               for name, run in runs.items()}
    by_runs = {name: runs_selection(run, arm) for name, run in runs.items()}
    md = [
        f"Measured data ({samples} samples at {SAMPLE_RATE:g} Hz, {100 * NOISE:g} % torque noise, "
        "zero sensor bias, Savitzky-Golay qd/qdd). Each plant is closed twice on the same "
        "data: declared model = Pinocchio on lynxmotion.urdf, and = the sparse model "
        "identified (prior-knowledge library) on the same training part, whose kept terms "
        "are refitted jointly with the effects by least squares (effects its terms span "
        "exactly are `absorbed`: it carries them already). Errors: held-out (last "
        f"{100 * HOLDOUT:g} %) relative RMS against the clean measured torque, per joint "
        "(the contract's error before/after), and against the measured "
        "(noisy) torque. The acceptance bar is what the noise allows on the same data, against "
        f"the clean torque: the extended model's error within {FLOOR_FACTOR:g}x of the noise "
        "floor (declared model + the plant's true effect set, refitted on the same training "
        f"part) on the same held-out samples; plus after <= 1/{IMPROVEMENT:g} of before on the "
        "joints a nameable effect acts on, and after <= before on joints whose effects the "
        "declared model absorbed. Truth error (true coefficients, clean torque) and the errors "
        "against the measured torque are information only. Effects are named only if robust "
        "on the training part (coefficients agree on its two halves, a passive effect is not "
        "negative, leaving it out raises the block cross-validated error); the others are "
        "listed as rejected candidates, and a joint the effects make worse on validation "
        "blocks falls back to the declared model.", "",
        *_table(runs), "",
        "The same data through `closeloop --data`'s selection (forward selection validated on "
        "blocks of the run, physical ranges, load friction and a payload on a body the data "
        "choose; Pinocchio declared; errors against the measured torque):", "",
        "| plant | plant effects | named by the runs selection | the plant's set (nothing where "
        "outside the dictionary) | "
        "error before | error after |", "|---|---|---|---|---|---|",
        *[f"| {name} | {row['truth'] or '-'} | {row['named'] or '-'} | "
          f"{'yes' if row['same_set'] else 'no'} | {_fmt(row['error_before'], '.3f')} | "
          f"{_fmt(row['error_after'], '.3f')} |" for name, row in by_runs.items()], "",
        "Effects are selected by forward selection with BIC over viscous, Coulomb, armature, "
        "offset and spring per joint plus an end-effector payload. The Coulomb candidate is "
        "MuJoCo's regularized dry friction, f clip((qd + lead qdd) / eps, -1, 1) (derived in "
        "identification/effects.py), with lead and eps estimated from the data. "
        "`unexplained` = a joint's residual after the refit is not white (Ljung-Box) and "
        f"carries structure above {UNEXPLAINED_SIZE:g} noise sigma.", "",
        *[f"![{p.stem}](figures/{p.name})" for p in figures],
    ]
    checks = [check(f"{plant}.{declared}.{k}", v) for plant, by_model in results.items()
              for declared, r in by_model.items() for k, v in r["checks"].items()]
    results["runs_selection"] = by_runs
    return SectionResult("\n".join(md), results, checks, figures=figures)


def runs_selection(run: CloseLoopRun, arm: Arm) -> dict:
    """The plant's measured data closed by `closeloop --data`'s loop on the one run (its last
    HOLDOUT scored): what it names against the plant's truth."""
    d = run.data
    arrays = {"q": d.q, "qd": d.qd, "qdd": d.qdd, "tau": d.tau, "tau_clean": d.tau_clean}
    out = run_runs(Runs(arrays, (dict(d.meta),), (str(d.meta["plant"]),), (len(d.q),), (d.t,)),
                   arm, "pinocchio", None, HOLDOUT)
    truth = {(t.effect, t.joint) for t in run.truth}
    named = {(n.term.effect, n.term.joint) for n in out.loop.named}
    return {"truth": ", ".join(f"{t.effect} j{t.joint} {t.coefficient:.4g}" for t in run.truth),
            "named": ", ".join(f"{n.term.effect} j{n.term.joint} {n.term.coefficient:.4g}"
                               for n in out.loop.named),
            "same_set": not named if run.outside_dictionary else truth == named,
            "error_before": out.error_before.tolist(), "error_after": out.error_after.tolist()}
