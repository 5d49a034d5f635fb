"""The global search in another process (plan --realtime): searches submitted to one
worker, forked from the planning process (it inherits the torque model and configuration
and loads the compiled code from the cache), each plan it finds better than those before
it sent back as it is found and taken when ready."""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor

from planning.config import PlannerConfig
from planning.globalsearch.multistart import MultiStart
from planning.types import SegmentPlan

_SEARCH = None  # the worker's MultiStart
_FOUND = None  # the worker's end of the queue of (search number, plan)


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class Background:
    """A one-worker pool running planning.globalsearch.multistart.MultiStart.search, its
    better plans sent back on a queue as they are found."""

    def __init__(self, model, config: PlannerConfig):
        context = multiprocessing.get_context("fork")
        self._found = context.SimpleQueue()
        self._pool = ProcessPoolExecutor(1, context, _start, (model, config, self._found))
        self._future: Future | None = None
        self._number = 0  # of the current search: plans of an older one are dropped
        self._latest: SegmentPlan | None = None  # the best found so far, not taken yet

    def submit(self, segment: tuple, warm: SegmentPlan | None) -> bool:
        """Start a search unless one is running; whether it started."""
        if self.busy():
            return False
        self._drain()  # the last search's best, sent before it ended, stays on offer
        self._number += 1
        self._future = self._pool.submit(_search, self._number, segment, warm)
        return True

    def ready(self) -> SegmentPlan | None:
        """The best plan the search has found so far, once (None if none is new)."""
        self._drain()
        plan, self._latest = self._latest, None
        return plan

    def done(self) -> bool:
        """Whether the search has found a plan not taken yet."""
        self._drain()
        return self._latest is not None

    def busy(self) -> bool:
        return self._future is not None and not self._future.done()

    def forget(self) -> None:
        """Drop the running search's plans (a new motion begins)."""
        self._number += 1
        self._future, self._latest = None, None

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)

    def _drain(self) -> None:
        while not self._found.empty():
            number, plan = self._found.get()
            if number == self._number:
                self._latest = plan


def _start(model, config: PlannerConfig, found) -> None:
    global _SEARCH, _FOUND
    _SEARCH, _FOUND = MultiStart(model, config), found


def _search(number: int, segment: tuple, warm: SegmentPlan | None) -> None:
    def found(plan: SegmentPlan, better: bool) -> None:
        if better:
            _FOUND.put((number, plan))

    _SEARCH.search(*segment, warm, found=found)
