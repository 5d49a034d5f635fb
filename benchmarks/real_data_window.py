"""The derivative window on the real Panda log, measured through the torque.

`ingest` chooses the Savitzky-Golay window for qdd from the log's spectrum (predicted
error of the acceleration itself). Here the least-squares reference of the log's README
(rigid-body atoms + viscous, Coulomb, offset per joint; harness.sections.real_data.models)
is fitted on the first 75 % and scored on the last 25 % against the measured torque with
qdd from each window, so the window the data chose can be compared with the one the torque
would have preferred (which ingestion cannot know without a model). Also printed: how
coherent each joint's logged velocity is with its torque above the excitation's band.

    python -m benchmarks.real_data_window [WINDOW ...]   (from the checkout)
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.signal import coherence  # noqa: E402

from harness.data.ingest import ingest  # noqa: E402
from harness.sections.real_data.models import least_squares  # noqa: E402
from harness.sections.real_data.section import HOLDOUT, LOG, RATE, ROBOT  # noqa: E402
from identification.metrics import rel_error  # noqa: E402


def main(windows: list[int | None]) -> None:
    print("window (samples)  held-out rel. error per joint             median")
    for window in windows:
        data = ingest(LOG / "panda_gaz2019.csv.gz", 7, ROBOT, RATE, window)
        a = data.arrays
        split = int(round(len(a["q"]) * (1 - HOLDOUT)))
        tau = least_squares(ROBOT, a["q"], a["qd"], a["qdd"], a["tau"], split)
        e = rel_error(tau[split:], a["tau"][split:])
        label = f"{data.meta['derivatives']['window_samples']}" + (" (chosen)" if window is None
                                                                    else "")
        print(f"{label:>16}  {', '.join(f'{x:.3f}' for x in e)}  {np.median(e):.3f}")


def coherence_band(lo: float = 1.0, hi: float = 60.0) -> None:
    """Median magnitude-squared coherence of each joint's logged velocity with its torque
    over lo..hi Hz (resampled log, first differences): motion the torque responds to, not
    sensor noise, where it is high."""
    data = ingest(LOG / "panda_gaz2019.csv.gz", 7, ROBOT)
    a, rate = data.arrays, data.meta["resampling"]["rate_hz"]
    f, c = coherence(np.diff(a["qd"], axis=0), np.diff(a["tau"], axis=0), fs=rate,
                     nperseg=2048, axis=0)
    band = (f >= lo) & (f <= hi)
    print(f"median coherence of qd_j with tau_j over {lo:g}-{hi:g} Hz: "
          + ", ".join(f"{x:.2f}" for x in np.median(c[band], axis=0)))


if __name__ == "__main__":
    coherence_band()
    main([int(w) for w in sys.argv[1:]] or [51, 101, 201, 301, 501, None, 1201])
