"""Study `bank`: the bank of plans (planning.bank, `plan`'s default re-planner) scored on
scenarios no default was chosen on (issue 55).

Seed 9784, drawn once (Python's secrets.randbelow, 2026-11-28) after the bank's defaults were
set on the development scenarios (the realtime study's 20, seed 2026, and docs/realtime.md's
nine UR5 and Panda crossings): 20 random Lynxmotion scenarios and 5 each on the UR5 (6
joints) and the Panda (7), drawn by planning.scenarios.random_scenarios (an obstacle crossing
the unobstructed optimum's links mid-motion, swaying; on the UR5 and the Panda start and goal
within +-1.5 rad). Each is planned as a user plans it,
`torquebench plan --robot R --model pinocchio --start .. --goal .. --obstacle-from ..
--obstacle-to .. --obstacle-sway .. --sway-periods ..` (nominal clocks, the same plans on any
machine), three ways: the default (the bank), `--bank 1` (one plan re-planned, the default
before the bank) and `--replanner penalty` (the paper's penalty loop). A plan that `plan`
refuses (no feasible plan: exit 2) is reported apart, not counted as within. On the
Lynxmotion the bank is also held to the issue's reference as it was first stated: the causal
multi-start (harness.plan.causal: Algorithm 2 re-planning by a multi-start of IPOPT to
convergence at every re-plan, the bench's starts), 19 of 20 within 0.5 % or below; a
scenario whose reference is infeasible is reported apart and not counted as within.

The quick form (the smoke test) plans 2 Lynxmotion scenarios.
"""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
from pathlib import Path

import numpy as np

from harness.bench.planning.section import CAUSAL_STARTS
from harness.cli import main
from harness.plan.arm_config import planner_config
from harness.plan.causal import against_causal
from harness.plan.fresh import arm_scenarios, plan_options
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm

SEED = 9784  # drawn once; see the module's docstring
# rad: the 6- and 7-joint arms' start and goal are drawn within +-SPAN of zero (their
# ranges of +-2 pi gave motions no joint can make in 2 s within its velocity limit: the
# first run of the study, every UR5 scenario refused)
SPAN = 1.5
# (robot, scenarios, the span its start and goal are drawn in: None for its joint ranges)
ROBOTS = (("lynxmotion", 20, None), ("ur5", 5, SPAN), ("panda", 5, SPAN))
WAYS = (("bank", ()), ("one plan", ("--bank", "1")), ("penalty loop", ("--replanner", "penalty")))
WITHIN = 0.005  # the bar: within 0.5 % of the penalty loop, or below
# the bank's re-plan CPU on the Lynxmotion (PLAN.json's timing.replan_cpu_ms: the whole
# bank's work at a re-plan, planning.bank.work), over the executions the bank planned
CPU_MAX_MS, CPU_MEDIAN_MS = 10.0, 2.0


def run(ctx: Context) -> SectionResult:
    robots = ((*ROBOTS[0][:1], 2, ROBOTS[0][2]),) if ctx.quick else ROBOTS
    ways = WAYS[:2] if ctx.quick else WAYS
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for offset, (name, count, span) in enumerate(robots):
            for i, scenario in enumerate(draw(name, count, SEED + offset, span)):
                row = {"robot": name, "scenario": i, **scenario_text(scenario)}
                for way, extra in ways:
                    row[way] = planned(name, scenario, extra, Path(tmp) / f"{name}{i}{way}.json")
                if name == "lynxmotion":  # the quick form: from the detours alone
                    row["causal"] = causal(name, scenario, row["bank"],
                                           0 if ctx.quick else CAUSAL_STARTS)
                rows.append(row)
    return SectionResult("\n".join(table(rows, ways)), {"seed": SEED, "rows": rows},
                         checks(rows), [] if ctx.quick else targets(rows))


def draw(name: str, count: int, seed: int, span: float | None = None) -> list:
    """The robot's random scenarios (harness.plan.fresh.arm_scenarios)."""
    return arm_scenarios(Arm.of(name), count, seed, span)


def causal(robot: str, scenario, bank: dict, starts: int) -> dict:
    """The causal multi-start reference on the scenario (its energy, feasibility) and the
    bank's executed energy over it (%, None when the bank planned nothing)."""
    arm = Arm.of(robot)
    ours = bank.get("energy")
    row = against_causal(arm.nominal, planner_config(arm), scenario,
                         float("nan") if ours is None else ours, starts)
    return {**row, "excess_pct": None if ours is None else row["excess_pct"]}


def scenario_text(scenario) -> dict:
    obstacle = scenario.obstacle
    return {"start": scenario.start, "goal": scenario.goal, "obstacle_from": obstacle.start,
            "obstacle_to": obstacle.end, "sway": obstacle.sway, "periods": obstacle.periods}


def planned(robot: str, scenario, extra: tuple, out: Path) -> dict:
    """`plan` on the scenario: executed energy (J), smallest clearance (m), re-plan CPU and
    clock (ms); {"refused": why} when plan exits 2."""
    argv = ["plan", "--robot", robot, "--model", "pinocchio", *plan_options(scenario), *extra,
            "--out", str(out)]
    errors = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(errors):
        code = main(argv)
    if code != 0:
        return {"refused": errors.getvalue().strip().splitlines()[-1:]}
    plan = json.loads(out.read_text())
    timing = plan["timing"]
    return {"energy": plan["energy"], "min_clearance": plan["min_clearance"],
            "threshold": plan["threshold"], "replanner": plan["replanner"],
            "bank_planned": plan.get("bank") is not None,  # not the other method's fallback
            "replan_cpu_ms": timing["replan_cpu_ms"],
            "replan_clock_ms": timing["replan_clock_ms"],
            "switches": len((plan.get("bank") or {}).get("switches", []))}


