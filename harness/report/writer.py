"""Bench report: DIR/report.md, DIR/report.json and DIR/headline.md, each complete or absent.

report.json: the run's meta (robot, command, machine, timing), `ok`, every failed check,
the targets table, the headline rows, and per section its status, results, checks,
targets, figures and warnings. Keys named `timing`, `seconds`, `*_s` or `*_ms` hold the
figures that depend on the machine's speed and load; everything else is the same on every
run of the same configuration (tests/test_bench.py).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from harness.io import write_json, write_text
from harness.report.results import Check, Row, SectionResult, Target, distinct

TITLES = {
    "identification": "Identification",
    "planning": "Planning around a moving obstacle",
    "replay": "Replay in MuJoCo",
    "closeloop": "Closing the loop on measured data",
    "real_data": "Real measured logs",
}


@dataclass(frozen=True)
class SectionOutcome:
    """What one section or study produced. status: 'ok' or 'failed'."""

    name: str
    status: str
    seconds: float = 0.0
    markdown: str = ""
    results: dict = field(default_factory=dict)
    checks: tuple[Check, ...] = ()
    targets: tuple[Target, ...] = ()
    headline: tuple[Row, ...] = ()
    figures: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    error: str = ""

    @classmethod
    def of(cls, name: str, result: SectionResult, seconds: float, warnings=()) -> SectionOutcome:
        return cls(name, "ok", seconds, result.markdown, result.results, tuple(result.checks),
                   tuple(result.targets), tuple(result.headline),
                   tuple(str(f) for f in result.figures), tuple(warnings))


def _clean(x):
    """JSON-safe copy: arrays to lists, non-finite floats to None, unknown objects to str."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    if isinstance(x, np.generic):
        return _clean(x.item())
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if x is None or isinstance(x, bool | int | str):
        return x
    if isinstance(x, Path):
        return str(x)
    return repr(x)


def _relative(figures, out_dir: Path) -> list[str]:
    """Figure paths relative to out_dir (the report does not depend on where the run wrote)."""
    base = out_dir.resolve()
    return [Path(f).resolve().relative_to(base).as_posix()
            if Path(f).resolve().is_relative_to(base) else str(f) for f in figures]


def _target(section: str, t: Target) -> dict:
    return {"section": section, **asdict(t), "met": t.met, "gap": t.gap}


def failed_checks(outcomes) -> list[str]:
    return [f"{o.name}: {c.name}" for o in outcomes for c in o.checks if not c.passed]


def report_json(outcomes: list[SectionOutcome], meta: dict, out_dir: Path) -> dict:
    """The machine-readable report."""
    sections = {}
    for o in outcomes:
        sections[o.name] = {
            "status": o.status, "error": o.error, "seconds": o.seconds, "results": o.results,
            "checks": [asdict(c) for c in o.checks],
            "targets": [_target(o.name, t) for t in o.targets],
            "figures": _relative(o.figures, out_dir), "warnings": list(o.warnings)}
    return _clean({
        **meta,
        "ok": all(o.status == "ok" for o in outcomes) and not failed_checks(outcomes),
        "checks": {"total": sum(len(o.checks) for o in outcomes),
                   "failed": failed_checks(outcomes)},
        "targets": [_target(o.name, t) for o in outcomes for t in o.targets],
        "headline": [{"section": o.name, **asdict(r)} for o in outcomes for r in o.headline],
        "sections": sections,
    })


def _number(x: float | None, unit: str, text: str | None = None) -> str:
    if x is None:
        return "–"
    return f"{text or f'{x:.3g}'} {unit}".strip()


def targets_markdown(outcomes) -> list[str]:
    """The targets table: what is aimed at, measured against it (with the digits that tell
    them apart), and the gap of a missed one (blank where met)."""
    rows = [(o.name, t) for o in outcomes for t in o.targets]
    if not rows:
        return ["_No targets._"]
    md = ["| section | target | measured | aim | gap | met |", "|---|---|---|---|---|---|"]
    for name, t in rows:
        measured, target = (distinct([t.measured, t.target]) if t.met is not None
                            else (None, None))
        aim = f"{'<=' if t.lower_is_better else '>='} {_number(t.target, t.unit, target)}"
        met = {True: "yes", False: "**no**", None: "–"}[t.met]
        timing = " (timing)" if t.timing else ""
        note = f" _({t.note})_" if t.note else ""  # where it is scored, what it is not
        gap = "" if t.met else _number(t.gap, t.unit)
        md.append(f"| {name} | {t.name}{timing}{note} | {_number(t.measured, t.unit, measured)} | "
                  f"{aim} | {gap} | {met} |")
    return md


def targets_verdict(outcomes) -> str:
    """What the top line says of the targets: how many met, missed and not measured (the
    missed ones are named below it: targets_missed)."""
    targets = [t for o in outcomes for t in o.targets]
    if not targets:
        return "no targets"
    missed = sum(t.met is False for t in targets)
    unmeasured = sum(t.met is None for t in targets)
    text = f"{sum(t.met is True for t in targets)} of {len(targets)} targets met"
    counts = [f"{n} {what}" for n, what in ((missed, "missed"), (unmeasured, "not measured"))
              if n]
    return f"**{text}** ({', '.join(counts)}: listed below)" if missed else \
        text + (f" ({counts[0]}: listed below)" if counts else "")


