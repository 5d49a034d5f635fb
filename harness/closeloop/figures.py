"""Figures of the closed loop: residual against each named effect's signal; errors per joint."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.closeloop.plant import CloseLoopRun
from harness.report.figures import plt, save_figure
from identification.closeloop.candidates.effects import UNITS, effect_torque

AXIS = {"viscous": ("qd", "rad/s"), "coulomb": ("qd + lead qdd", "rad/s"),
        "armature": ("qdd", "rad/s^2"), "offset": ("sample", "-"), "spring": ("q", "rad"),
        "payload": ("unit-payload torque", "N m/kg")}


def _signal(run: CloseLoopRun, term, rows: slice) -> tuple[np.ndarray, int]:
    """x-axis signal of a term and the joint it is plotted on (payload: the largest)."""
    d = run.data
    q, qd, qdd = d.q[rows], d.qd[rows], d.qdd[rows]
    if term.effect == "payload":
        unit = run.result.model._payload(q, qd, qdd)
        j = int(np.argmax(np.std(unit, axis=0)))
        return unit[:, j], j
    j = term.joint - 1
    x = {"viscous": qd, "coulomb": qd + term.lead * qdd, "armature": qdd,
         "spring": q, "offset": np.tile(np.arange(len(q))[:, None], (1, q.shape[1]))}[term.effect]
    return x[:, j], j


def residual_figure(run: CloseLoopRun, path: Path) -> Path | None:
    """Partial residual (measured - declared - the other named effects) vs each effect's signal."""
    terms = run.result.terms
    if not terms:
        return None
    rows = slice(0, run.result.split)
    d = run.data
    model = run.result.model
    residual = d.tau[rows] - model.declared.torque(d.q[rows], d.qd[rows], d.qdd[rows])
    fig, axes = plt.subplots(1, len(terms), figsize=(3.6 * len(terms), 3.2), squeeze=False)
    for ax, term in zip(axes[0], terms, strict=True):
        others = tuple(t for t in terms if t is not term)
        partial = residual - effect_torque(others, d.q[rows], d.qd[rows], d.qdd[rows],
                                           model._payload)
        own = effect_torque((term,), d.q[rows], d.qd[rows], d.qdd[rows], model._payload)
        x, j = _signal(run, term, rows)
        order = np.argsort(x)
        ax.plot(x, partial[:, j], ".", ms=1.5, alpha=0.4, label="residual")
        ax.plot(x[order], own[order, j], "r-", lw=1.5, label=f"{term.effect} fit")
        name, unit = AXIS[term.effect]
        ax.set_xlabel(f"{name}{term.joint if term.effect != 'payload' else ''} ({unit})")
        ax.set_ylabel(f"residual joint {j + 1} (N m)")
        ax.set_title(f"{term.effect} j{term.joint}: {term.coefficient:.4g} {UNITS[term.effect]}",
                     fontsize=9)
        ax.legend(fontsize=7, markerscale=4)
    save_figure(fig, path, dpi=110)
    return path


def error_figure(runs: dict[str, CloseLoopRun], path: Path) -> Path:
    """Held-out relative RMS error per joint before/after, for each declared model of each
    plant (the noise floor marked on the after bars)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(3.8 * len(runs), 3.4), squeeze=False)
    for ax, (name, run) in zip(axes[0], runs.items(), strict=True):
        group = (run, *run.others)
        width = 0.8 / (2 * len(group))
        joints = np.arange(1, len(run.result.error_before) + 1)
        for g, r in enumerate(group):
            x0 = joints - 0.4 + width * (2 * g + 0.5)
            ax.bar(x0, r.result.error_before, width, label=f"{r.declared}", alpha=0.45,
                   color=f"C{g}")
            ax.bar(x0 + width, r.result.error_after, width, label=f"{r.declared} + effects",
                   color=f"C{g}")
            if r.noise_floor is not None:
                ax.plot(x0 + width, r.noise_floor, "k_", ms=8, mew=2,
                        label="noise floor" if g == 0 else None)
        ax.set_yscale("log")
        ax.set_xticks(joints)
        ax.set_xlabel("joint")
        ax.set_ylabel("held-out relative RMS torque error")
        ax.set_title(name, fontsize=9)
        ax.legend(fontsize=6)
    save_figure(fig, path, dpi=110)
    return path


def events_figure(found, path: Path, pushes=(), title: str = "") -> Path | None:
    """The observer's external-torque estimate (persistent effects removed) per joint over a
    run, its thresholds, the events found (shaded: left out of the loop) and, in simulation,
    the pushes (dashed)."""
    if found.residual is None:
        return None
    t, r = found.t, found.residual
    dof = r.shape[1]
    fig, axes = plt.subplots(dof, 1, figsize=(8.0, 1.3 * dof + 0.6), sharex=True,
                             squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(t, r[:, j], lw=0.6, color="C0")
        ax.axhline(found.threshold[j], color="k", lw=0.5, ls=":")
        ax.axhline(-found.threshold[j], color="k", lw=0.5, ls=":")
        for e in found.events:
            ax.axvspan(e.start, e.end, color="C3", alpha=0.2, lw=0)
        for p in pushes:
            ax.axvline(p.start, color="C2", lw=0.8, ls="--")
            ax.axvline(p.start + p.duration, color="C2", lw=0.8, ls="--")
        ax.set_ylabel(f"j{j + 1} (N m)", fontsize=7)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("t (s, the run's own)")
    axes[0, 0].set_title(title or "external torque estimate: events shaded (left out), "
                         "thresholds dotted, true pushes dashed", fontsize=8)
    save_figure(fig, path, dpi=110)
    return path
