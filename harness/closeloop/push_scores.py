"""The push case's scores (harness.closeloop.push_case): each run's events against its
pushes, the cases summed, the issue's aims as targets and the cases as a table.

A push is found when an event overlaps it; its delay is the event's start minus the push's,
its onset error how far that start lies outside [the push's start, the first instant its joint
torque reached the detection's threshold] (onset_error); an event overlapping no push is false,
unless the plant's joint stop pushed back there (a push drove the joint onto its stop: the
world too, counted apart); a push whose joint torque never reaches the threshold on any joint
is `below threshold` (the physics hides it, not the detector).
"""

from __future__ import annotations

import numpy as np

ONSET = 0.03  # s: the onset aim
AGREE = 0.05  # the load and the friction named with the pushes within 5 % of without


def onset_error(found: float, start: float, visible: float) -> float:
    """How far (s) an event's onset found lies outside [start, visible]: from a push's start
    to the first instant its joint torque reached the detection's threshold (its end where
    it never did). Before the start it is early (negative); within, no detector could tell
    the moment better (a push's joint torque may stay under the noise for a while after it
    starts, as the arm turns it toward the force), so 0; after, it is late by the time since
    the push became visible."""
    return min(found - start, 0.0) + max(found - visible, 0.0)


def score_events(pushes, found, external: np.ndarray, t: np.ndarray,
                 stops: np.ndarray | None = None) -> dict:
    """A run's events (identification.closeloop.events.Events) against its pushes and their
    true joint torque external (n, dof) N m at times t; stops (n, dof) N m: the torque of the
    plant's joint stops (MuJoCo's constraint force): an event no push overlaps where a stop
    reached the threshold is the world too (a push drove the joint onto its stop), counted
    apart, not as false."""
    found_pushes, delays, below, latency, onset = [], [], [], [], []
    for push in pushes:
        inside = np.flatnonzero((t >= push.start) & (t <= push.start + push.duration))
        seen = np.max(np.abs(external[inside]) / found.threshold, axis=1) >= 1.0
        hit = [e for e in found.events
               if e.start <= push.start + push.duration and e.end >= push.start]
        found_pushes.append(bool(hit))
        below.append(not seen.any())
        delays.append(hit[0].start - push.start if hit else None)
        latency.append(hit[0].start - t[inside[np.argmax(seen)]] if hit and seen.any() else None)
        visible = t[inside[np.argmax(seen)]] if seen.any() else push.start + push.duration
        onset.append(None if not hit else onset_error(hit[0].start, push.start, visible))
    unpushed = [e for e in found.events if not any(
        e.start <= p.start + p.duration and e.end >= p.start for p in pushes)]

    def at_stop(e) -> bool:
        if stops is None:
            return False
        inside = (t >= e.start) & (t <= e.end)
        return bool(inside.any() and np.any(np.abs(stops[inside]) >= found.threshold))
    false = [e for e in unpushed if not at_stop(e)]
    return {"pushes": [p.to_json() for p in pushes], "found": found_pushes, "delay": delays,
            "delay_from_threshold": latency, "onset_error": onset, "below_threshold": below,
            "false_events": len(false), "events_at_stops": len(unpushed) - len(false),
            "events": [e.to_json() for e in found.events]}


def summary(cases: list[dict]) -> dict:
    """Detection rate, false events per minute, onset delays, and the load and friction named
    with the pushes against without (with and without looking for events), over cases."""
    runs = [r for c in cases for p in c["plants"].values() for r in p["runs"]]
    found = [f for r in runs for f in r["found"]]
    visible = [f for r in runs for f, b in zip(r["found"], r["below_threshold"], strict=True)
               if not b]
    delays = [d for r in runs for d in r["delay"] if d is not None]
    latency = [d for r in runs for d in r["delay_from_threshold"] if d is not None]
    onsets = [d for r in runs for d in r["onset_error"] if d is not None]
    minutes = sum(p["minutes"] for c in cases for p in c["plants"].values())
    false = sum(r["false_events"] for r in runs)
    stops = sum(r["events_at_stops"] for r in runs)
    quiet_false = sum(p["false_events_without_pushes"] for c in cases for p in c["plants"].values())

    def drift(key: str, which: str) -> list[float | None]:
        out = []
        for c in cases:
            p = c["plants"]["loaded"]
            a, b = p[which][key], p["without_pushes"][key]
            out.append(None if a is None or b is None else abs(a - b) / abs(b))
        return out

    worse = [(c["robot"], c["seed"], name, j + 1)
             for c in cases for name, p in c["plants"].items()
             for j, (a, b) in enumerate(zip(p["pushed"]["error_after"],
                                            p["pushed"]["error_before"], strict=True)) if a > b]
    return {"pushes": len(found), "found": sum(found), "above_threshold": len(visible),
            "found_above_threshold": sum(visible),
            "false_events": false, "false_per_minute": false / minutes if minutes else 0.0,
            "events_at_stops": stops,
            "false_events_without_pushes": quiet_false,
            "false_per_minute_without_pushes": quiet_false / minutes if minutes else 0.0,
            "false_per_minute_all": (false + quiet_false) / (2 * minutes) if minutes else 0.0,
            "delay_median": float(np.median(delays)) if delays else None,
            "delay_max_abs": float(np.max(np.abs(delays))) if delays else None,
            "delay_from_threshold_max_abs": float(np.max(np.abs(latency))) if latency else None,
            "onset_error_max_abs": float(np.max(np.abs(onsets))) if onsets else None,
            "onset_within": sum(abs(d) <= ONSET for d in onsets), "onsets": len(onsets),
            "mass_drift": drift("mass", "pushed"), "viscous_drift": drift("viscous_2", "pushed"),
            "mass_drift_without_events": drift("mass", "pushed_without_events"),
            "viscous_drift_without_events": drift("viscous_2", "pushed_without_events"),
            "worse_joints": worse}


