"""Checks and targets as the report counts them: a numpy boolean is a check like any other,
a target's gap is its shortfall in its own direction, an unmeasured target is neither met
nor missed; and the command line refuses to start without one of its command modules."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.identify.next_run import markdown as next_run_markdown
from harness.identify.next_run import rule_targets
from harness.report.results import Check, SectionResult, Target, check, distinct
from harness.report.writer import (
    SectionOutcome,
    failed_checks,
    headline_file,
    report_json,
    report_markdown,
    targets_markdown,
)


def test_numpy_booleans_are_checks_and_count():
    result = SectionResult("", checks=[check("a", np.bool_(False)), check("b", np.float64(1) > 0),
                                       Check("c", np.bool_(True))])
    outcome = SectionOutcome.of("s", result, 1.0)
    assert [c.passed for c in outcome.checks] == [False, True, True]
    assert all(type(c.passed) is bool for c in outcome.checks)
    assert failed_checks([outcome]) == ["s: a"]
    report = report_json([outcome], {}, Path("."))
    assert report["checks"] == {"total": 3, "failed": ["s: a"]} and report["ok"] is False


@pytest.mark.parametrize("measured, target, lower, met, gap", [
    (3.0, 2.0, True, False, 1.0), (1.0, 2.0, True, True, 0.0),
    (3.0, 5.0, False, False, 2.0), (6.0, 5.0, False, True, 0.0),
    (None, 5.0, True, None, None), (float("nan"), 5.0, False, None, None)])
def test_target_gap_and_met(measured, target, lower, met, gap):
    t = Target("t", measured, target, lower_is_better=lower)
    assert t.met is met and t.gap == gap


def test_a_missing_command_module_is_an_error(monkeypatch):
    import harness.cli as cli

    monkeypatch.setattr(cli, "COMMANDS", [*cli.COMMANDS, "nonexistent"])
    with pytest.raises(ModuleNotFoundError):
        cli.build_parser()


def _outcome(targets) -> SectionOutcome:
    return SectionOutcome.of("s", SectionResult("", checks=[check("c", True)], targets=targets), 1.0)


def test_the_top_line_counts_and_the_missed_targets_are_listed_below_it():
    """report.md's top line named every missed target in one sentence (about 700 characters
    on the bench); now it counts them, under 200 characters, and lists them below."""
    outcome = _outcome([Target("fast", 1.0, 2.0, "s"), Target("exact", 0.00304, 0.00276, "x"),
                        Target("unmeasured", None, 1.0)])
    lines = report_markdown([outcome], {"robot": "r"}, Path(".")).splitlines()
    top = lines[2]
    assert "all 1 checks hold" in top and "1 of 3 targets met" in top
    assert "1 missed, 1 not measured" in top and "exact" not in top
    assert "- missed: s: exact" in lines and "- not measured: s: unmeasured" in lines
    assert not any("fast" in line for line in lines[:lines.index("## Headline")])
    clean = report_markdown([_outcome([Target("fast", 1.0, 2.0, "s")])], {}, Path("."))
    assert "all 1 checks hold; 1 of 1 targets met." in clean.splitlines()[2]


def test_the_top_line_is_short_and_headline_md_under_40_lines_on_many_misses():
    long = "a target whose name is as long as the bench's, with its seeds and its judge " * 2
    many = [Target(f"{k} {long}", 2.0, 1.0) for k in range(60)]
    robot = "/a/very/long/path/" + "x" * 150 + "/tiago_pro.urdf"
    meta = {"robot": robot, "timing": {"elapsed_s": 347.0}}
    outcome = _outcome(many)
    top = report_markdown([outcome], meta, Path(".")).splitlines()[2]
    assert len(top) < 200 and "tiago_pro.urdf" in top and "0 of 60 targets met" in top
    headline = headline_file([outcome], meta)
    assert len(headline) < 40 and headline[0] == top
    listed = [line for line in headline if line.startswith("- missed: ")]
    assert headline[-1] == f"- ... and {60 - len(listed)} more (report.md)"


def test_the_gap_is_blank_where_met_and_figures_compared_read_apart():
    rows = targets_markdown([_outcome([Target("met", 1.0, 2.0, "x"),
                                       Target("close", 1.0504, 1.05, "x")])])
    met, close = (row.split(" | ") for row in rows[2:])
    assert met[4] == "" and met[5] == "yes |"  # no "0 x" on a met row
    assert close[2] == "1.0504 x" and close[3] == "<= 1.05 x"
    assert close[4] == "0.0004 x"
    assert distinct([0.00304, 0.00276, 0.003]) == ["0.00304", "0.00276", "0.003"]
    assert distinct([0.0030401, 0.0030402]) == ["0.0030401", "0.0030402"]
    assert distinct([1.0, 1.0]) == ["1", "1"]


def test_the_next_run_numbers_joints_from_1_in_json_and_markdown_alike():
    run = {"seed": 1, "errors": {"identified": [0.00304, 0.1], "least_squares": [0.00276, 0.2]},
           "rule_joints": [0, 1], "rule_holds_on": [1],
           "rule_joints_from_1": [1, 2], "rule_holds_on_from_1": [2]}
    table = next_run_markdown([run, {**run, "seed": 2}])
    assert table[-1] == "| 2 | 0.00304, 0.1 | 0.00276, 0.2 | [1, 2] | [2] |"
    target = rule_targets([dict(run, median_ratio_to_least_squares=1.0),
                           dict(run, seed=2, median_ratio_to_least_squares=1.0)])
    assert target[0].target == 4 and "counted over 2 seeds (1, 2)" in target[0].name
