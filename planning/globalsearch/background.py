"""The global search in another process (plan --realtime): searches submitted to one
worker, forked from the planning process when the Background is made (it inherits the torque
model and configuration, and at its first search builds its planner, loading the compiled code
from the cache), each plan it finds better than those before it sent back as it is found and
taken when ready."""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

from planning.config import PlannerConfig
from planning.globalsearch.multistart import MultiStart, bank_search
from planning.types import Segment, SegmentPlan

_PLANNER = None  # the worker's torque model and configuration
_SEARCH = None  # the worker's MultiStart, built from them
_FOUND = None  # the worker's end of the queue of (search number, plan)
_EVERY = False  # the worker sends every plan found, not only the better ones


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class Background:
    """A one-worker pool running planning.globalsearch.multistart.MultiStart.search, its
    better plans sent back on a queue as they are found. A search that raised, or a worker
    that died, is counted in `failures` and the loop goes on without it."""

    def __init__(self, model, config: PlannerConfig, every: bool = False):
        """every: the worker sends every plan it finds (a bank's), not only those better
        than the ones before."""
        context = multiprocessing.get_context("fork")
        # a Queue, not a SimpleQueue: its puts never block the worker on a full pipe
        self._found = context.Queue()
        self._pool = ProcessPoolExecutor(1, context, _start, (model, config, self._found,
                                                              every))
        self._taken: list[SegmentPlan] = []  # every plan received, not taken yet
        self._future: Future | None = None
        self._future_number = 0  # the number the running search was submitted with
        self._number = 0  # of the current search: plans of an older one are dropped
        self._latest: SegmentPlan | None = None  # the best found so far, not taken yet
        self.received = 0  # plans of the current search received
        self.failures = 0  # searches that raised, or a worker that died
        self._broken = False
        try:  # the worker forked now: forked at the first search, the pages the planning
            self._pool.submit(int).result()  # process then wrote were copied in a re-plan
        except BrokenProcessPool:
            self._broken, self.failures = True, 1

    def prepare(self, goal) -> None:
        """Have the worker build its search and the goal's NLPs now, before the motion (at
        its first search they took about a second of a Lynxmotion's 2-s motion: its plans came
        after the obstacle had passed); a search submitted meanwhile is refused (busy)."""
        if self._broken or self.busy():
            return
        try:
            self._future, self._future_number = self._pool.submit(_prepare, goal), self._number
        except BrokenProcessPool:
            self._broken, self._future = True, None
            self.failures += 1

    def wait(self) -> None:
        """Wait for the worker's preparation or search under way (a failure counted)."""
        if self._future is not None:
            with contextlib.suppress(Exception):  # counted by busy
                self._future.result()
            self.busy()

    def submit(self, segment: Segment, warm: SegmentPlan | None) -> bool:
        """Start a search unless one is running or a plan is still on offer; whether it
        started."""
        if self._broken or self.busy() or self.done():
            return False
        self._number += 1
        self._future_number, self.received = self._number, 0
        try:
            self._future = self._pool.submit(_search, self._number, segment, warm)
        except BrokenProcessPool:
            self._broken, self._future = True, None
            self.failures += 1
            return False
        return True

    def ready(self) -> SegmentPlan | None:
        """The best plan the search has found so far, once (None if none is new)."""
        self._drain()
        plan, self._latest = self._latest, None
        return plan

    def ready_all(self) -> list[SegmentPlan]:
        """Every plan received and not taken yet, in the order found."""
        self._drain()
        plans, self._taken = self._taken, []
        return plans

    def done(self) -> bool:
        """Whether the search has found a plan not taken yet."""
        self._drain()
        return self._latest is not None

    def busy(self) -> bool:
        """Whether a search runs, or its plans are still on their way (a put reaches the
        pipe after the search has returned)."""
        future = self._future
        if future is None or not future.done():
            return future is not None
        if future.exception() is not None:  # counted once
            self.failures += 1
            self._broken = isinstance(future.exception(), BrokenProcessPool)
        elif self._future_number == self._number:
            self._drain()
            if self.received < future.result():
                return True
        self._future = None
        return False

    def forget(self) -> None:
        """Drop the running search's plans (a new motion begins)."""
        self._number += 1
        self._latest = None

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)

    def _drain(self) -> None:
        while True:
            try:
                number, plan, better = self._found.get_nowait()
            except queue.Empty:
                return
            if number == self._number:
                if better:
                    self._latest = plan
                self._taken.append(plan)
                self.received += 1


def _start(model, config: PlannerConfig, found, every: bool = False) -> None:
    global _PLANNER, _FOUND, _EVERY
    _PLANNER, _FOUND, _EVERY = (model, config), found, every
    found.cancel_join_thread()  # the worker exits whatever the planning process left unread


def _built() -> MultiStart:
    """The worker's search, built at its first use (a preparation or a search): the planning
    process has compiled its code by then, and the worker loads it from the cache."""
    global _SEARCH
    if _SEARCH is None:
        _SEARCH = MultiStart(*_PLANNER)
    return _SEARCH


def _prepare(goal) -> int:
    """The search and the goal's NLPs built (no plan sent)."""
    _built().prepare(goal)
    return 0


def _search(number: int, segment: Segment, warm: SegmentPlan | None) -> int:
    """The search; how many plans it sent."""
    search = _built()
    sent = [0]

    def found(plan: SegmentPlan, better: bool) -> None:
        if better or _EVERY:
            _FOUND.put((number, plan, better))
            sent[0] += 1

    if _EVERY:  # a bank's: it holds the plan followed, and wants the classes soon
        search.search(segment, None, found=found, **bank_search(search.config))
    else:
        search.search(segment, warm, found=found)
    return sent[0]
