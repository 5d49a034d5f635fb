"""A measured log into the dataset contract: resampled, derivatives estimated, described.

1. The log is read and validated (harness.data.csvlog; a rosbag2 recording of
   sensor_msgs/JointState: harness.data.bag).
2. Resampling: every column is linearly interpolated onto a uniform grid at the median
   time step of the log (irregular stamps, dropped samples), from its first to its last
   stamp. The torque is interpolated, never smoothed: it is the regression target.
3. Missing derivatives: from the highest logged one (qd if logged, else q) by
   Savitzky-Golay differentiation of order POLYORDER on the uniform grid, with the window
   chosen from the data (harness.data.derivatives.choose_window). Logged columns are kept
   as logged (resampled).
4. Optionally decimated to `rate` Hz (every k-th grid sample, after differentiation).
5. Motor currents: with current gains (N m/A per joint) the effort columns (`tau1..taun`, or
   `i1..in`) are currents and the torque is gain x current; meta records the gains. With the
   gains unknown (gains_unknown), the currents are kept as `current` (A) and the dataset has no
   `tau`: nothing can take it for torque; `identify --loaded L.npz --load-mass KG` identifies
   the gains (harness.identify.drive_gains).

`meta` records the source, the resampling, the derivative method with its window and the
time-stamp statistics. There is no `tau_clean`: scores are against the measured torque.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.data.bag import is_bag, read_bag
from harness.data.csvlog import Log, read_log
from harness.data.derivatives import choose_window, savgol_window_derivatives
from harness.errors import UserError
from harness.robots.arm import Arm

POLYORDER = 4


@dataclass(frozen=True)
class Ingested:
    """The dataset payload of a log: arrays (t, q, qd, qdd, tau) and meta."""

    arrays: dict[str, np.ndarray]
    meta: dict

    def npz(self) -> dict[str, np.ndarray]:
        """The npz contract's keys (no tau_clean)."""
        return {**self.arrays, "meta": np.array(json.dumps(self.meta))}


