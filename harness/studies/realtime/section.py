"""`torquebench study realtime`: the real-time study on the robot, as a report section.

Its timing figures are targets (CPU time of the planning thread, measured side by side in
one run); whether a re-plan missed its deadline depends on the machine's speed, so every
result of the study is reported as timing-dependent."""

from __future__ import annotations

from harness.report.results import Context, SectionResult, Target
from harness.robots.scene import replay_scene
from harness.studies.realtime import measure, tables

REPLAN_MEDIAN_MS, REPLAN_MAX_MS, COLD_MAX_MS = 2.0, 10.0, 25.0
# a re-plan's work outside the anytime SQP's solve (the bar), and beside it
# everything but the compiled evaluations and DAQP
OVERHEAD_MS = 0.3


def run(ctx: Context) -> SectionResult:
    study = measure.run(ctx.arm.nominal, replay_scene(ctx.arm), ctx.quick)
    default = study["default"]
    warm, cold = default["replan_cpu_ms"], default["cold_cpu_ms"]
    per, causal = study["references"]["per_replan"], study["references"]["causal"]
    targets = [
        Target("default planner: warm re-plan CPU time, median", warm["median"] if warm["count"]
               else None, REPLAN_MEDIAN_MS, "ms", timing=True),
        Target("default planner: warm re-plan CPU time, max", warm["max"] if warm["count"]
               else None, REPLAN_MAX_MS, "ms", timing=True),
        Target("default planner: cold plan CPU time, max", cold["max"], COLD_MAX_MS, "ms",
               timing=True),
        *_anytime_targets(study["ways_in"][study["anytime_way"]], per),
        Target("anytime SQP re-plans within 0.5 % of a same-forecast multi-start",
               100 * per["within"] / max(per["replans"], 1), 95.0, "%",
               lower_is_better=False, timing=True),
        Target("scenarios whose executed energy is within 0.5 % of the causal multi-start "
               "planner's, or feasible where it is not"
               + _scenarios(study["setup"]["seed"]), causal["within"],
               18 * causal["scenarios"] / 20, "scenarios", lower_is_better=False, timing=True),
        *_clearance_targets(study),
    ]
    if ctx.quick:  # the smoke-test size plans uncompiled: not comparable with the targets
        targets = []
    return SectionResult("\n".join(tables.markdown_lines(study)), {"timing": study}, [],
                         targets)


def _scenarios(seed: int) -> str:
    """Which scenarios a target is scored on."""
    if seed == measure.DEVELOPMENT_SEED:
        return (f" (seed {seed}: the development scenarios the planner's settings were chosen "
                "on, not a held-out score)")
    return f" (seed {seed}, drawn once: no setting was chosen on it)"


def _anytime_targets(row: dict, per: dict) -> list[Target]:
    """The anytime SQP's own speed bars (it runs beside the default in the study)."""
    warm, cold = row["replan_cpu_ms"], row["cold_cpu_ms"]
    return [Target("anytime SQP: warm re-plan CPU time, median", warm["median"], REPLAN_MEDIAN_MS,
                   "ms", timing=True),
            Target("anytime SQP: warm re-plan CPU time, max", warm["max"], REPLAN_MAX_MS, "ms",
                   timing=True),
            Target("anytime SQP: cold plan CPU time, max", cold["max"], COLD_MAX_MS, "ms",
                   timing=True),
            Target("anytime SQP: Python around the solver per re-plan, median",
                   per["overhead_cpu_ms"]["median"], OVERHEAD_MS, "ms", timing=True),
            Target("anytime SQP: CPU outside its solve per re-plan, median",
                   per["outside_cpu_ms"]["median"], OVERHEAD_MS, "ms", timing=True)]


def _clearance_targets(study: dict) -> list[Target]:
    """No loss of clearance from the global search: the default's infeasible executions and
    smallest executed clearance against the anytime SQP's without it (when the study ran it)."""
    row = study["ways_in"][study["anytime_way"]]
    alone = next((r for name, r in study["ways_in"].items() if "no global search" in name), None)
    if alone is None:
        return []
    return [Target("default planner: infeasible executions (the anytime SQP alone's as target)",
                   row["executed_infeasible"], alone["executed_infeasible"], "", timing=True),
            Target("default planner: smallest executed clearance (the anytime SQP alone's as "
                   "target)", 1e3 * row["executed_min_clearance_m"],
                   1e3 * alone["executed_min_clearance_m"], "mm", lower_is_better=False,
                   timing=True)]
