"""The Headline: the README's question answered in at most MAX_ROWS rows.

Does a torque model learned from noisy data plan trajectories as well as the closed-form
model? Each row is built from one run's section results: the identified model's torque
error at the paper's noise level against the clean (closed-form) torque and against the
oracle, the plan energy of the identified vs the closed-form model, the replayed energy and
clearance, the close-the-loop error before/after, and the acceptance checks passed (every
boolean in a dict named `acceptance*` or `checks` in any section's results). A row whose
numbers the run did not produce is left out; study details stay in their sections.
"""

from __future__ import annotations

import numpy as np

PAPER_NOISE = 0.05  # the paper's noise level of Fig. 2 and Table IV (fraction of torque std)
MAX_ROWS = 12
CLOSELOOP_PLANTS = ("friction", "payload")  # plants whose named effects the headline shows
OWN_ROWS = 3  # rows taken from a section's own `headline` dict (another arm's sections)


def _pct(values) -> str:
    return ", ".join(f"{100 * float(v):.3f} %" for v in values)


def _row(question: str, measured: str, **numbers) -> dict:
    return {"question": question, "measured": measured, "numbers": numbers}


def _checks(results: dict, path: str = "") -> dict[str, bool]:
    """A section's acceptance checks: the boolean entries of every dict named
    'acceptance*' or 'checks' anywhere in its results (per plan, per plant, ...)."""
    found: dict[str, bool] = {}
    for key, value in results.items():
        if not isinstance(value, dict):
            continue
        where = f"{path}.{key}" if path else str(key)
        if str(key).startswith("acceptance") or key == "checks":
            found.update({f"{where}.{k}": v for k, v in value.items() if isinstance(v, bool)})
        found.update(_checks(value, where))
    return found


def acceptance_summary(section_results: dict[str, dict]) -> dict | None:
    """{'total', 'passed', 'failed': ['section: check', ...]} over every section's acceptance
    checks; None when no section declared any."""
    total, failed = 0, []
    for section, results in section_results.items():
        checks = _checks(results) if isinstance(results, dict) else {}
        total += len(checks)
        failed += [f"{section}: {k}" for k, ok in checks.items() if not ok]
    if not total:
        return None
    return {"total": total, "passed": total - len(failed), "failed": failed}


def identification_rows(results: dict) -> list[dict]:
    """Identified (coupled sparse) torque error at the paper's noise: vs the clean torque and
    vs the oracle (WLS on Pinocchio's base-parameter regressor), per joint."""
    entry = (results.get("levels") or {}).get(f"{PAPER_NOISE:g}") or {}
    joints = entry.get("joints") or []
    if not joints or not all("rel" in j and "oracle" in j for j in joints):
        return []
    rel, oracle = [j["rel"] for j in joints], [j["oracle"] for j in joints]
    level = f"{100 * PAPER_NOISE:g} %"
    return [
        _row(f"Identified torque model at the paper's {level} noise: held-out relative RMS error "
             "against the clean (closed-form) torque, per joint", _pct(rel), rel=rel),
        _row(f"Same, against the oracle (weighted least squares on Pinocchio's base-parameter "
             f"regressor, same {level} data): error ratio per joint",
             ", ".join(f"{r / o:.2f} x" for r, o in zip(rel, oracle, strict=True))
             + f" (oracle {_pct(oracle)})", ratio=[r / o for r, o in zip(rel, oracle, strict=True)],
             oracle=oracle),
    ]


def planning_rows(results: dict) -> list[dict]:
    """Paper-scenario plan energy of the identified vs the closed-form model."""
    paper = results.get("paper") or {}
    if not {"identified", "pinocchio"} <= paper.keys():
        return []
    e_id, e_cf = (float(paper[k]["energy_pinocchio_J"]) for k in ("identified", "pinocchio"))
    return [_row("Paper scenario: energy of the plan from the identified vs the closed-form model "
                 "(both evaluated with Pinocchio)",
                 f"{e_id:.4f} J vs {e_cf:.4f} J ({100 * (e_id - e_cf) / e_cf:+.3f} %)",
                 identified_J=e_id, closed_form_J=e_cf)]


