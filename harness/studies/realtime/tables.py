"""The realtime study's tables (markdown) and the issue's acceptance flags, from the
study's result (harness.studies.realtime.measure.run)."""

from __future__ import annotations

import numpy as np

from harness.studies.realtime import references
from harness.studies.realtime.measure import common_sums


def _ms(d: dict) -> str:
    if not d["count"]:
        return "none"
    return f"{d['median']:.2f} / {d['p95']:.2f} / {d['max']:.2f}"


def _pct(value) -> str:
    return "n/a" if value is None or not np.isfinite(value) else f"{value:+.2f} %"


def markdown_lines(study: dict) -> list[str]:
    """The study's tables: timing distributions per way in, deadline behaviour, optimality."""
    setup, default = study["setup"], study["default"]
    sums, count = common_sums(study["ways_in"])
    lines = [
        f"**Real time over {setup['scenarios']} random scenarios** (seed {setup['seed']}: "
        "start, goal, obstacle path crossing the unobstructed optimum, sway; Lynxmotion, "
        f"obstacle active). Default planner: {study['config']}. Times in ms as median / p95 / "
        "max; CPU = CPU time of the planning thread (insensitive to other load on the "
        "machine), wall = wall clock on this run's machine.", "",
        "| way in | cold plan, CPU | cold plan, wall | warm re-plan, CPU | warm re-plan, wall "
        f"| re-plans | failed | executed, replayed (J, sum over the {count} scenarios every "
        "way executed feasibly) | infeasible executions |",
        "|---|---|---|---|---|---|---|---|---|"]
    for name, row in study["ways_in"].items():
        lines.append(f"| {name} | {_ms(row['cold_cpu_ms'])} | {_ms(row['cold_wall_ms'])} | "
                     f"{_ms(row['replan_cpu_ms'])} | {_ms(row['replan_wall_ms'])} | "
                     f"{row['replans_attempted']} | {row['replan_failures']} | "
                     f"{sums[name]:.3f} | {row['executed_infeasible']} |")
    lines += [
        "", f"With a deadline of {setup['deadline_ms']:g} ms CPU per re-plan (one obstacle "
        f"sample period), the default planner attempted {default['replans_attempted']} "
        f"re-plans: {default['deadline_misses']} missed the deadline and "
        f"{default['replan_failures']} failed (unconverged, or refused beyond a joint limit; "
        "the arm kept its last plan each time, Algorithm 2, and tried again at the next "
        f"sample); warm re-plan CPU {_ms(default['replan_cpu_ms'])} ms, cold plan "
        f"CPU {_ms(default['cold_cpu_ms'])} ms.", "",
        "**Safety of what each way executed** (over all scenarios): smallest clearance, worst "
        "joint-limit excursion, largest |tau| / torque limit.", "",
        "| way in | min clearance (mm) | limit excursion (rad) | torque / limit |",
        "|---|---|---|---|"]
    for name, row in study["ways_in"].items():
        lines.append(f"| {name} | {1e3 * row['executed_min_clearance_m']:.1f} | "
                     f"{row['executed_limit_excursion_rad']:.1e} | "
                     f"{row['executed_torque_ratio']:.3f} |")
    return lines + ["", f"The anytime SQP: {study['anytime_way']}."] + \
        references.markdown(study["references"])


def acceptance(study: dict) -> dict:
    """The issue's targets, on CPU time (wall times on a shared machine are reported beside)."""
    default, refs = study["default"], study["references"]
    warm, cold = default["replan_cpu_ms"], default["cold_cpu_ms"]
    per, causal = refs["per_replan"], refs["causal"]
    return {"random_replan_cpu_max_le_10ms": warm["count"] == 0 or warm["max"] <= 10,
            "random_replan_cpu_median_le_2ms": warm["count"] == 0 or warm["median"] <= 2,
            "random_cold_plan_cpu_max_le_25ms": cold["max"] <= 25,
            "replans_within_0.5pct_of_same_forecast_multistart_ge_95pct":
                per["within"] >= 0.95 * per["replans"],
            "executed_within_0.5pct_of_causal_multistart_ge_18_of_20":
                causal["within"] >= 0.9 * causal["scenarios"]}
