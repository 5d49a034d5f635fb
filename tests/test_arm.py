"""The robot resolved once (issue #53): each robot file is parsed once per command, by one
module, and one rule decides which robot a command works on."""

from __future__ import annotations

import ast
import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import harness.robots.arm as arm_module
from harness.cli import main
from harness.errors import UserError
from harness.robots import files
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm

ROOT = Path(__file__).resolve().parents[1]
PARSERS = ("from_xml_path", "buildModelFromXML", "buildModelFromUrdf", "buildModelFromMJCF",
           "from_file")


@pytest.fixture
def parses(monkeypatch):
    """Every parse of a robot file, counted per (parser, file), each command from a fresh
    process's state (no Arm cached)."""
    counted: Counter = Counter()
    for name in ("parse_spec", "parse_pinocchio"):
        real = getattr(files, name)

        def counting(entry, *args, _real=real, _name=name, **kwargs):
            counted[(_name, str(entry.name), bool(args or kwargs))] += 1
            return _real(entry, *args, **kwargs)
        monkeypatch.setattr(files, name, counting)

    def fresh():
        arm_module._arm.cache_clear()
        counted.clear()
        return counted
    return fresh


def test_each_command_parses_the_robot_file_once(tmp_path, parses, capsys):
    data, model = tmp_path / "d.npz", tmp_path / "m.json"
    runs = {
        "generate": ["generate", "--robot", "ur5", "--samples", "600", "--seed", "3",
                     "--out", str(data)],
        "identify": ["identify", "--data", str(data), "--out", str(model)],
        "predict": ["predict", "--model", str(model), "--data", str(data),
                    "--out", str(tmp_path / "p.npz")],
        "export": ["export", "--model", str(model), "--format", "csv",
                   "--out", str(tmp_path / "m.csv")],
    }
    for command, argv in runs.items():
        counted = parses()
        assert main(argv) == 0, command
        assert counted and max(counted.values()) == 1, (command, counted)
        assert {robot for _, robot, _ in counted} == {"ur5"}, (command, counted)
    capsys.readouterr()


def test_only_the_files_module_parses_a_robot_file():
    """No module outside harness/robots/files.py calls a parser on a file (MuJoCo's and
    Pinocchio's readers of a path or of a robot's URDF text)."""
    found = []
    for path in (ROOT / "harness").rglob("*.py"):
        if path.name == "files.py" and path.parent.name == "robots":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in PARSERS:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.attr}")
    assert not found


def test_an_arm_is_built_once_per_robot_whatever_the_spelling(tmp_path, monkeypatch):
    urdf = Arm.of("ur5").entry.urdf
    monkeypatch.chdir(urdf.parent)
    assert Arm.of(urdf.name) is Arm.of(str(urdf)) is Arm.of(str(urdf.resolve()))
    assert Arm.of("ur5") is Arm.of("ur5") and Arm.of("ur5") is not Arm.of(str(urdf))
    # the registered UR5 and its URDF given by path are one robot's kinematics
    assert Arm.of("ur5").first_difference(Arm.of(str(urdf))) is None
    assert Arm.of("ur5").first_difference(Arm.of("panda")) == 0


def test_the_rule_given_then_model_then_data_then_default():
    ur5, panda = Arm.of("ur5"), Arm.of("panda")
    record = {"robot": "ur5", "dof": 6}
    assert resolve_arm(None) is Arm.of(DEFAULT_ROBOT)
    assert resolve_arm(None, data=[("d.npz", record)]) is ur5
    assert resolve_arm(None, model=("m.json", ur5.record), data=[("d.npz", record)]) is ur5
    assert resolve_arm("ur5", data=[("d.npz", record)]) is ur5
    with pytest.raises(UserError, match="d.npz records robot 'ur5'.*not 'panda'"):
        resolve_arm("panda", data=[("d.npz", record)])
    with pytest.raises(UserError, match="m.json was identified for robot"):
        resolve_arm("panda", model=("m.json", ur5.record))
    with pytest.raises(UserError, match="records robot 'panda'"):
        resolve_arm(None, model=("m.json", ur5.record), data=[("d.npz", {"robot": "panda"})])
    # a data's kinematics hash alone refuses too (its file is elsewhere)
    with pytest.raises(UserError, match="not 'panda'"):
        resolve_arm("panda", data=[("d.npz", {"robot": "/gone/ur5.urdf",
                                              "robot_hash": ur5.record["hash"]})])
    assert resolve_arm("ur5", data=[("d.npz", {"robot": "/gone/ur5.urdf"})]) is ur5
    with pytest.raises(UserError, match="pass --robot"):
        resolve_arm(None, data=[("d.npz", {"robot": "/gone/ur5.urdf"})])
    assert panda.dof == 7


def test_a_plan_of_another_robot_is_refused_in_one_line(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    rest = [[0.0] * 6] * 2
    plan.write_text(json.dumps({"robot": "ur5", "t": [0.0, 0.1], "q": rest, "qd": rest,
                                "qdd": rest, "obstacle": [[1.0, 1.0, 1.0]] * 2,
                                "threshold": 0.05}))
    assert main(["replay", "--plan", str(plan), "--robot", "panda",
                 "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "ur5" in err and "panda" in err
    assert not (tmp_path / "r.json").exists()


def test_the_models_an_arm_hands_out_agree():
    arm = Arm.of("ur5")
    assert arm.mujoco.nv == arm.pinocchio.nv == arm.dof == 6
    lower, upper = arm.position_limits
    np.testing.assert_allclose(lower, arm.pinocchio.lowerPositionLimit, atol=1e-9)
    np.testing.assert_allclose(upper, arm.pinocchio.upperPositionLimit, atol=1e-9)


def test_a_model_of_a_robot_given_by_its_file_finds_it_again(tmp_path, capsys):
    """identify on a user's URDF records the file, so export (and plan, predict) need no
    --robot: the README's own walk (it refused with 'pass --robot', the record held the
    file's stem only)."""
    urdf = str(Arm.of("ur5").entry.urdf)
    data, model = tmp_path / "d.npz", tmp_path / "m.json"
    assert main(["generate", "--robot", urdf, "--samples", "600", "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0
    assert json.loads(model.read_text())["robot"]["file"] == str(Path(urdf).resolve())
    assert main(["export", "--model", str(model), "--format", "csv",
                 "--out", str(tmp_path / "m.csv")]) == 0
    capsys.readouterr()
