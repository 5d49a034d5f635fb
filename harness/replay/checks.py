"""What a replay must show, and how two replays compare.

Checked per plan: tracking RMS <= 1 mrad, replayed energy within 2 % of the planned energy and
of the plan's own dense energy (the planner's figure may be a coarse quadrature, the paper's
N = 10: the second separates replay fidelity from that quadrature error), minimum
centre-to-segment clearance >= lambda - 5 mm when the plan avoids an obstacle (or, for a plan
that could not keep lambda and says so, >= its own smallest clearance - 5 mm).
"""

from __future__ import annotations

from harness.replay.simulate import ReplayResult

TRACKING_LIMIT = 1e-3  # rad
ENERGY_TOLERANCE = 0.02  # relative
CLEARANCE_MARGIN = 0.005  # m


def role(name: str) -> str:
    """'closed-form', 'identified' or 'other' from a plan's name."""
    lowered = name.lower()
    if any(k in lowered for k in ("ident", "sparse", "sindy")):
        return "identified"
    if any(k in lowered for k in ("pinocchio", "closed", "analytic", "baseline")):
        return "closed-form"
    return "other"


def checks(result: ReplayResult) -> dict[str, bool]:
    """The checks of one replay, by name."""
    out = {
        "tracking_rms_le_1mrad": result.tracking_rms <= TRACKING_LIMIT,
        "energy_within_2pct": abs(result.energy_error) <= ENERGY_TOLERANCE,
        "energy_within_2pct_of_dense_plan": abs(result.energy / result.energy_reference - 1)
        <= ENERGY_TOLERANCE,
    }
    if result.threshold > 0:  # the threshold kept, or, by a plan that could not keep it, its own
        kept = result.threshold if result.planned_min_clearance is None \
            else min(result.threshold, result.planned_min_clearance)
        out["clearance_kept_within_5mm"] = result.min_clearance >= kept - CLEARANCE_MARGIN
    return out


def pairs(names) -> dict[str, tuple[str, str]]:
    """{scenario: (identified plan, closed-form plan)} for plans named alike but for the
    model ('identified_crossing' and 'pinocchio_crossing', 'paper_identified' and
    'paper_pinocchio')."""
    names = list(names)
    out = {}
    for name in names:
        if "identified" in name and name.replace("identified", "pinocchio") in names:
            out[name.replace("identified", "").strip("_")] = (
                name, name.replace("identified", "pinocchio"))
    return out


def table_row(name: str, r: ReplayResult, ok: dict[str, bool]) -> str:
    surface = "–" if r.surface_clearance is None else f"{r.surface_clearance * 1e3:.1f}"
    failed = [k for k, v in ok.items() if not v]
    verdict = "FAIL: " + ", ".join(failed) if failed else "pass"
    return (f"| {name} | {r.energy_planned:.4f} | {r.energy_reference:.4f} | {r.energy:.4f} "
            f"| {100 * r.energy_error:+.2f} % "
            f"| {r.min_clearance * 1e3:.1f} | {surface} | {r.threshold * 1e3:.0f} "
            f"| {r.tracking_rms * 1e3:.3f} | {r.max_tracking_error * 1e3:.3f} | {verdict} |")
