"""Study `replan_profile`: where an anytime-SQP iteration and a warm re-plan spend their CPU.

`torquebench plan`'s default planner (the bank of plans on the nominal clock, so the plans
are the command's own) on the Lynxmotion's default scenario and the README's UR5 crossing,
with the optimized build of the compiled functions (the one `--realtime` plans with), run
twice: bare, for the re-plans' CPU as PLAN.json reports it, and with timers around the
iteration's parts (harness.studies.replan_profile.timers), which must give the same plan.
Per scenario: each part's CPU per SQP iteration (median, 95th percentile, share of all the
iterations' CPU) and where each warm re-plan's CPU goes. Timings depend on the machine and
its load: the 1-minute load average is reported before and after each run.

The quick form (the smoke test) runs the Lynxmotion's scenario with 40 obstacle samples.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from harness.commands import plan as plan_command
from harness.plan.options import config_from_options, scenario_from_options
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.resolve import resolve_arm
from harness.robots.torque_models import read_model, torque_model
from harness.studies.replan_profile import timers
from planning.planners import executed
from planning.result import TIMING_KEYS, to_json

SCENARIOS = {"lynxmotion": ("--robot", "lynxmotion", "--model", "pinocchio"),
             "ur5": ("--robot", "ur5", "--model", "pinocchio", "--obstacle-from",
                     "0.37,-0.06,0.15", "--obstacle-to", "0.37,-0.06,0.65")}
QUICK = ("--samples", "40")
# issue #71's bars, on the Lynxmotion (ms of the planning thread's CPU)
ITERATION_MEDIAN_MS, ITERATION_P95_MS = 0.15, 0.3
REPLAN_MEDIAN_MS, REPLAN_MAX_MS = 1.0, 10.0
# a re-plan's windows: (name, what it holds)
REPLAN_PARTS = (("iterations", "the SQP iterations (the table above)"),
                ("solve setup", "an SQP solve before its first iteration (its frame, the "
                                "start's evaluation and restoration)"),
                ("choice", "the choice among a solve's iterates: their safety checks"),
                ("round", "a round around its solve: screening, parameters, bounds, start, "
                          "packing the plan"),
                ("bank", "the bank around its solves: its checks of its plans, scores, "
                         "bookkeeping"),
                ("checks", "of all these, the calls of the compiled safety checks (clearance "
                           "at the forecast samples, limits and torques, dense energy)"))


def run(ctx: Context) -> SectionResult:
    names = ("lynxmotion",) if ctx.quick else tuple(SCENARIOS)
    overhead = timers.overhead_ns()
    results, lines, checks, targets = {}, [], [], []
    for name in names:
        argv = SCENARIOS[name] + (QUICK if ctx.quick else ())
        result = profiled(argv, overhead)
        results[name] = result
        lines += _table(name, argv, result)
        checks.append(check(f"{name}: the same plan with the timers in place",
                            result.pop("same_plan"), "PLAN.json apart from "
                            + ", ".join(TIMING_KEYS)))
    lynx = results["lynxmotion"]
    load = f"load {lynx['load'][0]:.1f} before, {lynx['load'][1]:.1f} after"
    if not ctx.quick:
        targets = [
            Target("Lynxmotion SQP iteration CPU, median", lynx["iteration_ms"]["median"],
                   ITERATION_MEDIAN_MS, "ms", timing=True, note=load),
            Target("Lynxmotion SQP iteration CPU, 95th percentile", lynx["iteration_ms"]["p95"],
                   ITERATION_P95_MS, "ms", timing=True, note=load),
            Target("Lynxmotion warm re-plan CPU, median", lynx["replan_cpu_ms"]["median"],
                   REPLAN_MEDIAN_MS, "ms", timing=True, note=load),
            Target("Lynxmotion warm re-plan CPU, max", lynx["replan_cpu_ms"]["max"],
                   REPLAN_MAX_MS, "ms", timing=True, note=load)]
    text = "\n".join([f"Timers' own cost: {overhead:.0f} ns a timed call, taken out of each "
                      "iteration's Python share.", ""] + lines)
    return SectionResult(text, {"overhead_ns": overhead, "scenarios": results}, checks, targets)


def profiled(argv: tuple[str, ...], overhead_ns: float) -> dict:
    """One scenario planned bare and with the timers: the re-plans' CPU (bare), each
    iteration part's CPU and each re-plan window's (timed), the loads, same_plan."""
    load = [os.getloadavg()[0]]
    bare, config = _planned(argv)
    recorder = timers.Recorder()
    with timers.installed(recorder):
        timed, _ = _planned(argv)
    load.append(os.getloadavg()[0])
    iterations = recorder.iterations
    per_call = overhead_ns * recorder.calls / max(len(iterations), 1)
    parts = {}
    total = np.array([it["total"] for it in iterations], float) - per_call
    for part in timers.PARTS:
        parts[part] = np.array([it.get(part, 0) for it in iterations], float)
    parts["Python around"] = total - sum(parts.values())
    replans = recorder.replans
    windows = _windows(replans)
    cpu = np.asarray(bare["timing"]["replan_cpu_ms"], float)
    return {
        "command": "torquebench plan " + " ".join(argv), "load": load,
        "iterations": len(iterations), "replans_timed": len(replans),
        "corrections": int(sum(it.get("corrections", 0) for it in iterations)),
        "clock_ms_per_iteration": config.anytime.iteration_ms,
        "iteration_ms": _stats(total / 1e6),
        "parts_us": {part: {**_stats(values / 1e3), "share": float(values.sum() / total.sum())}
                     for part, values in parts.items()},
        "replan_windows_ms": windows,
        "replan_cpu_ms": {**_stats(cpu), "max": float(cpu.max(initial=0.0))},
        "energy": bare["energy"], "same_plan": _plan(bare) == _plan(timed)}


def _planned(argv: tuple[str, ...]) -> tuple[dict, object]:
    """PLAN.json's payload of `plan argv` with the optimized build (the nominal clock),
    and the configuration that planned it."""
    args = plan_command.parse([*argv, "--out", "unused"])
    model_file = read_model(args.model)
    arm = resolve_arm(args.robot, model=model_file.recorded)
    config = dataclasses.replace(config_from_options(args, arm), quick_build=False)
    scenario = scenario_from_options(args, arm, config)
    model = torque_model(model_file, arm)
    config, result = executed(model, config, scenario, either=True)
    return to_json(result, scenario, config, args.model), config


def _windows(replans: list[dict]) -> dict:
    """Per re-plan (ms): its CPU without the global search's, and each of REPLAN_PARTS."""
    def column(key):
        return np.array([r.get(key, 0) for r in replans], float) / 1e6
    whole = column("replan") - column("search")
    sqp, rounds, choice = column("sqp"), column("round"), column("choice")
    iterations = column("iterations")
    values = {"iterations": iterations, "solve setup": sqp - iterations, "choice": choice,
              "round": rounds - sqp - choice, "bank": whole - rounds,
              "checks": column("checks")}
    out = {"replan": _stats(whole)}
    for name, _ in REPLAN_PARTS:
        out[name] = {**_stats(values[name]), "share": float(values[name].sum() / whole.sum())}
    return out


