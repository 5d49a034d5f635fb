"""DIR/summary.md: the sweep's grid, the error bands per condition, the figures.

A cell's error is the median over the joints of its relative RMS errors; a condition's band is
the median and the inter-quartile range of that error over the seeds."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.io import atomic_write
from harness.sweep.cell import FRESH_SAMPLES, FRESH_SEED, CellResult
from harness.sweep.grid import Grid


@dataclass(frozen=True)
class Band:
    """The error of one condition over its seeds, and the method's fit time there."""

    robot: str
    method: str
    noise: float
    samples: int
    cells: int
    median: float
    q25: float
    q75: float
    seconds: float  # median fit time, s


def bands(results: list[CellResult]) -> list[Band]:
    """One Band per (robot, method, noise, samples) present in results, in that order."""
    groups: dict[tuple, list[CellResult]] = {}
    for r in results:
        c = r.cell
        groups.setdefault((c.robot, c.method, c.noise, c.samples), []).append(r)
    out = []
    for key in sorted(groups, key=lambda k: (k[0], k[1], k[2], k[3])):
        errors = [r.median for r in groups[key]]
        q25, med, q75 = np.percentile(errors, [25, 50, 75])
        out.append(Band(*key, len(errors), float(med), float(q25), float(q75),
                        float(np.median([r.seconds for r in groups[key]]))))
    return out


def pct(x: float) -> str:
    """A relative error in percent, three significant digits (noise-free cells reach 1e-13 %)."""
    return f"{100 * x:.3g} %"


def command(grid: Grid, out: Path, address: str | None) -> str:
    """The command line that makes this sweep."""
    parts = ["torquebench sweep", f"--robots {','.join(grid.robots)}",
             f"--noise {','.join(f'{n:g}' for n in grid.noise)}", f"--seeds {len(grid.seeds)}",
             f"--methods {','.join(grid.methods)}", f"--samples {','.join(map(str, grid.samples))}"]
    if address:
        parts.append(f"--address {address}")
    return " ".join([*parts, f"--out {out}"])


def _best(bs: list[Band], grid: Grid) -> list[str]:
    """Per robot, the method with the lowest median error at the largest noise and sample count."""
    noise, samples = max(grid.noise), max(grid.samples)
    lines = []
    for robot in grid.robots:
        at = [b for b in bs if b.robot == robot and b.noise == noise and b.samples == samples]
        if at:
            best = min(at, key=lambda b: b.median)
            lines.append(f"- `{robot}` at {noise:.0%} noise, {samples} samples: lowest median error "
                         f"{best.method} ({pct(best.median)}, IQR {pct(best.q25)} - {pct(best.q75)}); "
                         + ", ".join(f"{b.method} {pct(b.median)}" for b in at if b is not best))
    return lines


def write_summary(path: Path, grid: Grid, results: list[CellResult], cmd: str, run: dict,
                  figures: list[str]) -> None:
    """Write summary.md atomically; run: cells computed here, their wall time, cells reused."""
    bs = bands(results)
    rate = f", {run['computed'] / run['wall'] * 60:.1f} cells/min" if run["computed"] and run["wall"] else ""
    md = ["# Sweep", "", f"Command: `{cmd}`", "",
          f"Grid: {len(grid.robots)} robots x {len(grid.noise)} noise levels x {len(grid.seeds)} seeds "
          f"x {len(grid.methods)} methods x {len(grid.samples)} sample counts = {len(grid)} cells; "
          f"{len(results)} in results.csv. This run computed {run['computed']} cells in "
          f"{run['wall']:.1f} s{rate} and reused {run['reused']}.", "",
          "Each cell generates its own data (MuJoCo inverse dynamics along the seed's excitation, "
          "torque noise as a fraction of each joint's torque std), trains the method on all of "
          f"them and is scored on a fresh noise-free trajectory ({FRESH_SAMPLES} samples, seed "
          f"{FRESH_SEED}): relative RMS error per joint against its clean torque. A cell's error "
          "is the median over its joints; each condition below gives the median and the "
          "inter-quartile range over the seeds, and the median time of the method's fit.", "",
          *_best(bs, grid), "",
          "| robot | method | noise | samples | cells | median error | IQR | fit s (median) |",
          "|---|---|---|---|---|---|---|---|"]
    md += [f"| {b.robot} | {b.method} | {b.noise:g} | {b.samples} | {b.cells} | {pct(b.median)} | "
           f"{pct(b.q25)} - {pct(b.q75)} | {b.seconds:.3f} |" for b in bs]
    md += ["", *(f"![{Path(f).stem}]({Path(f).name})" for f in figures), ""]

    def write(tmp: str) -> None:
        Path(tmp).write_text("\n".join(md))

    atomic_write(path, write)
