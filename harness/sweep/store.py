"""DIR/results.csv: one row per finished cell, appended as the cells finish.

Each row is written with one write() of the complete line and fsync'ed before the next cell is
recorded, so a sweep killed at any moment leaves every finished row on disk and at most a torn
last line (no final newline). Opening the file again drops a torn last line (its cell runs
again, with a warning); any other unreadable line is damage the sweep did not make: an error
naming the line, the file left as it is. It widens the per-joint columns if a robot with
more joints joins, and rewrites the file atomically when it had to change anything.

Columns: robot, noise, seed, method, samples, dof, error_j1..error_jK (relative RMS error per
joint; empty past the robot's dof), median (over the joints), seconds (the method's fit),
cell_seconds (the whole cell), cpu_seconds (the whole cell's CPU time). Floats are written with
repr, so a value read back is the value computed.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

from harness.errors import UserError
from harness.io import atomic_write
from harness.sweep.cell import CellResult
from harness.sweep.grid import Cell

KEY = ("robot", "noise", "seed", "method", "samples")
TIMES = ("seconds", "cell_seconds", "cpu_seconds")


def header(joints: int) -> list[str]:
    return [*KEY, "dof", *(f"error_j{j + 1}" for j in range(joints)), "median", *TIMES]


def _line(result: CellResult, joints: int) -> str:
    c, e = result.cell, [repr(x) for x in result.errors]
    fields = [c.robot, repr(c.noise), str(c.seed), c.method, str(c.samples), str(len(e)),
              *e, *[""] * (joints - len(e)), repr(result.median),
              *(repr(getattr(result, t)) for t in TIMES)]
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(fields)
    return buffer.getvalue()


def _parse(row: dict) -> CellResult:
    """A CellResult from a csv row (ValueError/TypeError/KeyError if it is not one)."""
    cell = Cell(row["robot"], float(row["noise"]), int(row["seed"]), row["method"], int(row["samples"]))
    errors = tuple(float(row[f"error_j{j + 1}"]) for j in range(int(row["dof"])))
    result = CellResult(cell, errors, *(float(row[t]) for t in TIMES))
    if not errors or float(row["median"]) != result.median:
        raise ValueError("inconsistent row")
    return result


def read(path: Path) -> tuple[dict[tuple, CellResult], int, int]:
    """The finished cells of a results file (first row of a cell wins), the number of per-joint
    columns of its header, and the number of lines dropped (a torn last line, 0 or 1);
    UserError for an unreadable complete line."""
    text = path.read_text() if path.exists() else ""
    lines = text.split("\n")
    dropped = 1 if lines[-1] else 0  # a last line without its newline is torn
    lines = lines[:-1]
    if not lines:
        return {}, 0, dropped
    head = next(csv.reader([lines[0]]))
    if tuple(head[:len(KEY)]) != KEY or head[-len(TIMES):] != list(TIMES):
        raise UserError(f"{path} exists and is not a sweep's results file (header {head[:6]})")
    rows: dict[tuple, CellResult] = {}
    for number, fields in enumerate(csv.reader(lines[1:]), start=2):
        try:
            if len(fields) != len(head):
                raise ValueError(f"{len(fields)} fields, the header has {len(head)}")
            result = _parse(dict(zip(head, fields, strict=True)))
        except (ValueError, TypeError, KeyError) as exc:
            raise UserError(f"{path} line {number} is unreadable ({exc}); only a torn last line "
                            "is dropped: repair or remove the file") from None
        rows.setdefault(result.cell.key, result)
    return rows, len(head) - len(KEY) - 2 - len(TIMES), dropped


class ResultsStore:
    """The results file of a sweep folder, opened for appending finished cells."""

    def __init__(self, path: str | Path, joints: int):
        self.path = Path(path)
        self.rows, width, self.dropped = read(self.path)
        self.joints = max(joints, width)
        if self.dropped or width != self.joints or not self.path.exists():
            self._rewrite()

    def _rewrite(self) -> None:
        def write(tmp: str) -> None:
            with open(tmp, "w") as f:
                f.write(",".join(header(self.joints)) + "\n")
                f.writelines(_line(r, self.joints) for r in self.rows.values())
                f.flush()
                os.fsync(f.fileno())

        atomic_write(self.path, write)

    def __contains__(self, cell: Cell) -> bool:
        return cell.key in self.rows

    def append(self, result: CellResult) -> None:
        """Add one finished cell: the complete line in one write, then fsync."""
        if len(result.errors) > self.joints:
            raise ValueError(f"{result.cell.robot} has {len(result.errors)} joints, the file {self.joints}")
        data = _line(result, self.joints).encode()
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        try:
            written = os.write(fd, data)
            while written < len(data):  # a regular file takes it all at once; be sure anyway
                written += os.write(fd, data[written:])
            os.fsync(fd)
        finally:
            os.close(fd)
        self.rows[result.cell.key] = result
