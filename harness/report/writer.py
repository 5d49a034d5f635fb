"""Bench report: DIR/report.md, DIR/report.json and DIR/headline.md, each complete or absent."""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from harness.io import write_json, write_text
from harness.report.headline import headline_markdown

TITLES = {
    "identification": "Identification (paper Figs. 2–8, Tables III/IV)",
    "planning": "Planning (paper Figs. 9–11)",
    "replay": "Replay in MuJoCo",
    "closeloop": "Closing the loop on measured data",
    "real_data": "Real measured data: a Franka Emika Panda (Gaz et al. 2019)",
}


@dataclass(frozen=True)
class SectionOutcome:
    """What one bench section produced. status: 'ok', 'failed' or 'not available'."""

    name: str
    status: str
    seconds: float = 0.0
    markdown: str = ""
    results: dict = field(default_factory=dict)
    figures: tuple[str, ...] = ()
    error: str = ""


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


def _relative_figures(outcome: SectionOutcome, out_dir: Path) -> SectionOutcome:
    """The outcome with figure paths relative to out_dir (report.json does not depend on
    where the run wrote)."""
    base = out_dir.resolve()
    rel = tuple(Path(f).resolve().relative_to(base).as_posix()
                if Path(f).resolve().is_relative_to(base) else f for f in outcome.figures)
    return replace(outcome, figures=rel)


def report_json(outcomes: list[SectionOutcome], numbers: dict, meta: dict) -> dict:
    """The machine-readable report: headline, per-section status and results."""
    return _clean({
        **meta,
        "ok": all(o.status != "failed" for o in outcomes),
        "acceptance_failed": (numbers.get("acceptance") or {}).get("failed", []),
        "headline": numbers,
        "sections": {o.name: {k: v for k, v in asdict(o).items() if k not in ("name", "markdown")}
                     for o in outcomes},
    })


def _figure_links(outcome: SectionOutcome, out_dir: Path) -> list[str]:
    """Image links relative to report.md, for figures the section's text does not show yet."""
    links, base = [], out_dir.resolve()
    for fig in outcome.figures:
        path = Path(fig).resolve()  # a relative figure path is relative to the working directory
        rel = path.relative_to(base) if path.is_relative_to(base) else path
        if f"]({rel.as_posix()})" not in outcome.markdown:
            links.append(f"![{path.stem}]({rel.as_posix()})")
    return links


def _section_markdown(outcome: SectionOutcome, out_dir: Path) -> list[str]:
    body = outcome.markdown.strip()
    if body.startswith("## "):  # the section brought its own title
        title, _, body = body.partition("\n")
        title = title[3:].strip()
    else:
        title = TITLES.get(outcome.name, outcome.name)
    lines = [f"## {title}", ""]
    if outcome.status == "not available":
        return lines + ["_Section not available yet._", ""]
    if outcome.status == "failed":
        return lines + [f"**FAILED** after {outcome.seconds:.1f} s: `{outcome.error}`", ""]
    lines += [f"_{outcome.seconds:.1f} s_", "", body.strip(), ""]
    return lines + [link for link in _figure_links(outcome, out_dir)] + [""]


def report_markdown(outcomes: list[SectionOutcome], numbers: dict, meta: dict,
                    out_dir: Path) -> str:
    """The human-readable report."""
    failed = [o.name for o in outcomes if o.status == "failed"]
    missing = [o.name for o in outcomes if o.status == "not available"]
    status = f"all {len(outcomes)} sections ran" if not failed and not missing else "; ".join(
        filter(None, [f"failed: {', '.join(failed)}" if failed else "",
                      f"not available: {', '.join(missing)}" if missing else ""]))
    verdict = numbers.get("acceptance") or {}
    if not verdict:
        status += "; no acceptance checks"
    elif verdict["failed"]:
        status += (f"; **{len(verdict['failed'])} of {verdict['total']} acceptance checks "
                   f"failed** ({', '.join(verdict['failed'])})")
    else:
        status += f"; all {verdict['total']} acceptance checks passed"
    elapsed = (meta.get("timing") or {}).get("elapsed_s", 0.0)
    lines = [
        "# torquebench report", "",
        f"Robot `{meta.get('robot')}`, {elapsed:.0f} s in total"
        f"{' (quick mode)' if meta.get('quick') else ''}: {status}.", "",
        "## Headline", "", headline_markdown(numbers), "",
    ]
    for outcome in outcomes:
        lines += _section_markdown(outcome, out_dir)
    return "\n".join(lines).rstrip() + "\n"


def write_report(out_dir: Path, outcomes: list[SectionOutcome], numbers: dict,
                 meta: dict) -> dict:
    """Write report.json, report.md and headline.md into out_dir; returns the JSON payload."""
    out_dir = Path(out_dir)
    payload = report_json([_relative_figures(o, out_dir) for o in outcomes], numbers, meta)
    json.dumps(payload, allow_nan=False)  # fail before writing anything
    write_text(out_dir / "headline.md", headline_markdown(payload["headline"]) + "\n")
    write_text(out_dir / "report.md", report_markdown(outcomes, numbers, meta, out_dir))
    write_json(out_dir / "report.json", payload)
    return payload
