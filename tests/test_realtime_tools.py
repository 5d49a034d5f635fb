"""The realtime study's command-line tools (python -m harness.studies.realtime.<tool>) parse
their options and name them in --help: ways (the study per way in), oneshot (the optimizer
alone), anatomy (where a warm re-plan's time goes)."""

from __future__ import annotations

import runpy
import sys

import pytest


@pytest.mark.parametrize("tool, option", [("ways", "--ways"), ("oneshot", "--scenarios"),
                                          ("anatomy", "--split")])
def test_tool_help(tool, option, monkeypatch, capsys):
    """`python -m harness.studies.realtime.TOOL --help`, run as that command runs the module
    (as __main__), in this process."""
    monkeypatch.setattr(sys, "argv", [f"{tool}.py", "--help"])
    with pytest.raises(SystemExit) as exit_:
        runpy.run_module(f"harness.studies.realtime.{tool}", run_name="__main__",
                         alter_sys=True)
    assert exit_.value.code == 0 and option in capsys.readouterr().out
