"""The headline numbers of a bench run, gathered from every section's results.

A section may put its own `"headline": {name: value}` into its results; the
harness adds what it can compute itself (re-plan times from the plans, the
replay's energy and clearance), and for identification falls back to any
held-out / oracle error it finds. Missing numbers are simply absent.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

FALLBACK_KEYS = ("oracle", "rel_rmse", "rel_error", "error_before", "error_after", "unexplained")
MAX_FALLBACK = 8


def _leaves(tree, path: str = "") -> Iterator[tuple[str, object]]:
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from _leaves(value, f"{path}.{key}" if path else str(key))
    else:
        yield path, tree


def _is_number_or_numbers(x) -> bool:
    if isinstance(x, bool | int | float | np.generic):
        return True
    return isinstance(x, list | tuple) and 0 < len(x) <= 12 and all(
        isinstance(v, int | float | np.generic) for v in x)


def fallback(results: dict) -> dict:
    """Error-like numbers of a section that declared no headline."""
    found = {}
    for path, value in _leaves(results):
        if "checks" in path.lower():
            continue
        if any(k in path.lower() for k in FALLBACK_KEYS) and _is_number_or_numbers(value):
            found[path] = value
            if len(found) == MAX_FALLBACK:
                break
    return found


def identification_numbers(results: dict) -> dict:
    """Held-out relative error per joint, sparse model vs oracle, at every noise level."""
    out, levels = {}, results.get("levels") or {}
    try:  # levels are fractions of the torque std (0.05) or percents (5)
        scale = 100.0 if max(float(k) for k in levels) <= 1 else 1.0
    except ValueError:
        return out
    for level, entry in levels.items():
        joints = entry.get("joints", []) if isinstance(entry, dict) else []
        if joints and all("rel" in j and "oracle" in j for j in joints):
            pct = f"{float(level) * scale:g}"
            out[f"noise {pct} %: sparse rel err"] = [j["rel"] for j in joints]
            out[f"noise {pct} %: oracle rel err"] = [j["oracle"] for j in joints]
    return out


def planning_numbers(plans: dict) -> dict:
    """Re-plan time (ms) and replan count from the plans' solve_ms lists."""
    out = {}
    for name, plan in plans.items():
        solves = [float(v) for v in plan.get("solve_ms", []) or []]
        if solves:
            out[f"{name}.first_solve_ms"] = solves[0]
        if len(solves) > 1:
            out[f"{name}.replan_ms_median"] = float(np.median(solves[1:]))
            out[f"{name}.replan_ms_max"] = float(np.max(solves[1:]))
        if "replans" in plan:
            out[f"{name}.replans"] = plan["replans"] if not isinstance(
                plan["replans"], list) else len(plan["replans"])
    return out


def replay_numbers(results: dict) -> dict:
    """Energy, clearance and tracking of every replayed plan, and the side-by-side ratio."""
    out = {}
    for name, r in results.get("plans", {}).items():
        out[f"{name}.energy_planned_J"] = r["energy_planned"]
        out[f"{name}.energy_plan_dense_J"] = r["energy_reference"]
        out[f"{name}.energy_replayed_J"] = r["energy"]
        out[f"{name}.min_clearance_m"] = r["min_clearance"]
        out[f"{name}.surface_clearance_m"] = r["surface_clearance"]
        out[f"{name}.tracking_rms_rad"] = r["tracking_rms"]
        out[f"{name}.acceptance"] = all(r["acceptance"].values())
    side = results.get("comparison")
    if side:
        out["energy_ratio_identified_over_closed_form_replayed"] = side["energy_ratio_replayed"]
        out["energy_ratio_identified_over_closed_form_planned"] = side["energy_ratio_planned"]
    return out


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
    """{'checks failed': 'N of M' or 'none of M', 'failed': 'section: check, ...'} over every
    section's acceptance checks; None when no section declared any."""
    total, failed = 0, []
    for section, results in section_results.items():
        checks = _checks(results) if isinstance(results, dict) else {}
        total += len(checks)
        failed += [f"{section}: {k}" for k, ok in checks.items() if not ok]
    if not total:
        return None
    if not failed:
        return {"checks failed": f"none of {total}"}
    return {"checks failed": f"**{len(failed)} of {total} acceptance checks failed**",
            "failed": ", ".join(failed)}


def headline(section_results: dict[str, dict], plans: dict) -> dict[str, dict]:
    """{section: {quantity: value}} of the headline numbers; 'acceptance' first."""
    out: dict[str, dict] = {}
    summary = acceptance_summary(section_results)
    if summary:
        out["acceptance"] = summary
    for name, results in section_results.items():
        own = results.get("headline") if isinstance(results, dict) else None
        numbers = dict(own) if isinstance(own, dict) else {}
        if name == "identification":
            numbers.update(identification_numbers(results))
        if name == "planning":
            numbers.update(planning_numbers(plans))
        elif name == "replay":
            numbers.update(replay_numbers(results))
        elif not numbers:
            numbers = fallback(results)
        if numbers:
            out[name] = numbers
    return out


def _format(value) -> str:
    if isinstance(value, bool) or value is None:
        return {True: "yes", False: "**no**", None: "–"}[value]
    if isinstance(value, int | float | np.generic):
        close_to_one = 0.99 < abs(float(value)) < 1.01  # ratios: show the small difference
        return f"{float(value):.6g}" if close_to_one else f"{float(value):.4g}"
    if isinstance(value, list | tuple):
        return ", ".join(_format(v) for v in value)
    return str(value)


def headline_markdown(numbers: dict[str, dict]) -> str:
    """The headline as one markdown table (section, quantity, value)."""
    lines = ["| section | quantity | value |", "|---|---|---|"]
    for section, values in numbers.items():
        lines += [f"| {section} | {key} | {_format(v)} |" for key, v in values.items()]
    return "\n".join(lines) if len(lines) > 2 else "_No headline numbers (no section ran)._"
