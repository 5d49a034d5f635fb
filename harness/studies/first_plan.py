"""Study `first_plan`: the first plan on a new robot, compilation included (issue 43 item 7).

`torquebench plan --robot panda --model pinocchio` (7 joints, its registered motion, an
obstacle passing its forearm) run as
a user runs it, each run a fresh process timed from start to exit (wall, and the CPU of the
process and its compilers), each scenario with an empty compile cache of its own:

1. the first plan (nominal clocks: the quick -O0 build, planning.formulation.compiled),
2. the same command again (the cache warm),
3. `--realtime` on an empty cache (the optimized build: its re-plans' CPU counts),
4. the default command on that cache, which takes the optimized build: its PLAN.json must
   equal the first run's apart from the timing keys (the plan does not depend on the build).

The quick form (the smoke test) plans the double pendulum instead. Timings depend on the
machine and its load: the load average is reported beside them.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness.report.results import Context, SectionResult, Target, check
from planning.result import TIMING_KEYS

ROOT = Path(__file__).resolve().parents[2]  # the runs plan with this tree's code
FIRST_PLAN_S = 30.0  # the bar, compilation included
# the obstacle passes the Panda's forearm (the default path is the Lynxmotion's: inside the
# Panda's fitted link capsules at its start)
ROBOTS = {False: ("panda", "--obstacle-from", "0.3,0.15,0.3", "--obstacle-to", "0.3,0.15,0.8"),
          True: ("double_pendulum", "--start", "0,0", "--goal", "1.2,-0.8",
                                    "--obstacle-from", "0.2,0,0.3", "--obstacle-to", "0.2,0,-0.3")}
RUNS = (("first plan (quick build)", "quick", ()), ("second run", "quick", ()),
        ("first plan --realtime (optimized build)", "optimized", ("--realtime",)),
        ("default plan on the optimized build", "optimized", ()))


def run(ctx: Context) -> SectionResult:
    robot = ROBOTS[ctx.quick]
    runs = []
    with tempfile.TemporaryDirectory() as caches:
        for name, cache, extra in RUNS:
            out = Path(caches) / f"{len(runs)}.json"
            runs.append({"run": name, **_timed(robot, extra, Path(caches) / cache, out)})
            runs[-1]["plan"] = json.loads(out.read_text())
    quick, optimized = (_without_timing(runs[k].pop("plan")) for k in (0, 3))
    for r in runs[1:3]:
        r.pop("plan")
    same = quick == optimized
    lines = [f"`torquebench plan --robot {' '.join(robot)} --model pinocchio`, each a fresh "
             "process; wall and CPU (the process and its compilers) in s; load: the 1-minute "
             "load average before and after (2 cores).", "",
             "| run | wall (s) | CPU (s) | load before / after |", "|---|---|---|---|"]
    lines += [f"| {r['run']} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['load'][0]:.1f} / "
              f"{r['load'][1]:.1f} |" for r in runs]
    lines += ["", f"The default plan from the quick build and from the optimized one: "
              f"{'the same' if same else 'DIFFERENT'} PLAN.json apart from its timing keys."]
    targets = [] if ctx.quick else [
        Target("first plan on a new 7-DOF robot, compilation included (wall)",
               runs[0]["wall_s"], FIRST_PLAN_S, "s", timing=True,
               note=f"load {runs[0]['load'][0]:.1f} before, {runs[0]['load'][1]:.1f} after")]
    checks = [check("the same plan from the quick and the optimized build", same,
                    "PLAN.json apart from " + ", ".join(TIMING_KEYS))]
    return SectionResult("\n".join(lines), {"robot": robot[0], "runs": runs, "same_plan": same},
                         checks, targets)


def _timed(robot: tuple[str, ...], extra: tuple[str, ...], cache: Path, out: Path) -> dict:
    """One `plan` run with the compile cache in `cache`: wall and CPU time (s), load."""
    command = [sys.executable, "-m", "harness", "plan", "--robot", *robot, "--model",
               "pinocchio", *extra, "--out", str(out)]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    began = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, "TORQUEBENCH_CACHE": str(cache)})
    wall = time.perf_counter() - began
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command[2:])} exited {done.returncode}: "
                           f"{done.stderr.strip().splitlines()[-1:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load": (load, os.getloadavg()[0])}


def _without_timing(plan: dict) -> dict:
    return {key: value for key, value in plan.items() if key not in TIMING_KEYS}