def _stats(values: np.ndarray) -> dict:
    values = np.asarray(values, float)
    if not len(values):
        return {"median": float("nan"), "p95": float("nan")}
    return {"median": float(np.median(values)), "p95": float(np.percentile(values, 95))}


def _plan(payload: dict) -> str:
    return repr({k: v for k, v in payload.items() if k not in TIMING_KEYS})


def _table(name: str, argv: tuple[str, ...], result: dict) -> list[str]:
    it, load = result["iteration_ms"], result["load"]
    lines = [f"### {name}", "", f"`torquebench plan {' '.join(argv)}` (optimized build, "
             f"nominal clock), load {load[0]:.1f} before, {load[1]:.1f} after (2 cores): "
             f"{result['iterations']} SQP iterations ({result['corrections']} second-order "
             f"corrections) in {result['replans_timed']} warm re-plans; an iteration "
             f"{1e3 * it['median']:.0f} us median, {1e3 * it['p95']:.0f} us p95 "
             f"(charged {1e3 * result['clock_ms_per_iteration']:.0f} us on the nominal clock).",
             "", "| part of an iteration | median (us) | p95 (us) | share |", "|---|---|---|---|"]
    for part, row in result["parts_us"].items():
        lines.append(f"| {part} | {row['median']:.1f} | {row['p95']:.1f} | "
                     f"{100 * row['share']:.1f} % |")
    windows, cpu = result["replan_windows_ms"], result["replan_cpu_ms"]
    lines += ["", f"Warm re-plans (bare run, PLAN.json's replan_cpu_ms): median "
              f"{cpu['median']:.2f} ms, p95 {cpu['p95']:.2f}, max {cpu['max']:.2f} ms; with "
              f"the timers, each re-plan's CPU (the global search's left out) median "
              f"{windows['replan']['median']:.2f} ms:", "",
              "| part of a re-plan | median (ms) | p95 (ms) | share |", "|---|---|---|---|"]
    for part, _ in REPLAN_PARTS:
        row = windows[part]
        lines.append(f"| {part} | {row['median']:.3f} | {row['p95']:.3f} | "
                     f"{100 * row['share']:.1f} % |")
    return lines + [""]
