"""`torquebench study realtime_runs`: `plan --realtime` (CPU budgets: the plan depends on the
machine by design) run RUNS times on each of SCENARIOS fresh Lynxmotion scenarios, first on
the machine as it is ("quiet": the study adds nothing; its load average reported) and then
under a load the study makes (one busy-loop process per core the study may run on, killed
when the runs end or fail). Each run is `torquebench plan --robot R --model pinocchio
--start .. --goal .. --obstacle-from .. --obstacle-to .. --obstacle-sway .. --sway-periods ..
--realtime` in a process of its own (harness.studies.realtime_runs.runs), the runs of the
scenarios interleaved. Per scenario and condition: runs refused, each run's smallest executed
clearance against the threshold (and `plan`'s 2 mm tolerance), the executed energy's min,
median, max and spread; targets per condition: every run keeps the clearance, none refused.
A run that does not keep the clearance leaves its PLAN.json payload in DIR/lost_clearance/.

Seed 1544 drawn once on 2026-12-08 (numpy.random.default_rng().integers(10_000)); no planner
setting was chosen on its scenarios (harness.plan.fresh.arm_scenarios, from the unobstructed
optimum). The quick form (the smoke test): one scenario, 2 runs a condition.
"""

from __future__ import annotations

import os

from harness.io import write_json
from harness.plan.arm_config import planner_config
from harness.plan.fresh import arm_scenarios, plan_options
from harness.report.results import Context, SectionResult, check
from harness.studies.bank import scenario_text
from harness.studies.realtime_runs import load, runs, scores
from planning.globalsearch.background import cores

SEED = 1544  # drawn once on 2026-12-08; see the module's docstring
SCENARIOS, RUNS = 5, 20
QUICK_SCENARIOS, QUICK_RUNS = 1, 2


def run(ctx: Context) -> SectionResult:
    count, repeats = (QUICK_SCENARIOS, QUICK_RUNS) if ctx.quick else (SCENARIOS, RUNS)
    arm = ctx.arm
    cases = arm_scenarios(arm, count, SEED)
    commands = [("--robot", arm.reference, "--model", "pinocchio", *plan_options(case))
                for case in cases]
    threshold = planner_config(arm).threshold
    spinners = cores()
    conditions, loads, alive = {}, {}, True
    for name in ("quiet", f"loaded ({spinners} busy loops)"):
        before = os.getloadavg()[0]
        if name == "quiet":
            found = _runs(commands, repeats)
        else:
            with load.busy(spinners) as pids:
                found = _runs(commands, repeats)
                alive = all(load.running(pid) for pid in pids)
        loads[name] = (before, os.getloadavg()[0])
        conditions[name] = found
    _keep_lost(ctx, conditions)
    scored = {name: [scores.scored(r, threshold) for r in found]
              for name, found in conditions.items()}
    note = f"seed {SEED}, {count} scenarios x {repeats} runs"
    text = _markdown(arm, commands, repeats, spinners, loads, scored)
    errors = sum(r["errors"] for rows in scored.values() for r in rows)
    return SectionResult(
        "\n".join(text),
        {"seed": SEED, "runs_per_scenario": repeats, "busy_loops": spinners,
         "threshold_m": threshold, "load_average": loads,
         "scenarios": [scenario_text(case) for case in cases],
         "commands": [_command(c) for c in commands], "scores": scored,
         "runs": conditions},
        [check("every run planned or was refused (none raised)", errors == 0, f"{errors} raised"),
         check("the study's load ran throughout its runs", alive,
               f"{spinners} busy loops alive at the end of the loaded runs")],
        [] if ctx.quick else scores.targets(scored, note))


def _runs(commands, repeats: int) -> list[list[dict]]:
    """Each command run `repeats` times, the commands interleaved: per command its runs."""
    found = [[] for _ in commands]
    for _ in range(repeats):
        for i, argv in enumerate(commands):
            found[i].append(runs.run(argv))
    return found


def _keep_lost(ctx: Context, conditions: dict) -> None:
    """Write each run that lost the clearance's PLAN.json payload (kept out of the results)."""
    for c, (name, found) in enumerate(conditions.items()):
        for i, scenario_runs in enumerate(found):
            for k, r in enumerate(scenario_runs):
                payload = r.pop("plan", None)
                if payload is not None:
                    write_json(ctx.out_dir / "lost_clearance" / f"c{c}_s{i}_r{k}.json",
                               {"condition": name, **payload})


def _command(argv) -> str:
    return "torquebench plan " + " ".join(argv) + " --realtime --out PLAN.json"


def _markdown(arm, commands, repeats, spinners, loads, scored) -> list[str]:
    lines = [f"`plan --realtime` on {len(commands)} fresh {arm.label} scenarios (seed {SEED}, "
             f"drawn once), {repeats} runs of each per condition, each run a process of its "
             f"own; loaded: {spinners} busy-loop processes (one per core this study may run "
             "on). Load average (1 min) before and after: "
             + "; ".join(f"{n} {a:.1f} -> {b:.1f}" for n, (a, b) in loads.items()) + ".", "",
             "A run's margin is its smallest clearance at the obstacle samples less the "
             "threshold; `plan` counts down to -2 mm as kept. The energy is the executed "
             "motion's (the planning model's, PLAN.json's `energy`) over the runs `plan` "
             "writes.", ""]
    lines += scores.table(scored)
    lines += ["", "Commands (one per scenario):", ""]
    lines += [f"{i}. `{_command(c)}`" for i, c in enumerate(commands)]
    return lines
