"""The sweep's figures: error against noise, error against sample count, fit time per method.

Errors are the cells' medians over their joints; lines are the median over the seeds and the
shaded band the inter-quartile range, on a log scale, one colour per method, one panel per
robot."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.report.figures import plt, save_figure
from harness.sweep.grid import Grid
from harness.sweep.summary import Band


def _panels(n: int, title: str):
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.4), squeeze=False)
    fig.suptitle(title, fontsize=10)
    return fig, axes[0]


def _curves(ax, bands: list[Band], methods, x_of) -> dict:
    """One median line + IQR band per method; returns {method: (x, median, q25, q75)}."""
    drawn = {}
    for k, method in enumerate(methods):
        bs = sorted((b for b in bands if b.method == method), key=x_of)
        if not bs:
            continue
        x = np.array([x_of(b) for b in bs], float)
        med, lo, hi = (np.array([getattr(b, a) for b in bs]) * 100 for a in ("median", "q25", "q75"))
        color = f"C{k}"
        ax.plot(x, med, "o-", color=color, label=method, ms=3)
        ax.fill_between(x, lo, hi, color=color, alpha=0.2, lw=0)
        drawn[method] = (x, med, lo, hi)
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    return drawn


def error_vs_noise(bands: list[Band], grid: Grid, path: Path) -> dict:
    samples = max(grid.samples)
    fig, axes = _panels(len(grid.robots), f"Error against noise ({samples} samples; median and "
                        f"IQR over {len(grid.seeds)} seeds)")
    drawn = {}
    for ax, robot in zip(axes, grid.robots, strict=True):
        at = [b for b in bands if b.robot == robot and b.samples == samples]
        drawn[robot] = _curves(ax, at, grid.methods, lambda b: b.noise * 100)
        ax.set(title=robot, xlabel="torque noise (% of torque std)",
               ylabel="relative RMS error (%, median over joints)")
    axes[0].legend(fontsize=8)
    save_figure(fig, path)
    return drawn


def error_vs_samples(bands: list[Band], grid: Grid, path: Path) -> dict:
    noise = max(grid.noise)
    fig, axes = _panels(len(grid.robots), f"Error against sample count ({noise:.0%} noise; median "
                        f"and IQR over {len(grid.seeds)} seeds)")
    drawn = {}
    for ax, robot in zip(axes, grid.robots, strict=True):
        at = [b for b in bands if b.robot == robot and b.noise == noise]
        drawn[robot] = _curves(ax, at, grid.methods, lambda b: b.samples)
        ax.set(title=robot, xlabel="training samples", xscale="log",
               ylabel="relative RMS error (%, median over joints)")
    axes[0].legend(fontsize=8)
    save_figure(fig, path)
    return drawn


def time_per_method(results, grid: Grid, path: Path) -> dict:
    fig, axes = _panels(len(grid.robots), "Fit time per cell and method (all noise levels, seeds "
                        "and sample counts)")
    drawn = {}
    for ax, robot in zip(axes, grid.robots, strict=True):
        times = {m: [r.seconds for r in results if r.cell.robot == robot and r.cell.method == m]
                 for m in grid.methods}
        times = {m: t for m, t in times.items() if t}
        if times:
            ax.boxplot(list(times.values()), tick_labels=list(times), showfliers=True)
        ax.set(title=robot, ylabel="fit time per cell (s)", yscale="log")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        drawn[robot] = times
    save_figure(fig, path)
    return drawn


def write_figures(bands: list[Band], results, grid: Grid, out: Path) -> dict[str, dict]:
    """All three figures into out; {file name: what each panel drew}."""
    return {"error_vs_noise.png": error_vs_noise(bands, grid, out / "error_vs_noise.png"),
            "error_vs_samples.png": error_vs_samples(bands, grid, out / "error_vs_samples.png"),
            "time_per_method.png": time_per_method(results, grid, out / "time_per_method.png")}
