"""What a user reads names no issue of this project's tracker, which a user cannot look up: the
module docstrings of the package and the texts of `study --list` and of every command's help."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from harness.cli import main

ROOT = Path(__file__).resolve().parents[1]
ISSUE = re.compile(r"[Ii]ssue #\d+|#\d+ item")


def _docstrings(path: Path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node)
            if doc:
                yield getattr(node, "name", path.name), doc


def test_no_docstring_names_an_issue_number():
    found = [f"{path.relative_to(ROOT)}:{name}"
             for package in ("harness", "identification", "planning")
             for path in sorted((ROOT / package).rglob("*.py"))
             for name, doc in _docstrings(path) if ISSUE.search(doc)]
    assert not found, found


def test_study_list_and_help_name_no_issue_number(capsys):
    assert main(["study", "--list"]) == 0
    for command in ("study", "closeloop", "identify", "plan", "predict", "bench"):
        try:
            main([command, "--help"])
        except SystemExit:
            pass
    out = capsys.readouterr().out
    assert "pushes" in out and not ISSUE.search(out), ISSUE.findall(out)
