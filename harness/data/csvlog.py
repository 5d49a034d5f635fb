"""A measured log in the documented CSV form, read and validated.

Header `t, q1..qn, [qd1..qn], [qdd1..qn], tau1..taun` (any column order; s, rad,
rad/s, rad/s^2, N m), or `i1..in` (motor currents, A) for the effort columns, one row per
sample, comma-separated; a `.gz` file is read
compressed. Every problem is a UserError naming it: an unknown or missing column, a
group of another size than the robot's joints, a value that is not a number, NaN or
inf, time stamps that do not strictly increase or leave a gap, too few samples.
"""

from __future__ import annotations

import gzip
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.data.dataset import MAGNITUDE
from harness.errors import UserError

GROUPS = ("q", "qd", "qdd", "tau", "i")  # joint columns <group><joint>, joints 1..n
REQUIRED = ("q", "tau")  # the effort: tau1..taun, or i1..in (currents)
MIN_SAMPLES = 200
MAX_GAP = 25.0  # a step longer than this many median steps is a gap in the log
_COLUMN = re.compile(r"^(q|qd|qdd|tau|i)([1-9][0-9]*)$")


@dataclass(frozen=True)
class Log:
    """The log's columns: t (n,) s, and each present group (n, dof), in the file's units."""

    path: Path
    t: np.ndarray
    groups: dict[str, np.ndarray]

    @property
    def dof(self) -> int:
        return self.groups["q"].shape[1]


def _open(path: Path):
    """Text lines of the file (gzip-compressed if it ends in .gz; a UTF-8 byte-order mark
    dropped)."""
    if path.suffix == ".gz":
        return gzip.open(path, "rt", encoding="utf-8-sig")
    return open(path, encoding="utf-8-sig")


def _header(path: Path) -> list[str]:
    try:
        with _open(path) as f:
            line = f.readline()
    except (OSError, UnicodeDecodeError, EOFError) as exc:
        raise UserError(f"{path}: cannot read ({exc})") from None
    names = [c.strip().strip('"') for c in line.strip().split(",")]
    if not line.strip() or names == [""]:
        raise UserError(f"{path}: empty file, expected a header 't, q1..qn, tau1..taun'")
    return names


def _layout(path: Path, names: list[str], dof: int) -> dict[str, list[int]]:
    """Column index of t and of each group's joints 1..dof."""
    seen: dict[str, int] = {}
    groups: dict[str, dict[int, int]] = {g: {} for g in GROUPS}
    for i, name in enumerate(names):
        if name in seen:
            raise UserError(f"{path}: column '{name}' appears twice")
        seen[name] = i
        match = _COLUMN.match(name)
        if name == "t":
            continue
        if not match:
            raise UserError(f"{path}: unknown column '{name}' (expected t, q1..qn, qd1..qn, "
                            "qdd1..qn, tau1..taun or i1..in)")
        groups[match.group(1)][int(match.group(2))] = i
    if "t" not in seen:
        raise UserError(f"{path}: no time column 't'")
    if groups["tau"] and groups["i"]:
        raise UserError(f"{path}: both tau and i (current) columns: give one effort group")
    layout = {"t": [seen["t"]]}
    for g in GROUPS:
        joints = groups[g]
        if not joints:
            if g in REQUIRED and not (g == "tau" and groups["i"]):
                raise UserError(f"{path}: missing columns {g}1..{g}{dof}")
            continue
        if max(joints) > dof:
            raise UserError(f"{path}: column {g}{max(joints)} but the robot has {dof} joints "
                            "(dof mismatch)")
        missing = [f"{g}{j}" for j in range(1, dof + 1) if j not in joints]
        if missing:
            raise UserError(f"{path}: missing column{'s' * (len(missing) > 1)} "
                            f"{', '.join(missing)} (the robot has {dof} joints)")
        layout[g] = [joints[j] for j in range(1, dof + 1)]
    return layout


def _bad_line(path: Path, names: list[str]) -> str:
    """The first line that is not len(names) numbers, described (slow: on error only)."""
    with _open(path) as f:
        next(f)
        for number, line in enumerate(f, start=2):
            if not line.strip():
                continue
            cells = [c.strip() for c in line.rstrip("\r\n").split(",")]
            if len(cells) != len(names):
                return f"line {number} has {len(cells)} values, the header names {len(names)}"
            for name, cell in zip(names, cells, strict=True):
                try:
                    float(cell)
                except ValueError:
                    return f"line {number}, column '{name}': '{cell}' is not a number"
    return "not a table of numbers"


def _values(path: Path, names: list[str]) -> np.ndarray:
    try:
        with warnings.catch_warnings():  # a header-only file is reported as too short below
            warnings.filterwarnings("ignore", message=".*input contained no data")
            values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float)
    except ValueError:
        raise UserError(f"{path}: {_bad_line(path, names)}") from None
    except (OSError, EOFError) as exc:
        raise UserError(f"{path}: cannot read ({exc})") from None
    if values.size and values.shape[1] != len(names):
        raise UserError(f"{path}: rows have {values.shape[1]} values, the header names "
                        f"{len(names)}")
    return values


def _line(row: int) -> str:
    """Where sample row (0-based) is in a CSV log: its line (the header is line 1)."""
    return f"line {row + 2}"


def _check_time(path: Path, t: np.ndarray, where=_line) -> None:
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if len(bad):
        i = int(bad[0])
        raise UserError(f"{path}: time stamps must strictly increase: {where(i + 1)} has t = "
                        f"{t[i + 1]:.9g} after t = {t[i]:.9g}")
    median = float(np.median(steps))
    gap = np.flatnonzero(steps > MAX_GAP * median)
    if len(gap):
        i = int(gap[0])
        raise UserError(f"{path}: a gap of {steps[i]:.4g} s after t = {t[i]:.9g} "
                        f"({steps[i] / median:.0f} median steps): split the log there")


def validated(path: Path, names: list[str], values: np.ndarray, dof: int, where=_line) -> Log:
    """The log of columns names (t, q1..qn, ...) holding values (samples, columns) of a robot
    with dof joints, checked as a CSV log is (where(row): how a sample is located in the
    source, for the messages): enough samples, finite, within the dataset contract's bounds,
    time strictly increasing without gaps."""
    layout = _layout(path, names, dof)
    if len(values) < MIN_SAMPLES:
        raise UserError(f"{path}: {len(values)} samples, at least {MIN_SAMPLES} are needed")
    finite = np.isfinite(values)
    if not finite.all():
        row, col = (int(x[0]) for x in np.nonzero(~finite))
        raise UserError(f"{path}: column '{names[col]}' is NaN or infinite at {where(row)}")
    for group, cols in layout.items():  # the dataset contract's bounds (harness.data.dataset)
        bound, unit = MAGNITUDE.get(group, (1e6, "A"))
        worst = np.abs(values[:, cols]).max()
        if worst > bound:
            row, col = np.unravel_index(np.argmax(np.abs(values[:, cols])), values[:, cols].shape)
            raise UserError(f"{path}: column '{names[cols[col]]}' reaches {worst:.3g} {unit} at "
                            f"{where(int(row))}, beyond any arm's ({bound:g} {unit})")
    t = values[:, layout["t"][0]]
    _check_time(path, t, where)
    return Log(path, t, {g: values[:, cols] for g, cols in layout.items() if g != "t"})


def read_log(path: str | Path, dof: int) -> Log:
    """The validated log of a robot with dof joints."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"log file not found: {path}")
    names = _header(path)
    _layout(path, names, dof)  # the header's problems before the values'
    return validated(path, names, _values(path, names), dof)