def resample(t: np.ndarray, x: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Columns of x (n, k) sampled at t, linearly interpolated at grid."""
    return np.stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])], axis=1)


def uniform_grid(t: np.ndarray) -> tuple[np.ndarray, float]:
    """The grid from t[0] to t[-1] at the median step, and its rate (Hz)."""
    step = float(np.median(np.diff(t)))
    n = int(np.floor((t[-1] - t[0]) / step + 1e-9)) + 1
    return t[0] + step * np.arange(n), 1.0 / step


def estimate(log: Log, grid: np.ndarray, rate: float,
             window: int | None = None) -> tuple[dict[str, np.ndarray], dict]:
    """q, qd, qdd, tau on the grid (missing derivatives estimated) and their description;
    window (odd, samples): given instead of chosen from the data."""
    out = {g: resample(log.t, x, grid) for g, x in log.groups.items()}
    missing = [g for g in ("qd", "qdd") if g not in out]
    if not missing:
        return out, {"method": "logged", "estimated": []}
    source = "qd" if "qd" in out else "q"
    orders = tuple(("q", "qd", "qdd").index(g) - ("q", "qd").index(source) for g in missing)
    if window is None:
        described = choose_window(out[source], rate, POLYORDER, orders).to_json()
    else:
        if window < POLYORDER + 1 or window % 2 == 0 or window > len(grid):
            raise UserError(f"--window must be odd, in [{POLYORDER + 1}, {len(grid)}] samples, "
                            f"got {window}")
        described = {"method": "savitzky-golay", "window_samples": window,
                     "window_s": window / rate, "polyorder": POLYORDER, "rule": "given"}
    estimates = savgol_window_derivatives(out[source], rate, described["window_samples"],
                                          POLYORDER, orders)
    out.update(dict(zip(missing, estimates, strict=True)))
    return out, {**described, "source": source, "estimated": missing}


CURRENT_KEY = "current"  # a dataset of motor currents whose gains are unknown: A, no tau


def _currents(log: Log, gains, unknown: bool = False) -> tuple[Log, dict]:
    """The log with its effort as torque (gain x current, N m), or kept as current (A) when
    the gains are unknown, and the effort's description."""
    effort = "i" if "i" in log.groups else "tau"
    columns = f"columns {effort}1..{effort}{log.dof}"
    if unknown:
        if gains is not None:
            raise UserError("give the drive gains (--current-gains) or say they are unknown "
                            "(--gains-unknown), not both")
        groups = {k: v for k, v in log.groups.items() if k != effort}
        groups[CURRENT_KEY] = log.groups[effort]
        return Log(log.path, log.t, groups), {
            "logged": f"motor current (A), {columns}", "current_gains": None,
            "current": "motor current (A), drive gains unknown: no torque in this dataset; "
                       "identify --loaded L.npz --load-mass KG identifies the gains"}
    if gains is None:
        if effort == "i":
            raise UserError(f"{log.path}: columns i1..in are motor currents: give their drive "
                            "gains, --current-gains K1,...,Kn (N m/A per joint), or identify "
                            "them (--gains-unknown, then identify --loaded --load-mass)")
        return log, {"logged": "torque (N m)"}
    gains = np.asarray(gains, float)
    if gains.shape != (log.dof,) or not np.all(np.isfinite(gains)) or np.any(gains == 0):
        raise UserError(f"--current-gains needs {log.dof} finite non-zero gains (N m/A), got "
                        f"{len(gains)}")
    groups = {k: v for k, v in log.groups.items() if k != effort}
    groups["tau"] = log.groups[effort] * gains
    return Log(log.path, log.t, groups), {
        "logged": f"motor current (A), {columns}",
        "current_gains": gains.tolist(), "torque": "gain x current (N m/A x A)"}


def ingest(path: str | Path, arm: Arm, rate: float | None = None,
           window: int | None = None, current_gains=None, gains_unknown: bool = False,
           topic: str | None = None) -> Ingested:
    """The log at path of arm (its joints), as a dataset at rate Hz (default: the
    resampling rate, the log's median step): a CSV log, or a rosbag2 recording of
    sensor_msgs/JointState (harness.data.bag; its topic `topic`, default the only one);
    window: the Savitzky-Golay window in samples of the resampled grid (default: chosen from
    the data); current_gains (N m/A per joint): the effort columns are motor currents, the
    torque gain x current; gains_unknown: they are currents kept as `current` (A), the
    dataset has no torque."""
    dof = arm.dof
    read = {"format": "csv"}
    if is_bag(path):
        raw, read = read_bag(path, list(arm.pinocchio.names[1:]), topic)
    else:
        raw = read_log(path, dof)
    log, effort = _currents(raw, current_gains, gains_unknown)
    grid, grid_rate = uniform_grid(log.t)
    states, derivatives = estimate(log, grid, grid_rate, window)
    every = 1
    if rate is not None:
        if not 0 < rate <= grid_rate * (1 + 1e-9):
            raise UserError(f"--rate must be in (0, {grid_rate:.6g}] Hz (the log's median step), "
                            f"got {rate:g}")
        every = max(1, int(round(grid_rate / rate)))
    keep = slice(None, None, every)
    efforts = ("tau",) if "tau" in states else (CURRENT_KEY,)
    arrays = {"t": grid[keep], **{k: states[k][keep] for k in ("q", "qd", "qdd", *efforts)}}
    steps = np.diff(log.t)
    meta = {"mode": "measured log", "source": Path(path).name, "read": read,
            "plant": arm.reference,
            "robot": arm.reference, "robot_hash": arm.record["hash"],
            **{k: arm.record[k] for k in ("chain", "held", "hold") if k in arm.record},
            "dof": dof, "samples": int(len(arrays["q"])), "logged": sorted(log.groups),
            "raw_samples": int(len(log.t)), "duration_s": float(log.t[-1] - log.t[0]),
            "raw_step_s": {"min": float(steps.min()), "median": float(np.median(steps)),
                           "max": float(steps.max())},
            "resampling": {"method": "linear interpolation onto a uniform grid at the median "
                           "step", "rate_hz": grid_rate, "decimation": every,
                           "rate_out_hz": grid_rate / every},
            "derivatives": derivatives, "effort": effort, "noise": None, "seed": None}
    return Ingested(arrays, meta)