def targets_missed(outcomes, limit: int | None = None) -> list[str]:
    """One bullet per missed, then per unmeasured target (section: name); at most limit
    bullets, the rest counted in a last one."""
    targets = [(o.name, t) for o in outcomes for t in o.targets]
    lines = [*(f"- missed: {name}: {t.name}" for name, t in targets if t.met is False),
             *(f"- not measured: {name}: {t.name}" for name, t in targets if t.met is None)]
    if limit is not None and len(lines) > limit:
        lines = [*lines[:limit - 1], f"- ... and {len(lines) - limit + 1} more (report.md)"]
    return lines


def headline_markdown(outcomes) -> list[str]:
    rows = [r for o in outcomes for r in o.headline]
    if not rows:
        return ["_No headline numbers (no section ran)._"]
    return ["| question | measured |", "|---|---|",
            *(f"| {r.question} | {r.measured} |" for r in rows)]


def _section_markdown(o: SectionOutcome, out_dir: Path) -> list[str]:
    lines = [f"## {TITLES.get(o.name, o.name)}", ""]
    if o.status == "failed":
        return lines + [f"**FAILED** after {o.seconds:.1f} s: `{o.error}`", ""]
    failed = [c for c in o.checks if not c.passed]
    verdict = (f"all {len(o.checks)} checks hold" if not failed else
               f"**{len(failed)} of {len(o.checks)} checks failed**: "
               + "; ".join(f"{c.name} ({c.detail})" for c in failed))
    lines += [f"_{o.seconds:.1f} s; {verdict}._", "", o.markdown.strip(), ""]
    for w in o.warnings:
        lines.append(f"> warning: {w}")
    links = [f"![{Path(f).stem}]({f})" for f in _relative(o.figures, out_dir)
             if f"]({f})" not in o.markdown]
    return lines + links + [""]


def status_line(outcomes, meta: dict) -> str:
    """The report's top line (under 200 characters): the robot, the time, how many checks
    hold and how many targets were met; what failed or was missed is listed below it."""
    failed = [o.name for o in outcomes if o.status == "failed"]
    checks = failed_checks(outcomes)
    total = sum(len(o.checks) for o in outcomes)
    status = (f"{len(failed)} sections failed" if failed else
              f"**{len(checks)} of {total} checks failed**" if checks else
              f"all {total} checks hold") + f"; {targets_verdict(outcomes)}"
    elapsed = (meta.get("timing") or {}).get("elapsed_s", 0.0)
    robot = str(meta.get("robot"))
    robot = Path(robot).name if "/" in robot else robot  # a file's path: its name
    return (f"Robot `{robot}`, {elapsed:.0f} s in total"
            f"{' (quick mode)' if meta.get('quick') else ''}: {status}.")


def report_markdown(outcomes: list[SectionOutcome], meta: dict, out_dir: Path) -> str:
    """The human-readable report."""
    failed = [o.name for o in outcomes if o.status == "failed"]
    below = [*(f"- section failed: {name}" for name in failed),
             *(f"- check failed: {name}" for name in failed_checks(outcomes)),
             *targets_missed(outcomes)]
    lines = ["# torquebench report", "", status_line(outcomes, meta), "",
             *below, *([""] if below else []),
             "Checks must hold (a failure is a bug and fails the run); targets are what the "
             "project aims at, reported with their gap.", "",
             "## Headline", "", *headline_markdown(outcomes), "",
             "## Targets", "", *targets_markdown(outcomes), ""]
    for outcome in outcomes:
        lines += _section_markdown(outcome, out_dir)
    return "\n".join(lines).rstrip() + "\n"


HEADLINE_LINES = 40  # headline.md stays shorter than this


def headline_file(outcomes, meta: dict) -> list[str]:
    """headline.md: the top line, the headline rows and the targets missed or not measured
    (the whole table is report.md's), under HEADLINE_LINES lines."""
    lines = [status_line(outcomes, meta), "", "## Headline", "", *headline_markdown(outcomes),
             "", "## Targets", "", f"{targets_verdict(outcomes)}; the whole table: report.md."]
    room = HEADLINE_LINES - 2 - len(lines)
    missed = targets_missed(outcomes, max(room, 1))
    return [*lines, *([""] if missed else []), *missed]


def write_report(out_dir: Path, outcomes: list[SectionOutcome], meta: dict) -> dict:
    """Write report.json, report.md and headline.md into out_dir; returns the JSON payload."""
    out_dir = Path(out_dir)
    payload = report_json(outcomes, meta, out_dir)
    json.dumps(payload, allow_nan=False)  # fail before writing anything
    write_text(out_dir / "headline.md", "\n".join(headline_file(outcomes, meta)) + "\n")
    write_text(out_dir / "report.md", report_markdown(outcomes, meta, out_dir))
    write_json(out_dir / "report.json", payload)
    return payload
