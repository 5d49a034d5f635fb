"""`torquebench bench` assembly with stand-in sections: data flow, failures, report files."""

from __future__ import annotations

import json
import sys
import types

import numpy as np
import pytest

from harness.cli import main
from tests.test_replay import quintic_plan

SECTION = "harness.sections."


def _module(name: str, run) -> types.ModuleType:
    module = types.ModuleType(SECTION + name)
    module.run = run
    return module


@pytest.fixture
def sections(monkeypatch):
    """Install stand-in sections; returns the dict of calls each received."""
    calls: dict[str, dict] = {}
    model = object()

    def identification(out_dir, quick=False):
        calls["identification"] = {"quick": quick}
        return {"markdown": "identified", "model": model,
                "results": {"heldout_rel_rmse": [0.01, 0.002, 0.003], "oracle_rel_rmse": 0.002},
                "figures": []}

    def planning(out_dir, quick=False, identified_model=None):
        calls["planning"] = {"model_passed": identified_model is model}
        closed = {**quintic_plan(), "energy": 0.4793, "solve_ms": [700.0, 90.0, 110.0],
                  "replans": 2, "min_clearance": 0.05}
        slower = dict(quintic_plan(duration=2.2), energy=0.45, solve_ms=[800.0], replans=0)
        return {"markdown": "planned", "results": {}, "figures": [],
                "plans": {"pinocchio": closed, "identified": slower}}

    def closeloop(out_dir, quick=False):
        raise RuntimeError("residual analysis diverged\nsecond line")

    def real_data(out_dir, quick=False):  # the real log's section has its own tests
        return {"markdown": "real", "results": {"acceptance": {"stand_in": True}}, "figures": []}

    for name, run in (("identification", identification), ("planning", planning),
                      ("closeloop", closeloop), ("real_data", real_data)):
        monkeypatch.setitem(sys.modules, SECTION + name, _module(name, run))
    return calls


def test_bench_feeds_sections_records_failure_and_exits_nonzero(tmp_path, sections, capsys):
    out = tmp_path / "bench"
    assert main(["bench", "--out", str(out), "--quick"]) == 1
    err = capsys.readouterr().err
    assert "closeloop: FAILED" in err and "RuntimeError: residual analysis diverged" in err
    assert sections["planning"]["model_passed"] and sections["identification"]["quick"]

    report = json.loads((out / "report.json").read_text())
    assert report["ok"] is False
    assert report["sections"]["closeloop"]["status"] == "failed"
    assert report["sections"]["closeloop"]["error"] == "RuntimeError: residual analysis diverged"
    replay = report["sections"]["replay"]["results"]["plans"]
    assert set(replay) == {"pinocchio", "identified"}
    assert replay["pinocchio"]["acceptance"]["tracking_rms_le_1mrad"]
    # The identified plan claimed 0.45 J but needs ~0.44 J over 2.2 s: energy check is real.
    ident = replay["identified"]
    assert ident["energy_planned"] == 0.45 and ident["energy"] != pytest.approx(0.45, rel=1e-3)

    head = report["headline"]
    assert head["planning"]["pinocchio.replan_ms_median"] == 100.0
    assert head["identification"]["oracle_rel_rmse"] == 0.002
    ratio = head["replay"]["energy_ratio_identified_over_closed_form_replayed"]
    assert ratio == pytest.approx(replay["identified"]["energy"] / replay["pinocchio"]["energy"])

    md = (out / "report.md").read_text()
    assert "**FAILED**" in md and "figures/replay_power.png" in md
    assert (out / "headline.md").read_text().startswith("| section | quantity | value |")
    for fig in report["sections"]["replay"]["figures"]:
        assert (out / "figures").is_dir() and fig.endswith(".png")
        with open(fig, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_missing_section_is_reported_not_failed(tmp_path, monkeypatch, capsys):
    for name in ("identification", "planning", "closeloop"):
        monkeypatch.setitem(sys.modules, SECTION + name, None)  # import raises ImportError
    monkeypatch.setattr("harness.commands.bench.load_section",
                        lambda name: None if name != "replay" else sys.modules[SECTION + "replay"])
    import harness.sections.replay  # noqa: F401  (ensure loaded)

    out = tmp_path / "bench"
    assert main(["bench", "--out", str(out), "--no-video"]) == 0
    md = (out / "report.md").read_text()
    assert md.count("Section not available yet") == 5  # with arm_identification, real_data
    assert "No plans to replay" in md
    assert json.loads((out / "report.json").read_text())["ok"] is True


def test_report_json_has_no_nan(tmp_path):
    from harness.report.writer import SectionOutcome, write_report

    outcome = SectionOutcome("x", "ok", results={"a": float("nan"), "b": np.arange(2)})
    payload = write_report(tmp_path, [outcome], {}, {"robot": "r"})
    assert payload["sections"]["x"]["results"] == {"a": None, "b": [0, 1]}


def test_readme_sections_are_replaced_in_place_and_idempotent(tmp_path):
    from harness.report.readme import update_readme
    from harness.report.writer import SectionOutcome, write_report

    outcome = SectionOutcome("replay", "ok")
    write_report(tmp_path, [outcome], {"replay": {"a.energy_replayed_J": 0.5, "other": 1.5}},
                 {"robot": "r"})
    readme = tmp_path / "README.md"
    readme.write_text("# T\n\n## Latest benchmark\n\nold table\n\n## Commands\n\nkeep me\n")
    update_readme(tmp_path, readme)
    first = readme.read_text()
    assert "old table" not in first and "| replay | a.energy_replayed_J | 0.5 |" in first
    assert "other" not in first  # only the key numbers go into the README
    assert first.index("## Latest benchmark") < first.index("## Commands") < first.index(
        "## Reading the report")
    assert "keep me" in first
    update_readme(tmp_path, readme)
    assert readme.read_text() == first


def test_identification_headline_and_section_titles(tmp_path):
    from harness.report.headline import identification_numbers
    from harness.report.writer import SectionOutcome, report_markdown

    levels = {"0.05": {"joints": [{"rel": 0.004, "oracle": 0.003}] * 3}}
    numbers = identification_numbers({"levels": levels})
    assert numbers["noise 5 %: sparse rel err"] == [0.004] * 3
    outcome = SectionOutcome("identification", "ok", markdown="## Own title\n\nbody")
    md = report_markdown([outcome], {}, {"robot": "r"}, tmp_path)
    assert "## Own title" in md and md.count("## ") == 2  # headline + the section's own title
