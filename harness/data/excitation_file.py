"""An excitation as a file: the CSV `t,q1..qn,qd1..qdn,qdd1..qddn` that `excite` writes and
`generate --excitation` reads (s, rad, rad/s, rad/s^2)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.errors import UserError
from harness.io import write_text


@dataclass(frozen=True)
class Trajectory:
    """Sampled joint states (n, dof) at times t (n,), s and rad."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd (len(t), dof) at times t, linearly interpolated between samples."""
        return tuple(np.column_stack([np.interp(t, self.t, x[:, j]) for j in range(x.shape[1])])
                     for x in (self.q, self.qd, self.qdd))


def header(dof: int) -> list[str]:
    """The CSV columns: t, q1..qn, qd1..qdn, qdd1..qddn."""
    return ["t"] + [f"{k}{j}" for k in ("q", "qd", "qdd") for j in range(1, dof + 1)]


def write_trajectory(path: str | Path, trajectory: Trajectory) -> None:
    """The trajectory as an excitation CSV, written atomically (12 significant digits)."""
    rows = np.hstack([trajectory.t[:, None], trajectory.q, trajectory.qd, trajectory.qdd])
    lines = [",".join(header(trajectory.q.shape[1]))]
    lines += [",".join(f"{v:.12g}" for v in row) for row in rows]
    write_text(path, "\n".join(lines) + "\n")


def read_trajectory(path: str | Path, dof: int) -> Trajectory:
    """The trajectory in an excitation CSV for a dof-joint robot; UserError if the file is
    missing, its header is not header(dof), a value is not a number or t is not increasing."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"excitation file not found: {path}")
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"cannot read excitation file {path}: {exc}") from None
    if not rows or [c.strip() for c in rows[0]] != header(dof):
        got = ",".join(rows[0][:4]) + ",..." if rows else "an empty file"
        raise UserError(f"{path}: expected the header t,q1..q{dof},qd1..qd{dof},qdd1..qdd{dof} "
                        f"for a {dof}-joint robot, got {got}")
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=float)
    except ValueError:
        raise UserError(f"{path}: a value is not a number") from None
    if data.ndim != 2 or len(data) < 2 or data.shape[1] != 1 + 3 * dof:
        raise UserError(f"{path}: needs at least 2 rows of {1 + 3 * dof} values")
    if not np.all(np.isfinite(data)) or np.any(np.diff(data[:, 0]) <= 0):
        raise UserError(f"{path}: values must be finite and t increasing")
    return Trajectory(data[:, 0], data[:, 1:1 + dof], data[:, 1 + dof:1 + 2 * dof],
                      data[:, 1 + 2 * dof:])
