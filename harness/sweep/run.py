"""Run a sweep's unfinished cells as Ray tasks and record each as it finishes.

By default a local Ray instance with one worker slot per CPU (`ray.init(num_cpus=os.cpu_count(),
include_dashboard=False)`, bound to the loopback address, usage statistics off, quiet logs);
with `address`, the cells run on that Ray cluster instead (the harness, identification and
model packages travel with the job; its nodes need the project's dependencies installed). A
process that has already initialized Ray (a library user, the tests) keeps its instance.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from harness.errors import UserError
from harness.sweep.cell import CellFailure, CellResult, run_cell
from harness.sweep.grid import Cell, Grid
from harness.sweep.progress import Progress
from harness.sweep.store import ResultsStore
from identification.regression.base import validation_mask

BLAS_ENV = {v: "1" for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}


@contextmanager
def ray_session(address: str | None = None):
    """Ray, initialized for the duration (unless the process already had it)."""
    import ray

    if ray.is_initialized():
        yield ray
        return
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # no reporting beyond this machine
    quiet = dict(logging_level=logging.ERROR, log_to_driver=False)
    if address:
        import harness
        import identification
        import models

        env = {"env_vars": BLAS_ENV, "py_modules": [harness, identification, models]}
        try:
            ray.init(address=address, runtime_env=env, **quiet)
        except (ConnectionError, ValueError) as exc:
            raise UserError(f"cannot join the Ray cluster at {address}: {exc}") from None
    else:
        for var, value in BLAS_ENV.items():  # local workers inherit the driver's environment
            os.environ.setdefault(var, value)
        ray.init(num_cpus=os.cpu_count(), include_dashboard=False, _node_ip_address="127.0.0.1",
                 **quiet)
    try:
        yield ray
    finally:
        ray.shutdown()


def ray_cells(ray, cells: Iterable[Cell]) -> Iterator[CellResult | CellFailure]:
    """Every cell as one Ray task (one CPU each); results in the order they finish."""
    task = ray.remote(num_cpus=1)(run_cell)
    pending = {task.remote(c): c for c in cells}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
        if ready:  # everything else already finished too, without waiting
            ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=0)
        for ref in ready:
            del pending[ref]
            yield ray.get(ref)


def _joints(grid: Grid) -> int:
    from harness.robots.registry import load_chain

    return max(load_chain(r).dof for r in grid.robots)


def check_samples(grid: Grid) -> None:
    """Every sample count must exceed the robot's library and, for the sparse methods and the
    peers (all but the oracle), hold one full validation block of their tuning."""
    from harness.sweep.cell import library

    mask = validation_mask(10**4)  # the tuning's default blocks
    first = int(np.argmax(mask))
    block = first + int(np.argmin(mask[first:]))  # samples up to the end of the first block
    for robot in grid.robots:
        need = len(library(robot)) + 1
        if min(grid.samples) < need:
            raise UserError(f"--samples {min(grid.samples)} is too few for robot {robot}: its "
                            f"library has {need - 1} columns, need at least {need} samples")
    if set(grid.methods) - {"oracle"} and min(grid.samples) < block:
        raise UserError(f"--samples {min(grid.samples)} is too few for the sparse methods: their "
                        f"tuning holds out blocks of the data, need at least {block} samples")


def run_sweep(grid: Grid, out: Path, address: str | None = None, progress_every: float = 10.0):
    """Run the cells of grid not yet in out/results.csv; returns (store, cells run here)."""
    check_samples(grid)
    store = ResultsStore(out / "results.csv", _joints(grid))
    todo = [c for c in grid.cells() if c not in store]
    progress = Progress(len(grid), len(grid) - len(todo), every=progress_every)
    if todo:
        with ray_session(address) as ray:
            for result in ray_cells(ray, todo):
                if isinstance(result, CellFailure):
                    raise UserError(f"cell {result.cell.label()}: {result.message}")
                store.append(result)
                progress.update()
    return store, len(todo)
