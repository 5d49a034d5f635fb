"""The global search in another process (plan --realtime): searches submitted to one
worker, forked from the planning process (it inherits the torque model and configuration
and loads the compiled code from the cache), each result taken when ready."""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor

from planning.config import PlannerConfig
from planning.globalsearch.multistart import MultiStart
from planning.types import SegmentPlan

_SEARCH = None  # the worker's MultiStart


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class Background:
    """A one-worker pool running planning.globalsearch.multistart.MultiStart.search."""

    def __init__(self, model, config: PlannerConfig):
        self._pool = ProcessPoolExecutor(1, multiprocessing.get_context("fork"), _start,
                                         (model, config))
        self._future: Future | None = None

    def submit(self, segment: tuple, warm: SegmentPlan | None) -> bool:
        """Start a search unless one is running; whether it started."""
        if self._future is not None and not self._future.done():
            return False
        self._future = self._pool.submit(_search, segment, warm)
        return True

    def ready(self) -> SegmentPlan | None:
        """The finished search's plan, once (None while it runs, or if it failed)."""
        future = self._future
        if future is None or not future.done():
            return None
        self._future = None
        return None if future.exception() is not None else future.result()

    def done(self) -> bool:
        """Whether a search has finished and its plan is not taken yet."""
        return self._future is not None and self._future.done()

    def busy(self) -> bool:
        return self._future is not None and not self._future.done()

    def forget(self) -> None:
        """Drop the running search's result (a new motion begins)."""
        self._future = None

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


def _start(model, config: PlannerConfig) -> None:
    global _SEARCH
    _SEARCH = MultiStart(model, config)


def _search(segment: tuple, warm: SegmentPlan | None) -> SegmentPlan:
    return _SEARCH.search(*segment, warm)[0]
