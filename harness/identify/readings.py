"""The identified parameters' summary as `identify` prints it: each reading with its 95 %
interval (identification.parameter_intervals), `value +- interval (95 %)`."""

from __future__ import annotations

import math

HEADER = "identified parameters, value +- interval (95 %); the interval: {rule}"


def _pm(value: float, half: float, unit: str = "") -> str:
    unit = f" {unit}" if unit else ""
    if half is None or not math.isfinite(half):
        return f"{value:.4g}{unit} (no interval)"
    return f"{value:.4g} +- {half:.2g}{unit}"


def describe(intervals: dict) -> list[str]:
    """stdout lines: every printed reading with its interval; a consistent fit's bodies with
    the readings the data determine (the rest: held by the prior and the constraints)."""
    if not intervals:
        return []
    lines = [HEADER.format(rule=intervals["rule"])]
    for name, e in intervals.get("base_parameters", {}).items():
        lines.append(f"  {name} = {_pm(e['value'], e['interval_95'], e['unit'])}")
    for e in intervals.get("friction_laws", []):
        lines.append(f"  {e['term']} = {_pm(e['value'], e['interval_95'], 'N m')}")
    for j, joint in enumerate(intervals.get("joints", [])):
        lines.append(f"  tau{j + 1}: " + ", ".join(f"{name} {_pm(e['value'], e['interval_95'])}"
                                                   for name, e in joint.items()))
    for body in intervals.get("bodies", []):
        lines.append(f"  body {body['joint']}: " + _body(body))
    if "bodies" in intervals:  # a joint's armature, viscous, Coulomb: among the base atoms
        lines.append("  (a body's reading not shown is not determined by the data alone: held "
                     "by the prior and the constraints; MODEL.json parameter_intervals)")
    return lines


def _body(body: dict) -> str:
    """One body's identifiable readings: mass, and the centre of mass's and the inertia's
    components the data determine."""
    parts = []
    mass = body["mass"]
    if mass["identifiable"]:
        parts.append(f"mass {_pm(mass['value'], mass['interval_95'], 'kg')}")
    for key, label, names in (("com", "com", "xyz"),
                              ("inertia_at_com", "I", ["xx", "xy", "xz", "yx", "yy", "yz",
                                                       "zx", "zy", "zz"])):
        e = body[key]
        values, halves, known = (_flat(e[k]) for k in ("value", "interval_95", "identifiable"))
        for k, (v, h, ok) in enumerate(zip(values, halves, known, strict=True)):
            if ok and not (key == "inertia_at_com" and names[k][0] > names[k][1]):
                parts.append(f"{label}_{names[k]} {_pm(v, h, e['unit'])}")
    return ", ".join(parts) or "no reading determined by the data alone"


def _flat(x) -> list:
    return [y for row in x for y in row] if x and isinstance(x[0], list) else list(x)
