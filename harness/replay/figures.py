"""Figures of replayed plans: power (cf. the paper's Fig. 11) and tracking error."""

from __future__ import annotations

from pathlib import Path

from harness.replay.simulate import ReplayTrace
from harness.report.figures import plt, save_figure


def power_figure(traces: dict[str, ReplayTrace], path: Path) -> Path:
    """|sum tau qd| over time, replayed (solid) and planned feedforward (dashed): one panel
    per plan with its own y-axis, so one plan's power does not flatten the others."""
    fig, axes = plt.subplots(len(traces), 1, figsize=(7, 2.2 * len(traces) + 0.6),
                             sharex=True, squeeze=False)
    for i, (ax, (name, tr)) in enumerate(zip(axes[:, 0], traces.items(), strict=True)):
        ax.plot(tr.t, abs(tr.power), color=f"C{i}", label="replayed")
        ax.plot(tr.t, abs(tr.power_reference), color="k", ls="--", lw=1,
                label="planned (feedforward)")
        ax.set_ylabel("|P| [W]")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time t [s]")
    fig.suptitle("Power |Σ τ_i q̇_i| over time, replayed in MuJoCo", fontsize=10)
    return save_figure(fig, path)


def tracking_figure(traces: dict[str, ReplayTrace], path: Path) -> Path:
    """Joint tracking error q - q_ref in mrad, per joint and plan."""
    fig, ax = plt.subplots(figsize=(7, 4))
    styles = ("-", "--", ":")
    for i, (name, tr) in enumerate(traces.items()):
        error = (tr.q - tr.q_ref) * 1000
        for j in range(error.shape[1]):
            ax.plot(tr.t, error[:, j], color=f"C{i}", ls=styles[j % 3], label=f"{name}: q{j + 1}")
    ax.set(xlabel="time t [s]", ylabel="tracking error q − q_ref [mrad]",
           title="Tracking error of feedforward + PD in MuJoCo")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    return save_figure(fig, path)
