"""Ctrl-C (SIGINT), remembered: a library that catches KeyboardInterrupt somewhere inside
its own loop cannot make the harness forget it. `install` (by the CLI) records every SIGINT
before raising KeyboardInterrupt as Python does; `check` raises it again where the harness
is about to go on (next bench section, renaming a finished result file into place)."""

from __future__ import annotations

import signal
import threading

INTERRUPTED = threading.Event()


def _handler(signum, frame) -> None:
    INTERRUPTED.set()
    raise KeyboardInterrupt


def install() -> None:
    """Record SIGINT (main thread only, as Python requires)."""
    if threading.current_thread() is threading.main_thread():
        INTERRUPTED.clear()
        signal.signal(signal.SIGINT, _handler)


def check() -> None:
    """Raise KeyboardInterrupt if a SIGINT arrived, even one a library swallowed."""
    if INTERRUPTED.is_set():
        raise KeyboardInterrupt
