"""Throughput of `torquebench sweep`: the same cells run serially in one process and as Ray
tasks on a local instance, side by side in one run.

The serial pass calls the cell runner (harness.sweep.cell.run_cell) in a loop in this process;
the Ray pass starts a local Ray instance (harness.sweep.run.ray_session, one worker slot per
CPU) and runs every cell as one task (harness.sweep.run.ray_cells). Module imports are done
before either clock starts (the Ray workers are warmed by one import task each); both passes
pay their per-robot start-up (fresh trajectory, libraries) inside the clock, the Ray pass once
per worker. Each cell also records its own CPU time, so the cores kept busy are measured
beside the wall-clock rates: on a shared machine the wall rates move with the others' load,
the CPU figures much less.

"all CPU" counts every process of the pass (the serial process; the Ray driver, GCS, raylet,
agents and workers), so "cells per CPU-min" is the rate the pass would reach with a CPU to
itself per busy core, and "cores busy" how many cores it actually got.

Target (issue #14): Ray's cells per minute >= 0.8 x (CPUs x the serial rate), here 2 CPUs.

    python -m benchmarks.sweep_throughput [--seeds 3] [--samples 1000] [--out FILE.json]

(as a module from the repository root: run as a script, benchmarks/identification.py would
shadow the identification package).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from harness.sweep.cell import run_cell  # noqa: E402
from harness.sweep.grid import parse_grid  # noqa: E402
from harness.sweep.run import ray_cells, ray_session  # noqa: E402

TARGET = 0.8  # of the ideal speed-up (one per CPU)


def _warm(ray, workers: int) -> None:
    """Start every worker and import the cell runner there (as this process already has)."""
    @ray.remote(num_cpus=1)
    def imported() -> int:
        import harness.sweep.cell  # noqa: F401

        time.sleep(0.5)  # keep the slot busy so every worker gets one
        return os.getpid()

    ray.get([imported.remote() for _ in range(workers)])


def tree_cpu(root: int | None = None) -> float:
    """CPU seconds (user + system) so far of this process and all its living descendants (Linux
    /proc; the local Ray's GCS, raylet, agents and workers descend from the driver)."""
    root = root or os.getpid()
    stats = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:  # ended meanwhile
                continue
            stats[int(entry)] = (int(fields[1]), (int(fields[11]) + int(fields[12])))  # ppid, ticks
    tree, grew = {root}, True
    while grew:
        new = {pid for pid, (ppid, _) in stats.items() if ppid in tree} - tree
        tree |= new
        grew = bool(new)
    return sum(stats[pid][1] for pid in tree if pid in stats) / os.sysconf("SC_CLK_TCK")


def _pass(name: str, results, wall: float, total_cpu: float) -> dict:
    cpu = sum(r.cpu_seconds for r in results)
    return {"pass": name, "cells": len(results), "wall_s": wall, "cells_per_min": len(results) / wall * 60,
            "cell_cpu_s": cpu, "all_cpu_s": total_cpu, "cores_busy": total_cpu / wall,
            "cell_share_of_cpu": cpu / total_cpu, "cells_per_cpu_min": len(results) / total_cpu * 60}


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", default="lynxmotion,double_pendulum")
    p.add_argument("--noise", default="0.02,0.05")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--methods", default="coupled,per-joint,oracle,stlsq,ssr")
    p.add_argument("--samples", default="1000")
    p.add_argument("--out", default=None, help="write the results as JSON")
    args = p.parse_args(argv)
    grid = parse_grid(args.robots, args.noise, args.seeds, args.methods, args.samples)
    cells, cpus = grid.cells(), os.cpu_count() or 1
    print(f"{len(cells)} cells ({args.robots}; noise {args.noise}; {args.seeds} seeds; "
          f"{args.methods}; {args.samples} samples), {cpus} CPUs; load average before: "
          f"{os.getloadavg()[0]:.2f}", flush=True)

    start, cpu = time.perf_counter(), tree_cpu()
    serial = [run_cell(c) for c in cells]
    passes = [_pass("serial (one process)", serial, time.perf_counter() - start, tree_cpu() - cpu)]
    print(f"serial done: {passes[0]['wall_s']:.1f} s", flush=True)

    with ray_session() as ray:
        tic = time.perf_counter()
        _warm(ray, cpus)
        warm_s = time.perf_counter() - tic
        start, cpu = time.perf_counter(), tree_cpu()
        parallel = list(ray_cells(ray, cells))
        passes.append(_pass(f"Ray ({cpus} worker slots)", parallel, time.perf_counter() - start,
                            tree_cpu() - cpu))
    same = {r.cell: r.errors for r in serial} == {r.cell: r.errors for r in parallel}
    ratio = passes[1]["cells_per_min"] / passes[0]["cells_per_min"]
    bar = TARGET * cpus
    # on an otherwise idle machine, if every core is kept busy: each pass at its CPU-time rate
    idle = cpus * passes[1]["cells_per_cpu_min"] / passes[0]["cells_per_cpu_min"]
    print("\n| pass | cells | wall s | cells/min | cells' CPU s | all CPU s | cores busy | "
          "cells' share of CPU | cells per CPU-min |")
    print("|---|---|---|---|---|---|---|---|---|")
    for x in passes:
        print(f"| {x['pass']} | {x['cells']} | {x['wall_s']:.1f} | {x['cells_per_min']:.1f} | "
              f"{x['cell_cpu_s']:.1f} | {x['all_cpu_s']:.1f} | {x['cores_busy']:.2f} | "
              f"{x['cell_share_of_cpu']:.3f} | {x['cells_per_cpu_min']:.1f} |")
    print(f"\nRay / serial cells per minute: {ratio:.2f} (target >= {TARGET} x {cpus} = {bar:.2f}: "
          f"{'met' if ratio >= bar else 'NOT met'}); from CPU time, on an otherwise idle machine with "
          f"every core kept busy: {idle:.2f}; Ray worker warm-up {warm_s:.1f} s (not in the "
          f"rate); identical errors in both passes: {same}; load average after: "
          f"{os.getloadavg()[0]:.2f}")
    results = {"passes": passes, "ratio": ratio, "ratio_cpu_time_estimate": idle, "cpus": cpus,
               "warm_up_s": warm_s,
               "acceptance": {f"ray_rate_at_least_{bar:.2f}x_serial": bool(ratio >= bar),
                              "identical_errors": same}}
    if args.out:
        from harness.io import write_json

        write_json(args.out, results)
    return results


if __name__ == "__main__":
    main(sys.argv[1:])
