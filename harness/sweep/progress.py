"""The sweep's progress line on the terminal: cells done / total, elapsed, time left."""

from __future__ import annotations

import sys
import time
from typing import TextIO


def clock(seconds: float) -> str:
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    return f"{h}:{rest // 60:02d}:{rest % 60:02d}" if h else f"{rest // 60}:{rest % 60:02d}"


class Progress:
    """Cells done of total; time left = the remaining cells at this run's rate so far.

    On a terminal one line is redrawn in place; otherwise (a log) a line is printed at most
    every `every` seconds and at the end."""

    def __init__(self, total: int, done: int, stream: TextIO | None = None, every: float = 10.0):
        self.total, self.done, self.start_done = total, done, done
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.every, self.start, self.last = every, time.perf_counter(), -float("inf")

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        new = self.done - self.start_done
        left = "?" if not new else clock(elapsed / new * (self.total - self.done))
        reused = f", {self.start_done} reused" if self.start_done else ""
        return (f"sweep: {self.done}/{self.total} cells{reused} | {clock(elapsed)} elapsed | "
                f"~{left} left")

    def update(self, cells: int = 1) -> None:
        self.done += cells
        now = time.perf_counter()
        final = self.done >= self.total
        if self.tty:
            self.stream.write("\r" + self.line() + ("\n" if final else ""))
        elif final or now - self.last >= self.every:
            self.stream.write(self.line() + "\n")
        else:
            return
        self.last = now
        self.stream.flush()
