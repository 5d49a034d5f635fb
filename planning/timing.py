"""Time a plan takes: wall and CPU clocks of the planning thread, and Python's garbage
collector held off while a plan runs."""

from __future__ import annotations

import functools
import gc
import time


class Stopwatch:
    """Wall and CPU time (ms, this thread) since it was made."""

    def __init__(self):
        self.wall, self.cpu = time.perf_counter(), time.thread_time()

    def cpu_ms(self) -> float:
        return 1e3 * (time.thread_time() - self.cpu)

    def read(self) -> tuple[float, float]:
        return 1e3 * (time.perf_counter() - self.wall), self.cpu_ms()


def collection_deferred(plan):
    """`plan` with Python's cyclic garbage collector held off while it runs (and set back as
    it was after): a collection inside a plan frees whatever cycles the process left, tens
    of ms (docs/realtime.md, 'planning.timing'). It runs at an allocation between plans instead."""

    @functools.wraps(plan)
    def deferred(*args, **kwargs):
        enabled = gc.isenabled()
        gc.disable()
        try:
            return plan(*args, **kwargs)
        finally:
            if enabled:
                gc.enable()

    return deferred
