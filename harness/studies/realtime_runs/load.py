"""A load the study makes itself: busy-loop child processes, one per core, for as long as a
block runs."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator

# a pure-Python busy loop that ends itself once its parent (the process id it is given) is
# gone, re-parented, so a study killed outright leaves no spinning process behind
SPIN = ("import os, sys\nwhile os.getppid() == int(sys.argv[1]):\n"
        "    for _ in range(200_000):\n        pass\n")


@contextlib.contextmanager
def busy(count: int) -> Iterator[list[int]]:
    """count busy-loop processes running while the block runs (their process ids), killed
    and reaped when it is left, whatever it raised."""
    spinning: list[subprocess.Popen] = []
    try:
        for _ in range(count):
            spinning.append(subprocess.Popen([sys.executable, "-c", SPIN, str(os.getpid())],
                                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                             stderr=subprocess.DEVNULL))
        yield [p.pid for p in spinning]
    finally:
        for process in spinning:
            process.kill()
        for process in spinning:
            process.wait()


def running(pid: int) -> bool:
    """Whether a process of this id exists (one of busy's, while its block runs)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True
