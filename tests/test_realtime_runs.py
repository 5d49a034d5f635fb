"""The realtime_runs study's pieces (not its timings): the load it makes spins and is gone
after its block, even one that raised, and ends itself when the study dies; a scenario's
`plan` options give the scenario back; a run's summary reads the execution (its closest
sample recomputed from the segments); the runs' scores and targets on made-up runs; a run in
its own process that is refused or raises is a finding, not the study's end."""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from harness.commands import plan as plan_command
from harness.plan.fresh import plan_options
from harness.plan.options import config_from_options, scenario_from_options
from harness.robots.arm import Arm
from harness.robots.torque_models import read_model
from harness.studies.realtime_runs import load, runs, scores
from planning.config import Scenario
from planning.formulation.clearance import link_clearances
from planning.formulation.obstacle import SwayingObstacle
from planning.result import to_json


def _cpu_ticks(pid: int) -> int:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])  # utime + stime


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_the_load_spins_and_is_gone_after_a_block_that_raised():
    with pytest.raises(RuntimeError), load.busy(2) as pids:
        time.sleep(0.6)
        assert len(set(pids)) == 2 and all(_cpu_ticks(pid) > 0 for pid in pids)
        raise RuntimeError("a run failed")
    assert not any(_alive(pid) for pid in pids)  # killed and reaped


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_a_spinner_ends_itself_when_the_study_dies():
    """A study killed outright (no block left, no cleanup) leaves no spinner behind."""
    code = ("import os, sys\nfrom harness.studies.realtime_runs import load\n"
            "with load.busy(1) as pids:\n    print(pids[0], flush=True)\n    os._exit(0)\n")
    study = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True, cwd=Path(__file__).parents[1], timeout=60)
    pid = int(study.stdout.split()[0])
    try:
        deadline = time.monotonic() + 10
        while _spinning(pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _spinning(pid)
    finally:
        if _spinning(pid):
            os.kill(pid, 9)


def _spinning(pid: int) -> bool:
    """Whether pid runs (exited and not reaped yet: a zombie, state Z, does not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_a_scenarios_plan_options_give_it_back():
    arm = Arm.of("lynxmotion")
    obstacle = SwayingObstacle((0.1234567, -0.2, 0.25), (0.2, 0.31, 0.19), 2.0,
                               sway=(0.013, -0.02, 0.004), periods=1.37)
    scenario = Scenario((0.3, 1.1, -1.2), (-0.9, 0.7, -0.8), 2.0, obstacle)
    args = plan_command.parse(["--robot", "lynxmotion", "--model", "pinocchio",
                               *plan_options(scenario), "--out", "unused"])
    given = scenario_from_options(args, arm, config_from_options(args, arm))
    t = np.linspace(0.0, 2.0, 101)
    assert np.allclose(given.obstacle.position(t), obstacle.position(t), atol=1e-6)
    assert np.allclose(given.start, scenario.start) and np.allclose(given.goal, scenario.goal)


def test_a_runs_summary_reads_its_execution():
    """The smallest clearance and when: recomputed from the segment followed at each obstacle
    sample; the energy and the warm re-plans' CPU as PLAN.json has them."""
    args = plan_command.parse(["--robot", "lynxmotion", "--model", "pinocchio", "--samples",
                               "40", "--out", "unused"])
    config, scenario, _, _, result = plan_command.planned(args, Arm.of("lynxmotion"),
                                                          read_model("pinocchio"))
    found = runs.summary(result, config.threshold)
    execution = result.execution
    starts = [s.trajectory.t_begin for s in execution.segments]
    samples = scenario.obstacle.samples
    times = scenario.duration * np.arange(1, samples + 1) / samples
    closest = []
    for t in times:
        segment = execution.segments[np.searchsorted(starts, t, side="right") - 1]
        q = segment.trajectory.state(np.array([t]))[0]
        closest.append(link_clearances(config.geometry, q, scenario.obstacle.position(
            np.array([t]))).min())
    assert found["min_clearance_m"] == pytest.approx(min(closest), abs=1e-9)
    assert found["closest_t_s"] == pytest.approx(times[int(np.argmin(closest))])
    payload = to_json(result, scenario, config, "pinocchio")
    assert found["energy_J"] == payload["energy"] and found["replans"] == payload["replans"]
    assert found["replan_cpu_max_ms"] == max(payload["solve_cpu_ms"][1:])
    assert found["keeps_clearance"] and not found["refused"]


def _run(clearance, energy, refused=False):
    return {"min_clearance_m": clearance, "energy_J": energy, "refused": refused,
            "replan_cpu_max_ms": 5.0}


def test_scores_count_the_runs_by_the_threshold_and_its_2_mm():
    threshold = 0.08
    found = [_run(0.0815, 0.30), _run(0.0781, 0.31), _run(0.0779, 0.33, refused=True),
             _run(0.0800, 0.29), {"refused": True, "why": ["start inside"],
                                  "min_clearance_m": None}]
    row = scores.scored(found, threshold)
    kept = [0.30, 0.31, 0.29]  # the runs plan writes
    assert (row["runs"], row["refused"], row["kept"]) == (5, 2, 3)
    assert row["smallest_margin_m"] == pytest.approx(-0.0021)
    assert row["energy_J"]["median"] == pytest.approx(statistics.median(kept))
    assert row["energy_J"]["spread_pct"] == pytest.approx(
        100 * (max(kept) - min(kept)) / statistics.median(kept))
    other = scores.scored([_run(0.09, 0.5)], threshold)
    met = {t.name.split(":")[0] + t.name[-8:]: (t.measured, t.target, t.met)
           for t in scores.targets({"quiet": [row, other]}, "")}
    assert met == {"quiet - 2 mm)": (4, 6, False), "quiet refuses": (2, 0, False)}


def test_a_run_refused_or_raising_in_its_own_process_is_a_finding():
    raised = runs.run(("--robot", "no-such-arm", "--model", "pinocchio"))
    assert "error" in raised and "no-such-arm" in raised["error"]
    refused = runs.run(("--robot", "lynxmotion", "--model", "pinocchio", "--samples", "40",
                        "--goal", "0.1,3.0,-0.1", "--duration", "0.05"))
    assert refused["refused"] and refused["why"] and refused["min_clearance_m"] is None
