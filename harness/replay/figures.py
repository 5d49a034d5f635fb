"""Figures of replayed plans: power (cf. the paper's Fig. 11), clearance vs threshold
(Fig. 10), end-effector path with the obstacle path (Fig. 9) and tracking error."""

from __future__ import annotations

from pathlib import Path

from harness.replay.simulate import ReplayTrace
from harness.report.figures import plt, save_figure

MARGIN = 0.005  # m, acceptance band below the threshold


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


def model_power_figure(traces: dict[str, ReplayTrace], path: Path) -> Path:
    """Paper Fig. 11: replayed power of the paper scenario planned with each model (closed
    form and identified) on one axis, and their difference below."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5), sharex=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    for i, (name, tr) in enumerate(traces.items()):
        top.plot(tr.t, tr.power, color=f"C{i}", ls="-" if i == 0 else "--", label=name)
    top.axhline(0, color="k", lw=0.5)
    top.set(ylabel="power Σ τ_i q̇_i [W]",
            title="Paper scenario, replayed: closed-form vs identified model (cf. Fig. 11)")
    top.grid(alpha=0.3)
    top.legend(fontsize=8)
    names = list(traces)
    if len(names) >= 2:
        a, b = traces[names[0]], traces[names[1]]
        n = min(len(a.t), len(b.t))
        bottom.plot(a.t[:n], b.power[:n] - a.power[:n], color="C3")
        bottom.set_ylabel(f"{names[1]} − {names[0]} [W]", fontsize=8)
    bottom.axhline(0, color="k", lw=0.5)
    bottom.set_xlabel("time t [s]")
    bottom.grid(alpha=0.3)
    return save_figure(fig, path)


def clearance_figure(traces: dict[str, ReplayTrace], threshold: float, path: Path) -> Path:
    """Centre-to-segment distance of link 2 (d1) and link 3 (d2) to the obstacle."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for i, (name, tr) in enumerate(traces.items()):
        ax.plot(tr.t, tr.clearance[:, 0], color=f"C{i}", label=f"{name}: d1 (link 2)")
        ax.plot(tr.t, tr.clearance[:, 1], color=f"C{i}", ls="-.", label=f"{name}: d2 (link 3)")
    ax.axhline(threshold, color="k", lw=1, label=f"threshold λ = {threshold * 1000:.0f} mm")
    ax.axhline(threshold - MARGIN, color="k", lw=1, ls=":", label="λ − 5 mm (acceptance)")
    ax.set(xlabel="time t [s]", ylabel="distance obstacle centre to link [m]",
           title="Distance to obstacle vs threshold, replayed (cf. paper Fig. 10)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def path_figure(traces: dict[str, ReplayTrace], path: Path) -> Path:
    """3D end-effector paths of the replays and the obstacle's path."""
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    for i, (name, tr) in enumerate(traces.items()):
        ax.plot(*tr.end_effector.T, color=f"C{i}", label=f"{name}: end effector")
    first = next(iter(traces.values()))
    ax.plot(*first.obstacle.T, color="k", lw=2, label="obstacle centre (dot: t = 0)")
    ax.scatter(*first.obstacle[0], color="k", marker="o", s=15)
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]",
           title="Replayed paths and obstacle (cf. paper Fig. 9)")
    ax.legend(fontsize=8)
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