def excess(row: dict, way: str, against: str) -> float | None:
    """How much more `way` spent than `against` (a fraction), None if either was refused."""
    if "energy" not in row[way] or "energy" not in row.get(against, {}):
        return None
    return row[way]["energy"] / row[against]["energy"] - 1.0


def table(rows: list[dict], ways) -> list[str]:
    names = [way for way, _ in ways]
    lines = [f"Seed {SEED} (drawn once). Executed energy (J) of each way; the bank's excess "
             "over the penalty loop and over one plan; its class switches.", "",
             "| robot | # | " + " | ".join(names) + " | bank vs penalty | bank vs one plan "
             "| switches |", "|---|---|" + "---|" * (len(names) + 3)]
    for row in rows:
        cells = [f"{row[w]['energy']:.4f}" if "energy" in row[w] else "refused" for w in names]
        gaps = [excess(row, "bank", other) for other in ("penalty loop", "one plan")]
        lines.append(f"| {row['robot']} | {row['scenario']} | " + " | ".join(cells) + " | " +
                     " | ".join("-" if g is None else f"{100 * g:+.2f} %" for g in gaps) +
                     f" | {switches(row['bank'])} |")
    causal_rows = [r for r in rows if "causal" in r]
    if causal_rows:
        lines += ["", "Against the causal multi-start reference (Lynxmotion): its executed "
                  "energy (J), feasible or not, and the bank's excess over it.", "",
                  "| # | reference | feasible | bank | bank vs reference |", "|---|---|---|---|---|"]
        for r in causal_rows:
            c = r["causal"]
            gap = "-" if c["excess_pct"] is None else f"{c['excess_pct']:+.3f} %"
            bank = f"{r['bank']['energy']:.4f}" if "energy" in r["bank"] else "refused"
            lines.append(f"| {r['scenario']} | {c['reference_J']:.4f} | "
                         f"{'yes' if c['reference_feasible'] else 'no'} | {bank} | {gap} |")
    return lines


def switches(result: dict) -> str:
    """The bank's class switches, or whose plan `plan` gave when the bank's left the
    threshold (the other method's fallback)."""
    if result.get("bank_planned", True):
        return str(result.get("switches", "-"))
    return f"- ({result['replanner']}'s plan)"


def within(rows: list[dict], robots: tuple[str, ...]) -> tuple[int, int, int]:
    """Of the rows on these robots whose penalty loop planned: how many the bank planned
    within WITHIN of it or below; how many were counted; how many the penalty loop could not
    plan (reported apart)."""
    chosen = [r for r in rows if r["robot"] in robots]
    counted = [r for r in chosen if "energy" in r["penalty loop"]]
    gaps = [excess(r, "bank", "penalty loop") for r in counted]
    good = sum(1 for gap in gaps if gap is not None and gap <= WITHIN)
    return good, len(counted), len(chosen) - len(counted)


def checks(rows: list[dict]) -> list:
    planned_rows = [r["bank"] for r in rows if "energy" in r["bank"]]
    low = min((p["min_clearance"] - p["threshold"] for p in planned_rows), default=0.0)
    return [check("the bank's executions keep the threshold (2 mm tolerance)", low >= -2e-3,
                  f"smallest clearance minus threshold {1e3 * low:+.1f} mm"),
            check("the bank plans every scenario one plan plans",
                  all("energy" in r["bank"] for r in rows if "energy" in r["one plan"]),
                  "refusals: " + str(sum("energy" not in r["bank"] for r in rows)))]


def targets(rows: list[dict]) -> list[Target]:
    found = []
    for label, robots, bar in (("Lynxmotion", ("lynxmotion",), 19),
                               ("6- and 7-joint arms", ("ur5", "panda"), None)):
        good, counted, apart = within(rows, robots)
        found.append(Target(f"{label}: scenarios within 0.5 % of the penalty loop or below",
                            good, counted if bar is None else min(bar, counted), "",
                            lower_is_better=False,
                            note=f"of {counted}; {apart} the penalty loop could not plan"))
    referenced = [r["causal"] for r in rows if "causal" in r]
    if referenced:
        good = sum(1 for c in referenced if c["reference_feasible"] and c["excess_pct"] is not None
                   and c["excess_pct"] <= 100 * WITHIN)
        apart = sum(not c["reference_feasible"] for c in referenced)
        found.append(Target("Lynxmotion: scenarios within 0.5 % of the causal multi-start or "
                            "below (the target as first stated)", good, 19, "",
                            lower_is_better=False,
                            note=f"of {len(referenced)}; {apart} whose reference is infeasible "
                                 "reported apart, not counted as within"))
    lynx = [r["bank"] for r in rows if r["robot"] == "lynxmotion" and "energy" in r["bank"]]
    cpu = [ms for r in lynx if r.get("bank_planned", True) for ms in r["replan_cpu_ms"]]
    fallbacks = f"{sum(not r.get('bank_planned', True) for r in lynx)} executions `plan` " \
        "fell back to the other method for left out"
    if cpu:
        found += [Target("Lynxmotion: the bank's re-plan CPU, max", float(np.max(cpu)),
                         CPU_MAX_MS, "ms", timing=True, note=fallbacks),
                  Target("Lynxmotion: the bank's re-plan CPU, median", float(np.median(cpu)),
                         CPU_MEDIAN_MS, "ms", timing=True, note=fallbacks)]
    return found
