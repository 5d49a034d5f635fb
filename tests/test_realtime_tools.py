"""The realtime study's command-line tools (python -m harness.studies.realtime.<tool>) parse
their options and name them in --help: ways (the study per way in), oneshot (the optimizer
alone), anatomy (where a warm re-plan's time goes)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest


@pytest.mark.parametrize("tool, option", [("ways", "--ways"), ("oneshot", "--scenarios"),
                                          ("anatomy", "--split")])
def test_tool_help(tool, option):
    proc = subprocess.run([sys.executable, "-m", f"harness.studies.realtime.{tool}", "--help"],
                          capture_output=True, text=True, timeout=120,
                          cwd=Path(__file__).resolve().parents[1])
    assert proc.returncode == 0 and option in proc.stdout, proc.stderr
