"""One `torquebench plan ... --realtime` run in a process of its own, forked from the study
(as a command starts afresh, but with the modules already imported), summarized: refused or
not and why, the smallest executed clearance, the executed energy, the re-plans' CPU; and,
for a run that did not keep the clearance, its PLAN.json payload (written though `plan`
would refuse it) to look into."""

from __future__ import annotations

import multiprocessing
import time
import traceback

import numpy as np

from harness.commands import plan as plan_command
from harness.robots.resolve import resolve_arm
from harness.robots.torque_models import read_model
from planning.errors import PlanningError
from planning.result import CLEARANCE_TOLERANCE, PlanResult, to_json


def run(argv: tuple[str, ...]) -> dict:
    """`plan argv --realtime` in a forked process: its summary (summary), or {"refused":
    True, "why": [the error]} where plan raised before executing anything, or {"error": the
    traceback's last line} where it raised otherwise or the process died."""
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_child, args=(argv, send))
    child.start()
    send.close()
    try:
        found = receive.recv()
    except EOFError:
        found = {"error": "the run's process died"}
    child.join()
    return found


def _child(argv: tuple[str, ...], send) -> None:
    try:
        found = planned(argv)
    except Exception:  # noqa: BLE001 - any failure is the run's finding, not the study's end
        found = {"error": traceback.format_exc().strip().splitlines()[-1]}
    send.send(found)
    for process in multiprocessing.active_children():  # the global search's worker
        process.terminate()
        process.join()


def planned(argv: tuple[str, ...]) -> dict:
    """`plan argv --realtime` in this process, summarized (summary)."""
    args = plan_command.parse([*argv, "--realtime", "--out", "unused"])
    model_file = read_model(args.model)
    arm = resolve_arm(args.robot, model=model_file.recorded)
    start = time.perf_counter()
    try:
        config, scenario, _, _, result = plan_command.planned(args, arm, model_file)
    except PlanningError as error:
        return {"refused": True, "why": [str(error)], "min_clearance_m": None}
    found = summary(result, config.threshold)
    found["wall_s"] = time.perf_counter() - start
    if not found["keeps_clearance"]:
        found["plan"] = to_json(result, scenario, config, args.model)
    return found


def summary(result: PlanResult, threshold: float) -> dict:
    """What a run did: refused (what `plan` refuses: not feasible) and why, the smallest
    clearance at the obstacle samples (m, `plan`'s check; on the dense grid beside), whether it
    keeps the threshold within planning.result's tolerance, when and which sample came
    closest, the executed energy (J, the planning model's), the warm re-plans' CPU (ms)."""
    execution = result.execution
    samples = result.sample_clearance
    k = int(np.argmin(samples))
    warm = np.asarray(execution.solve_cpu_ms[1:], float)
    return {"refused": not result.feasible, "why": list(result.problems),
            "min_clearance_m": float(samples[k]),
            "dense_min_clearance_m": float(result.clearance.min()),
            "keeps_clearance": bool(samples[k] >= threshold - CLEARANCE_TOLERANCE),
            "closest_t_s": float(result.t[(k + 1) * (len(result.t) - 1) // len(samples)]),
            "energy_J": float(result.energy), "replans": len(execution.segments) - 1,
            "replan_failures": list(execution.replan_failures),
            "first_plan_cpu_ms": float(execution.solve_cpu_ms[0]),
            "replan_cpu_median_ms": float(np.median(warm)) if len(warm) else None,
            "replan_cpu_max_ms": float(warm.max()) if len(warm) else None,
            "search_failures": execution.search_failures}
