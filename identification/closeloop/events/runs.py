"""The events of several runs: found on each, the runs without them, and how closeloop.json and
the command's output state them."""

from __future__ import annotations

from identification.closeloop.events.detect import Events, find_events
from identification.closeloop.events.observer import GAIN


def run_events(model, runs, times, body=None, scales=None, smoothing=None) -> list[Events]:
    """find_events on each run (q, qd, qdd, tau, ...) with its times (n,) s and how its
    velocity was estimated (smoothing: one events.smoothing.StateSmoothing or None a run;
    None: none known for any)."""
    smoothing = [None] * len(runs) if smoothing is None else smoothing
    return [find_events(model, t, *run[:4], body, scales, s)
            for run, t, s in zip(runs, times, smoothing, strict=True)]


def without_events(run: tuple, events: Events) -> tuple:
    """The run's arrays (each (n, ...)) on the samples outside its events and their margins."""
    return tuple(a[events.kept] for a in run)


def events_json(files, found: list[Events]) -> dict:
    """closeloop.json's `events` (each with the file of its run) and `event_detection`."""
    events = [{**e.to_json(), "file": str(f)} for f, ev in zip(files, found, strict=True)
              for e in ev.events]
    runs = [{"file": str(f), **{k: v for k, v in ev.to_json().items()
                                if k not in ("events", "rule", "observer_gain")}}
            for f, ev in zip(files, found, strict=True)]
    rule = found[0].to_json()["rule"] if found else ""
    return {"events": events, "event_detection": {"observer_gain": GAIN, "rule": rule,
                                                  "runs": runs}}


def events_line(files, found: list[Events]) -> str:
    """One line for all the runs (a run's file named where there are several)."""
    if len(found) == 1:
        return found[0].line()
    with_events = [(f, ev) for f, ev in zip(files, found, strict=True) if ev.events]
    if not with_events:
        return f"external torque: no event in {len(found)} runs"
    return "; ".join(f"{f}: {ev.line()}" for f, ev in with_events)
