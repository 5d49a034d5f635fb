"""Figures of replayed plans: power (cf. the paper's Fig. 11) and tracking error."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.replay.simulate import ReplayTrace
from harness.report.figures import plt, save_figure


def power_figure(traces: dict[str, ReplayTrace], path: Path,
                 replans: dict[str, list[float]] | None = None) -> Path:
    """|sum tau qd| over time, replayed (solid) and planned feedforward (dashed): one panel
    per plan with its own y-axis, so one plan's power does not flatten the others; replans:
    per plan the instants (s) a re-plan took over, dotted (the plan followed changes there,
    its acceleration and so its torque step: the spikes in the power)."""
    fig, axes = plt.subplots(len(traces), 1, figsize=(7, 2.2 * len(traces) + 0.6),
                             sharex=True, squeeze=False)
    for i, (ax, (name, tr)) in enumerate(zip(axes[:, 0], traces.items(), strict=True)):
        ax.plot(tr.t, abs(tr.power), color=f"C{i}", label="replayed")
        ax.plot(tr.t, abs(tr.power_reference), color="k", ls="--", lw=1,
                label="planned (feedforward)")
        when = (replans or {}).get(name, [])
        if len(when):  # ticks on the time axis: the power's steps fall on them
            ax.plot(when, np.zeros(len(when)), "|", color="0.25", ms=9, mew=1,
                    transform=ax.get_xaxis_transform(), clip_on=False,
                    label="a re-plan takes over (its torque steps there)")
        ax.set_ylabel("|P| (W)")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time t (s)")
    fig.suptitle("Power |Σ τ_i q̇_i| over time, replayed in MuJoCo", fontsize=10)
    return save_figure(fig, path)


def tracking_axes(traces: dict[str, ReplayTrace]):
    """One panel per joint (tracking error q - q_ref in mrad), one line per plan in it, the
    plans' legend outside the panels (18 series on one axis hid each other and the data)."""
    dof = next(iter(traces.values())).q.shape[1]
    fig, axes = plt.subplots(dof, 1, figsize=(7.5, 1.5 * dof + 1.0), sharex=True,
                             squeeze=False, layout="constrained")
    for j, ax in enumerate(axes[:, 0]):
        for i, (name, tr) in enumerate(traces.items()):
            ax.plot(tr.t, (tr.q[:, j] - tr.q_ref[:, j]) * 1000, color=f"C{i}", lw=1, label=name)
        ax.set_ylabel(f"q{j + 1} − q{j + 1},ref (mrad)", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time t (s)")
    fig.suptitle("Tracking error of feedforward + PD in MuJoCo, per joint", fontsize=10)
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside right center", fontsize=8)
    return fig


def tracking_figure(traces: dict[str, ReplayTrace], path: Path) -> Path:
    """Joint tracking error q - q_ref in mrad: a panel per joint, a line per plan."""
    return save_figure(tracking_axes(traces), path, tight="none")