def _worst(values) -> float | None:
    """The largest drift, None (missed) when any effect went unnamed."""
    return None if not values or any(v is None for v in values) else 100 * max(values)


def push_targets(s: dict, where: str) -> list:
    """The issue's aims on the summary s of cases named by where."""
    from harness.report.results import Target

    return [Target(f"pushes found, of those whose joint torque reached the threshold "
                   f"({where}; {s['found']} of all {s['pushes']})", s["found_above_threshold"],
                   s["above_threshold"], "pushes", lower_is_better=False),
            Target(f"false events per minute, pushed and calm runs ({where})",
                   s["false_per_minute_all"], 0.0, "/min"),
            Target(f"largest onset error of a found push: before its start or after its joint "
                   f"torque first reached the threshold ({where}; {s['onset_within']} of "
                   f"{s['onsets']} within {1e3 * ONSET:.0f} ms)",
                   None if s["onset_error_max_abs"] is None else 1e3 * s["onset_error_max_abs"],
                   1e3 * ONSET, "ms",
                   note=("from the push's start alone: "
                         + ("-" if s["delay_max_abs"] is None
                            else f"{1e3 * s['delay_max_abs']:.0f} ms") + "; from the first "
                         "threshold crossing alone: "
                         + ("-" if s["delay_from_threshold_max_abs"] is None
                            else f"{1e3 * s['delay_from_threshold_max_abs']:.0f} ms")
                         + " (each counts what the physics hides or an early detection)")),
            Target(f"load's mass named with the pushes against without, worst draw ({where})",
                   _worst(s["mass_drift"]), 100 * AGREE, "%"),
            Target(f"joint 2's viscous friction named with the pushes against without, worst "
                   f"draw ({where})", _worst(s["viscous_drift"]), 100 * AGREE, "%")]


def push_markdown(cases: list[dict], s: dict) -> str:
    """The cases in a table and the summary in a paragraph."""
    def fig(v, scale=100, unit="%"):
        return "not named" if v is None else f"{scale * v:.2f} {unit}"

    md = ["| arm | seed | plant | pushes found | onset from the push's start (ms) | false events "
          "| named with pushes | without pushes | pushed, no events looked for |",
          "|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for name, p in c["plants"].items():
            found = sum(sum(r["found"]) for r in p["runs"])
            total = sum(len(r["found"]) for r in p["runs"])
            hidden = sum(sum(r["below_threshold"]) for r in p["runs"])
            delays = ", ".join(f"{1e3 * d:+.0f}" for r in p["runs"] for d in r["delay"]
                               if d is not None)
            false = sum(r["false_events"] for r in p["runs"])
            md.append(f"| {c['robot']} | {c['seed']} | {name} | {found} of {total} ({hidden} "
                      f"below the threshold) | {delays} | "
                      f"{false} (calm runs: {p['false_events_without_pushes']}) | "
                      + " | ".join(", ".join(p[k]["effects"]) or "none"
                                   for k in ("pushed", "without_pushes", "pushed_without_events"))
                      + " |")
    md += ["", f"Over {len(cases)} draws: {s['found']} of {s['pushes']} pushes found "
           f"({s['found_above_threshold']} of the {s['above_threshold']} whose joint torque "
           f"reached the threshold); {s['false_events']} false events on pushed runs (and "
           f"{s['events_at_stops']} where no push acted but a push had driven a joint onto its "
           "stop, whose torque reached the threshold: the world too, not counted false) and "
           f"{s['false_events_without_pushes']} on the same runs unpushed; onset from the push's "
           f"start median {fig(s['delay_median'], 1e3, 'ms')}, largest "
           f"{fig(s['delay_max_abs'], 1e3, 'ms')}; outside [start, first threshold crossing] "
           f"largest {fig(s['onset_error_max_abs'], 1e3, 'ms')}; "
           "the load's mass with the pushes against without: "
           + ", ".join(fig(v) for v in s["mass_drift"]) + " (without looking for events: "
           + ", ".join(fig(v) for v in s["mass_drift_without_events"]) + "); joint 2's viscous "
           "friction: " + ", ".join(fig(v) for v in s["viscous_drift"]) + " (without: "
           + ", ".join(fig(v) for v in s["viscous_drift_without_events"]) + "). Joints whose "
           "held-out error after the loop is above before: "
           + (", ".join(f"{r} seed {sd} {n} joint {j}" for r, sd, n, j in s["worse_joints"])
              or "none") + "."]
    return "\n".join(md)
