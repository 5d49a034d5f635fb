"""`torquebench bench` on a reduced real run (no stand-in sections): report files, headline,
exit status on a failed acceptance check, determinism apart from timings, and interrupts
(SIGINT, SIGKILL) leaving every result file complete or absent.

The reduced bench is `--quick --sections REDUCED`: a real section of the default robot with
acceptance checks, small enough to run several times here; the tests select it by name, so
sections added later do not change what they run.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.commands.bench import Progress, run_section
from harness.report.headline import MAX_ROWS, headline, headline_markdown
from tests.result_files import incomplete_files, interrupt

REDUCED = "arm_identification"
ARGS = ["bench", "--quick", "--no-video", "--sections", REDUCED]
# A key holding a timing says so: seconds, *_s, *_ms, "... s", timing/elapsed/started.
TIMING_KEY = re.compile(r"(seconds|timing|elapsed|started|(^|[_ ])m?s\b|_ms\b|_ms_|cpu_)", re.I)


@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    """One reduced real bench, in process: (exit status, output folder, stderr)."""
    out = tmp_path_factory.mktemp("bench") / "out"
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main([*ARGS, "--out", str(out)])
    return code, out, err.getvalue()


def test_reduced_bench_writes_complete_report(reduced):
    code, out, err = reduced
    report = json.loads((out / "report.json").read_text())
    assert code == 0 and report["ok"] and "report:" in err
    assert report["sections"][REDUCED]["status"] == "ok" and list(report["sections"]) == [REDUCED]
    assert report["command"] == "torquebench bench --quick --sections arm_identification --no-video"
    assert report["machine"]["cores"] >= 1 and report["timing"]["elapsed_s"] > 0
    assert incomplete_files(out) == ([], [])
    # the acceptance count is every boolean under an 'acceptance*' dict of the results
    results = report["sections"][REDUCED]["results"]
    expected = sum(isinstance(v, bool) for v in results["acceptance"].values())
    assert report["headline"]["acceptance"] == {"total": expected, "passed": expected,
                                                "failed": []}
    rows = report["headline"]["rows"]
    assert 0 < len(rows) <= MAX_ROWS and rows[-1]["measured"] == f"{expected} of {expected}"
    assert (out / "headline.md").read_text() == headline_markdown(report["headline"]) + "\n"
    md = (out / "report.md").read_text()
    assert f"all {expected} acceptance checks passed" in md and "## Headline" in md


def test_failed_acceptance_check_exits_3_naming_it(tmp_path, monkeypatch, capsys):
    """The real section under a bar it cannot meet: the report is written, the exit status
    is 3 and stderr names the failed check."""
    import harness.sections.arm_identification as section

    monkeypatch.setattr(section, "EXACT", 0.0)  # noise-free error must be exactly zero
    out = tmp_path / "out"
    assert main([*ARGS, "--out", str(out)]) == 3
    err = capsys.readouterr().err
    assert "bench FAILED acceptance: 1 of" in err and f"{REDUCED}: acceptance.noise_free_exact" in err
    report = json.loads((out / "report.json").read_text())
    assert report["acceptance_failed"] == [f"{REDUCED}: acceptance.noise_free_exact"]
    assert "**1 of" in (out / "report.md").read_text()  # the status line says it too


def test_a_section_that_raises_is_recorded_as_failed(tmp_path, capsys):
    """The real replay section on a plan without time stamps: failed, with its error line."""
    outcome, raw = run_section("replay", Progress(), tmp_path, True,
                               plans={"broken": {"q": [[0.0, 0.0, 0.0]]}}, video=False)
    assert outcome.status == "failed" and raw == {}
    assert outcome.error == "UserError: plan is missing field(s): t, qd, qdd, obstacle, threshold"
    assert "replay: FAILED" in capsys.readouterr().err


def test_unknown_section_is_one_line_exit_2(tmp_path, capsys):
    assert main(["bench", "--sections", "planning,nonsense", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "unknown section(s) nonsense" in err
    assert not (tmp_path / "o").exists()


def _without_timings(tree):
    if isinstance(tree, dict):
        return {k: _without_timings(v) for k, v in tree.items() if not TIMING_KEY.search(str(k))}
    if isinstance(tree, list):
        return [_without_timings(v) for v in tree]
    return tree


def test_two_runs_write_the_same_report_apart_from_timings(reduced, tmp_path):
    """The second run in a fresh process: report.json equal once the timing keys are gone, and
    no timing hides in a text value (every text equal, not only the numbers)."""
    _, first, _ = reduced
    second = tmp_path / "second"
    env_path = str(Path(__file__).resolve().parents[1])
    subprocess.run([sys.executable, "-m", "harness", *ARGS, "--out", str(second)], check=True,
                   capture_output=True, env={**dict(os.environ), "PYTHONPATH": env_path})
    a, b = (json.loads((d / "report.json").read_text()) for d in (first, second))
    assert _without_timings(a) == _without_timings(b)
    timings = [k for k in _keys(a) if TIMING_KEY.search(k)]
    assert "seconds" in timings and "elapsed_s" in timings  # the timings exist, under their names


def _keys(tree):
    if isinstance(tree, dict):
        for k, v in tree.items():
            yield str(k)
            yield from _keys(v)
    elif isinstance(tree, list):
        for v in tree:
            yield from _keys(v)


@pytest.mark.parametrize("sig, when", [
    (signal.SIGKILL, 1.0),  # while importing
    (signal.SIGKILL, f"{REDUCED}: started"),  # inside the section
    (signal.SIGKILL, f"{REDUCED}: done in"),  # while the report files are written
    (signal.SIGINT, f"{REDUCED}: started"),
    (signal.SIGINT, f"{REDUCED}: done in"),
])
def test_interrupted_bench_leaves_complete_files_or_none(tmp_path, sig, when):
    out = tmp_path / "out"
    code, err = interrupt([*ARGS, "--out", str(out)], sig, when)
    bad, temporaries = incomplete_files(out) if out.exists() else ([], [])
    assert not bad, bad
    if sig == signal.SIGINT and code is not None:
        assert code == 130 and err.strip().splitlines()[-1] == "torquebench bench: interrupted"
        assert not temporaries  # SIGINT unwinds: atomic_write removes its temporary
    report = out / "report.json"
    if report.exists():  # complete: all three report files were written
        assert json.loads(report.read_text())["sections"][REDUCED]["status"] == "ok"


def test_atomic_write_killed_mid_write_leaves_target_absent(tmp_path):
    """SIGKILL while harness.io.write_json writes a large payload: the target is absent (or,
    had the rename happened, complete) and only a hidden temporary remains."""
    target = tmp_path / "big.json"
    code = ("import harness.io as io\n"
            f"io.write_json({str(target)!r}, {{'x': [i * 0.5 for i in range(3_000_000)]}})\n")
    proc = subprocess.Popen([sys.executable, "-c", code], env={
        **dict(os.environ), "PYTHONPATH": str(Path(__file__).resolve().parents[1])})
    for _ in range(400):  # wait for the temporary to appear, then kill mid-write
        if any(p.name.startswith(".big.json.") for p in tmp_path.iterdir()):
            break
        time.sleep(0.02)
    proc.kill()
    proc.wait()
    bad, temporaries = incomplete_files(tmp_path)
    assert not bad and (not target.exists() or json.loads(target.read_text()))
    assert all(Path(t).name.startswith(".big.json.") for t in temporaries)


def test_headline_rows_from_section_results():
    """The rows are computed from the results given: ratios, percentages, the threshold."""
    levels = {"0.05": {"joints": [{"rel": 0.004, "oracle": 0.002}, {"rel": 0.001, "oracle": 0.002}]}}
    plans = {"p": {"energy": 0.5, "min_clearance": 0.0795, "threshold": 0.07},
             "i": {"energy": 0.51, "min_clearance": 0.081, "threshold": 0.07}}
    results = {
        "identification": {"levels": levels, "acceptance_5pct": {"a": True, "b": False}},
        "planning": {"paper": {"identified": {"energy_pinocchio_J": 0.49},
                               "pinocchio": {"energy_pinocchio_J": 0.5}}},
        "replay": {"plans": plans, "comparison": {"identified": "i", "closed_form": "p",
                                                  "energy_ratio_replayed": 1.02}},
    }
    h = headline(results)
    text = {r["question"].split(":")[0]: r["measured"] for r in h["rows"]}
    assert h["rows"][1]["numbers"]["ratio"] == [2.0, 0.5]
    assert "0.400 %, 0.100 %" in h["rows"][0]["measured"]
    assert "(-2.000 %)" in text["Paper scenario"]
    assert text["Replayed"] == "81.0 / 79.5 mm (threshold 70 mm)"
    assert h["acceptance"] == {"total": 2, "passed": 1, "failed": ["identification: acceptance_5pct.b"]}
    assert h["rows"][-1]["measured"].startswith("1 of 2") and len(h["rows"]) <= MAX_ROWS
    assert np.isclose(h["rows"][2]["numbers"]["identified_J"], 0.49)


def test_readme_latest_benchmark_is_labelled_and_idempotent(reduced, tmp_path):
    from harness.report.readme import update_readme

    _, out, _ = reduced
    readme = tmp_path / "README.md"
    readme.write_text("# T\n\n## Latest benchmark\n\nold table\n\n## Commands\n\nkeep me\n")
    update_readme(out, readme)
    first = readme.read_text()
    report = json.loads((out / "report.json").read_text())
    assert "old table" not in first and "keep me" in first
    assert headline_markdown(report["headline"]) in first
    assert report["machine"]["cpu"] in first and report["command"] in first
    assert report["timing"]["started_utc"] in first
    update_readme(out, readme)
    assert readme.read_text() == first
