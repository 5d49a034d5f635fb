"""A sweep killed half-way (SIGKILL of the sweep process, no chance to clean up) resumes where
it stopped: every row written before the kill is kept as it was, only the missing cells run.
Slow (two local Ray start-ups in subprocesses): run with `pytest -m slow`."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["--robots", "lynxmotion,double_pendulum", "--noise", "0,0.05", "--seeds", "3",
        "--methods", "coupled,oracle", "--samples", "300"]
TOTAL = 2 * 2 * 3 * 2


def _rows_written(path: Path) -> int:
    return max(path.read_bytes().count(b"\n") - 1, 0) if path.exists() else 0


@pytest.mark.slow
def test_sigkilled_sweep_resumes_losing_no_finished_cell(tmp_path):
    out = tmp_path / "sweep"
    cmd = [sys.executable, "-m", "harness", "sweep", *ARGS, "--out", str(out)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 600
        while _rows_written(out / "results.csv") < 5:
            assert proc.poll() is None and time.monotonic() < deadline, "sweep ended before the kill"
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    finally:
        try:  # the helper processes its local Ray left in its process group
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    text = (out / "results.csv").read_text()
    kept = text[: text.rfind("\n") + 1].splitlines(keepends=True)  # a torn last line is not kept
    assert 5 <= len(kept) - 1 < TOTAL
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    assert f"{TOTAL - (len(kept) - 1)} cells computed" in done.stdout
    after = (out / "results.csv").read_text().splitlines(keepends=True)
    assert after[: len(kept)] == kept and len(after) == TOTAL + 1
    keys = {(r["robot"], r["noise"], r["seed"], r["method"]) for r in csv.DictReader(after)}
    assert len(keys) == TOTAL
