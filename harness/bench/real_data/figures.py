"""Figures of the real-data section: errors per joint, residuals over time and against
velocity per joint (with the named effects' torque drawn over the residual they explain)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.report.figures import plt, save_figure
from identification.closeloop.candidates.effects import effect_torque

FRICTION = ("viscous", "coulomb", "sigmoid")
COLORS = {"nominal": "0.6", "least_squares": "tab:blue", "least_squares_lmi": "tab:cyan",
          "identified": "tab:green",
          "rigid_body": "tab:orange", "closed_loop": "tab:purple"}


def error_figure(errors: dict[str, np.ndarray], reference: list[float], path: Path,
                 title: str = "") -> Path:
    """Held-out relative error per joint of every model (log scale), the reference dashed;
    title: the robot and the log."""
    dof = len(reference)
    fig, ax = plt.subplots(figsize=(9, 3.6))
    width = 0.8 / len(errors)
    x = np.arange(1, dof + 1)
    for k, (name, e) in enumerate(errors.items()):
        ax.bar(x - 0.4 + (k + 0.5) * width, e, width, label=name.replace("_", " "),
               color=COLORS.get(name))
    ax.step(np.r_[x - 0.5, dof + 0.5], np.r_[reference, reference[-1]], where="post",
            color="k", ls="--", lw=1, label="least squares (source README)")
    ax.set(yscale="log", xlabel="joint", xticks=x,
           ylabel="relative RMS error (fraction)\nagainst the measured torque, held out")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, ncol=3)
    return save_figure(fig, path, dpi=110)


def residual_time_figure(t, tau, torques: dict[str, np.ndarray], split: int, path: Path,
                         title: str = "") -> Path:
    """Per joint, measured minus model torque over time; the held-out part shaded; title: the
    robot and the log."""
    dof = tau.shape[1]
    fig, axes = plt.subplots(dof, 1, figsize=(9, 1.5 * dof), sharex=True)
    for j, ax in enumerate(axes):
        for name, torque in torques.items():
            ax.plot(t, tau[:, j] - torque[:, j], lw=0.6, color=COLORS.get(name),
                    label=name.replace("_", " "))
        ax.axvspan(t[split], t[-1], color="0.92", zorder=0)
        ax.set_ylabel(f"r{j + 1} (N m)", fontsize=8)
    axes[0].legend(fontsize=7, ncol=len(torques), loc="upper left")
    axes[0].set_title((f"{title}: " if title else "")
                      + "residual = measured - model torque (shaded: held out)", fontsize=9)
    axes[-1].set_xlabel("t (s)")
    return save_figure(fig, path, dpi=100)


def residual_velocity_figure(states, tau, before, after, terms, path: Path,
                             title: str = "") -> Path:
    """Per joint: the rigid-body identification's residual against the joint velocity, the
    named friction's torque on that joint drawn over it (shifted to the residual's mean), and
    the residual after adding every named effect; title: the robot and the log."""
    q, qd, qdd = states
    dof = tau.shape[1]
    cols = 4
    rows = int(np.ceil(dof / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 2.6 * rows), squeeze=False)
    friction = tuple(t for t in terms if t.effect in FRICTION)
    effects = effect_torque(friction, q, qd, qdd)
    for j in range(rows * cols):
        ax = axes.flat[j]
        if j >= dof:
            ax.axis("off")
            continue
        order = np.argsort(qd[:, j])
        ax.plot(qd[:, j], tau[:, j] - before[:, j], ".", ms=1.5, color=COLORS["rigid_body"],
                label="rigid-body residual")
        ax.plot(qd[:, j], tau[:, j] - after[:, j], ".", ms=1.5, color=COLORS["closed_loop"],
                alpha=0.5, label="after the effects")
        named = [t.effect for t in terms if t.joint == j + 1]
        if any(t.joint == j + 1 for t in friction):
            ax.plot(qd[order, j], effects[order, j] - np.mean(effects[:, j])
                    + np.mean(tau[:, j] - before[:, j]), "k", lw=1, label="named friction (mean aligned)")
        ax.set_title(f"joint {j + 1}: {', '.join(named) or 'none named'}", fontsize=8)
        ax.set_xlabel("joint velocity qd (rad/s)", fontsize=8)
        if j % cols == 0:
            ax.set_ylabel("residual torque (N m)", fontsize=8)
        ax.tick_params(labelsize=7)
    legend = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, handle)
    fig.legend(list(legend.values()), list(legend), loc="lower right", fontsize=9, markerscale=8,
               frameon=False)
    fig.suptitle(title or "residual torque against joint velocity", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)
