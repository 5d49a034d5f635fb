"""Several logs of one robot as one dataset: `--data A.npz,B.npz` and `--validate C.npz`.

Each run keeps its own derivative estimate (made when it was generated or ingested); the
runs are concatenated in the order given, which is what a static regression on (q, qd, qdd,
tau) needs: no time series crosses from one run to the next. Each run keeps its own sensor
offset too: identify is told which run each sample comes from (Runs.labels). A run without `tau_clean`
(a measured log) makes the whole set one: the scores are then against the measured torque.
Which robot the runs are of is the command's to check: Runs.records, each run's file and meta,
go to harness.robots.arm.resolve_arm, which refuses a run of another robot.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.data.dataset import load_arrays
from harness.errors import UserError

KEYS = ("q", "qd", "qdd", "tau")


@dataclass(frozen=True)
class Runs:
    """Concatenated arrays of several runs, each run's meta, file and number of samples."""

    arrays: dict[str, np.ndarray]
    metas: tuple[dict, ...]
    files: tuple[str, ...]
    lengths: tuple[int, ...]
    times: tuple = ()  # each run's `t` as read (None where absent): run_times checks it

    @property
    def samples(self) -> int:
        return len(self.arrays["q"])

    @property
    def records(self) -> list[tuple[str, dict]]:
        """(file, meta) of each run: resolve_arm's data."""
        return list(zip(self.files, self.metas, strict=True))

    @property
    def labels(self) -> np.ndarray:
        """(samples,) the index of the run each sample comes from (identify's runs)."""
        return np.repeat(np.arange(len(self.lengths)), self.lengths)


def split_files(spec: str, option: str) -> list[str]:
    """The comma-separated file names of an option; UserError if none is given."""
    files = [f.strip() for f in spec.split(",") if f.strip()]
    if not files:
        raise UserError(f"{option} names no file")
    return files


def load_runs(files: list[str]) -> Runs:
    """The runs at files, concatenated; UserError if their joints differ (their robot is
    checked by the caller's resolve_arm, on Runs.records)."""
    loaded = [load_arrays(f, KEYS, optional=("tau_clean", "t")) for f in files]
    dofs = {a["q"].shape[1] for a, _ in loaded}
    if len(dofs) > 1:
        raise UserError(f"the logs {', '.join(files)} have different joint counts "
                        f"({', '.join(str(a['q'].shape[1]) for a, _ in loaded)})")
    keys = KEYS + (("tau_clean",) if all("tau_clean" in a for a, _ in loaded) else ())
    arrays = {k: np.concatenate([a[k] for a, _ in loaded]) for k in keys}
    return Runs(arrays, tuple(m for _, m in loaded), tuple(str(Path(f)) for f in files),
                tuple(len(a["q"]) for a, _ in loaded), tuple(a.get("t") for a, _ in loaded))


def run_times(file, arrays: dict, meta: dict) -> np.ndarray:
    """A run's time stamps (s): its `t`, else its samples at the rate its meta records
    (default 200 Hz); UserError unless they are one per sample and increasing."""
    n = len(arrays["q"])
    if arrays.get("t") is None:
        return np.arange(n) / float(meta.get("rate", 200.0))
    t = np.asarray(arrays["t"], float).ravel()
    if len(t) != n:
        raise UserError(f"{file}: 't' has {len(t)} samples, 'q' {n}")
    if n > 1 and np.any(np.diff(t) <= 0):
        raise UserError(f"{file}: 't' must increase")
    return t


def join(train: Runs, validate: Runs) -> Runs:
    """Training runs then validation runs, as one set whose last part is the validation."""
    if train.arrays["q"].shape[1] != validate.arrays["q"].shape[1]:
        raise UserError(f"--validate logs have {validate.arrays['q'].shape[1]} joints, --data "
                        f"logs {train.arrays['q'].shape[1]}")
    keys = [k for k in train.arrays if k in validate.arrays]
    return Runs({k: np.concatenate([train.arrays[k], validate.arrays[k]]) for k in keys},
                train.metas + validate.metas, train.files + validate.files,
                train.lengths + validate.lengths, train.times + validate.times)
