"""Every study runs at its smoke-test size (`torquebench study NAME --quick`): exit 0, a
complete report with the study's section, and its targets well formed; `--list` names them
all; an unknown study is one line and exit 2."""

from __future__ import annotations

import json

import pytest

from harness.cli import main
from harness.studies import STUDIES
from tests.result_files import incomplete_files


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STUDIES))
def test_study_smoke(tmp_path, name, capsys):
    out = tmp_path / name
    assert main(["study", name, "--quick", "--no-video", "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    section = report["sections"][name]
    assert section["status"] == "ok" and report["ok"] and report["study"] == name
    assert section["results"] and (out / "report.md").read_text().count(f"## {name}") == 1
    for target in section["targets"]:
        assert {"measured", "target", "gap", "met"} <= target.keys()
    assert incomplete_files(out) == ([], [])
    assert f"study {name}" in report["command"]


def test_study_list_names_every_study(capsys):
    assert main(["study", "--list"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{name}:" in printed for name in STUDIES)


def test_unknown_study_is_one_line_exit_2(tmp_path, capsys):
    assert main(["study", "nonsense", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "unknown study 'nonsense'" in err
    assert not (tmp_path / "o").exists()
