"""Checks and targets as the report counts them: a numpy boolean is a check like any other,
a target's gap is its shortfall in its own direction, an unmeasured target is neither met
nor missed; and the command line refuses to start without one of its command modules."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.report.results import Check, SectionResult, Target, check
from harness.report.writer import SectionOutcome, failed_checks, report_json


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