def replay_rows(results: dict) -> list[dict]:
    """The identified and closed-form plans replayed in MuJoCo: energy, clearance vs lambda."""
    side, plans = results.get("comparison"), results.get("plans") or {}
    if not side or side.get("identified") not in plans or side.get("closed_form") not in plans:
        return []
    ident, closed = plans[side["identified"]], plans[side["closed_form"]]
    clear = [float(ident["min_clearance"]), float(closed["min_clearance"])]
    return [
        _row("The identified and the closed-form plan replayed in MuJoCo (motors, tracking "
             "controller): energy spent",
             f"{ident['energy']:.4f} J vs {closed['energy']:.4f} J (ratio "
             f"{side['energy_ratio_replayed']:.5f})", identified_J=ident["energy"],
             closed_form_J=closed["energy"], ratio=side["energy_ratio_replayed"]),
        _row("Replayed: smallest link-obstacle clearance, identified / closed-form plan",
             f"{1e3 * clear[0]:.1f} / {1e3 * clear[1]:.1f} mm (threshold "
             f"{1e3 * float(ident['threshold']):.0f} mm)", identified_m=clear[0],
             closed_form_m=clear[1], threshold_m=ident["threshold"]),
    ]


def closeloop_rows(results: dict) -> list[dict]:
    """Close-the-loop held-out error before -> after adding the named effects (declared model:
    Pinocchio) on the plants with effects the model lacks."""
    rows = []
    for plant in CLOSELOOP_PLANTS:
        run = (results.get(plant) or {}).get("pinocchio") or {}
        if "error_before" in run and "error_after" in run:
            named = ", ".join(f"{e['effect']} j{e['joint']}" for e in run.get("effects", []))
            rows.append(_row(f"Closing the loop, {plant} plant (named: {named or 'nothing'}): "
                             "Pinocchio model's held-out error before -> after, per joint",
                             f"{_pct(run['error_before'])} -> {_pct(run['error_after'])}",
                             before=run["error_before"], after=run["error_after"]))
    return rows


def own_rows(section: str, results: dict) -> list[dict]:
    """Up to OWN_ROWS entries of a section's own `headline` dict (another arm's sections)."""
    own = results.get("headline") if isinstance(results.get("headline"), dict) else {}
    return [_row(f"{section}: {key}", _format(value), value=value)
            for key, value in list(own.items())[:OWN_ROWS]]


ROWS = {"identification": identification_rows, "planning": planning_rows,
        "replay": replay_rows, "closeloop": closeloop_rows}
ARM_ROWS = {"arm_replay": replay_rows}  # another arm's sections with the same results


def headline(section_results: dict[str, dict], plans: dict | None = None) -> dict:
    """{'rows': [{'question', 'measured', 'numbers'}] (at most MAX_ROWS, the acceptance row
    last), 'acceptance': acceptance_summary or None}. plans: unused, kept for callers."""
    rows: list[dict] = []
    default_robot = any(name in section_results for name in ROWS)
    for name, results in section_results.items():
        if not isinstance(results, dict):
            continue
        if name in ROWS:
            rows += ROWS[name](results)
        elif not default_robot and name in ARM_ROWS:
            rows += ARM_ROWS[name](results)
        elif not default_robot and name.startswith("arm_"):
            rows += own_rows(name, results)
    summary = acceptance_summary(section_results)
    rows = rows[:MAX_ROWS - 1]
    if summary:
        failed = summary["failed"]
        rows.append(_row("Acceptance checks passed (every section's)",
                         f"{summary['passed']} of {summary['total']}"
                         + (f"; **failed**: {', '.join(failed)}" if failed else ""),
                         passed=summary["passed"], total=summary["total"]))
    return {"rows": rows, "acceptance": summary}


def _format(value) -> str:
    if isinstance(value, bool) or value is None:
        return {True: "yes", False: "**no**", None: "–"}[value]
    if isinstance(value, int | float | np.generic):
        return f"{float(value):.4g}"
    if isinstance(value, list | tuple):
        return ", ".join(_format(v) for v in value)
    return str(value)


def headline_markdown(numbers: dict) -> str:
    """The headline as one markdown table (question, measured)."""
    rows = numbers.get("rows") or []
    if not rows:
        return "_No headline numbers (no section ran)._"
    return "\n".join(["| question | measured |", "|---|---|",
                      *(f"| {r['question']} | {r['measured']} |" for r in rows)])
