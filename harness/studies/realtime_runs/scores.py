"""The runs' scores: per scenario and condition, the refusals, the smallest executed clearance
of each run against the threshold, the executed energy's spread; the targets (every run
keeps the clearance, none refused) per condition; the report's tables."""

from __future__ import annotations

import numpy as np

from harness.report.results import Target
from planning.result import CLEARANCE_TOLERANCE


def scored(runs: list[dict], threshold: float) -> dict:
    """One scenario's runs under one condition: how many ran, were refused, kept the
    clearance (executed, threshold less the tolerance) or raised; each run's smallest
    clearance less the threshold (m, None where nothing was executed); the energies of the
    runs `plan` writes (J) with their min, median, max and spread (max - min, and relative
    to the median); the warm re-plans' CPU max over the runs (ms)."""
    margins = [None if r.get("min_clearance_m") is None else r["min_clearance_m"] - threshold
               for r in runs]
    energies = [r["energy_J"] for r in runs if not r.get("refused", True)]
    cpu = [r["replan_cpu_max_ms"] for r in runs if r.get("replan_cpu_max_ms") is not None]
    spread = {"min": None, "median": None, "max": None, "spread": None, "spread_pct": None}
    if energies:
        low, median, high = np.min(energies), np.median(energies), np.max(energies)
        spread = {"min": float(low), "median": float(median), "max": float(high),
                  "spread": float(high - low), "spread_pct": float(100 * (high - low) / median)}
    return {"runs": len(runs), "refused": sum(bool(r.get("refused")) for r in runs),
            "errors": sum("error" in r for r in runs),
            "kept": sum(m is not None and m >= -CLEARANCE_TOLERANCE for m in margins),
            "margins_m": margins,
            "smallest_margin_m": min((m for m in margins if m is not None), default=None),
            "energy_J": spread, "replan_cpu_max_ms": max(cpu, default=None)}


def targets(conditions: dict[str, list[dict]], note: str) -> list[Target]:
    """Per condition (its scenarios' scores): every run keeps the clearance; none refused."""
    found = []
    for name, rows in conditions.items():
        runs = sum(r["runs"] for r in rows)
        found += [Target(f"{name}: runs whose execution keeps the clearance (threshold - "
                         f"{1e3 * CLEARANCE_TOLERANCE:g} mm)", sum(r["kept"] for r in rows),
                         runs, "runs", lower_is_better=False, timing=True, note=note),
                  Target(f"{name}: runs `plan --realtime` refuses", sum(r["refused"] for r in rows),
                         0, "runs", timing=True, note=note)]
    return found


def _mm(margin) -> str:
    return "-" if margin is None else f"{1e3 * margin:+.2f}"


def table(conditions: dict[str, list[dict]]) -> list[str]:
    """Markdown: per condition and scenario, the runs, refusals, the smallest clearance's
    margin over the threshold (mm), the executed energy's min / median / max and spread."""
    lines = ["| condition | scenario | runs | refused | keep the clearance | smallest margin "
             "(mm) | energy min / median / max (J) | spread (J, % of median) | re-plan CPU "
             "max (ms) |", "|---|---|---|---|---|---|---|---|---|"]
    for name, rows in conditions.items():
        for i, row in enumerate(rows):
            e = row["energy_J"]
            energy = "-" if e["min"] is None else \
                f"{e['min']:.5f} / {e['median']:.5f} / {e['max']:.5f}"
            spread = "-" if e["min"] is None else f"{e['spread']:.2e} ({e['spread_pct']:.3f} %)"
            cpu = "-" if row["replan_cpu_max_ms"] is None else f"{row['replan_cpu_max_ms']:.2f}"
            lines.append(f"| {name} | {i} | {row['runs']} | {row['refused']} | {row['kept']} | "
                         f"{_mm(row['smallest_margin_m'])} | {energy} | {spread} | {cpu} |")
    return lines
