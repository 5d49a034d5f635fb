"""Run a sweep's unfinished cells as Ray tasks and record each as it finishes.

By default a new local Ray instance with one worker slot per CPU (`ray.init(address="local",
num_cpus=os.cpu_count(), include_dashboard=False)`, bound to the loopback address, usage
statistics off, quiet logs, one BLAS thread per worker);
with `address`, the cells run on that Ray cluster instead (the harness, identification and
model packages travel with the job; its nodes need the project's dependencies installed). A
process that has already initialized Ray (a library user, the tests) keeps its instance.
"""

from __future__ import annotations

import itertools
import logging
import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from harness.errors import UserError
from harness.robots.arm import Arm
from harness.sweep.cell import CellFailure, CellResult, run_cell
from harness.sweep.grid import Cell, Grid
from harness.sweep.progress import Progress
from harness.sweep.store import ResultsStore, read
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
        # "local": always a new instance, never a cluster `ray start` left running on this machine
        ray.init(address="local", num_cpus=os.cpu_count(), include_dashboard=False,
                 _node_ip_address="127.0.0.1", **quiet)
    try:
        yield ray
    finally:
        ray.shutdown()


def ray_cells(ray, cells: Iterable[Cell], window: int | None = None,
              references: dict[str, str] | None = None) -> Iterator[CellResult | CellFailure]:
    """Every cell as one Ray task (one CPU each); results in the order they finish.

    At most `window` tasks are in flight (default 4 per CPU of the cluster, at least 16), the
    next cells submitted as results come back: the driver's bookkeeping stays small however
    large the grid, and the cells run in grid order (seeds outermost). references: each cell
    robot's Arm.reference, the string a worker builds its Arm from (default: the cell's robot)."""
    task = ray.remote(num_cpus=1)(run_cell)
    window = window or max(16, 4 * int(ray.cluster_resources().get("CPU", 1)))
    todo, pending, references = iter(cells), {}, references or {}
    while True:
        for cell in itertools.islice(todo, window - len(pending)):
            pending[task.remote(cell, references.get(cell.robot))] = cell
        if not pending:
            return
        ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
        if ready:  # everything else already finished too, without waiting
            ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=0)
        for ref in ready:
            del pending[ref]
            yield ray.get(ref)


def check_samples(grid: Grid) -> None:
    """Every sample count must exceed the robot's library and, for the sparse methods and the
    peers (all but the oracle), hold one full validation block of their tuning."""
    from harness.sweep.cell import library

    mask = validation_mask(10**4)  # the tuning's default blocks
    first = int(np.argmax(mask))
    block = first + int(np.argmin(mask[first:]))  # samples up to the end of the first block
    for robot in grid.robots:
        need = len(library(Arm.of(robot))) + 1
        if min(grid.samples) < need:
            raise UserError(f"--samples {min(grid.samples)} is too few for robot {robot}: its "
                            f"library has {need - 1} columns, need at least {need} samples")
    if set(grid.methods) - {"oracle"} and min(grid.samples) < block:
        raise UserError(f"--samples {min(grid.samples)} is too few for the sparse methods: their "
                        f"tuning holds out blocks of the data, need at least {block} samples")


def run_sweep(grid: Grid, out: Path, address: str | None = None, progress_every: float = 10.0):
    """Run the cells of grid not yet in out/results.csv; returns (store, cells run here).

    Nothing is written before the cells can run (bad input, an unreachable cluster: no file)."""
    arms = {r: Arm.of(r) for r in grid.robots}  # each robot resolved once, here
    check_samples(grid)
    joints, path = max(a.dof for a in arms.values()), out / "results.csv"
    if path.is_dir():
        raise UserError(f"{path} is a directory")
    finished = read(path)[0]
    todo = [c for c in grid.cells() if c.key not in finished]
    progress = Progress(len(grid), len(grid) - len(todo), every=progress_every)
    if not todo:
        return ResultsStore(path, joints), 0
    with ray_session(address) as ray:
        store = ResultsStore(path, joints)
        references = {r: a.reference for r, a in arms.items()}  # strings cross to the workers
        for result in ray_cells(ray, todo, references=references):
            if isinstance(result, CellFailure):
                raise UserError(f"cell {result.cell.label()}: {result.message}")
            store.append(result)
            progress.update()
    return store, len(todo)
