"""Which robot `plan` plans: --robot, else the robot its MODEL.json records, else the
Lynxmotion (harness.robots.arm.resolve_arm); a model of another robot than --robot is
refused in one line, exit 2, no file."""

from __future__ import annotations

import json

import numpy as np

from harness.cli import main
from harness.robots.arm import Arm
from identification.kinematic_model import KinematicModel
from identification.model import model_to_dict

FAR = ["--obstacle-from", "5,5,5", "--obstacle-to", "5,5,6"]  # out of every arm's reach


def _nominal_model(robot: str, path) -> str:
    """A MODEL.json on robot's base atoms whose coefficients are its URDF's (the closed form
    written as `identify` writes a model, with its robot record)."""
    arm = Arm.of(robot)
    library = arm.library
    model = KinematicModel(library, library.fold @ arm.nominal.atom_parameters(),
                           np.zeros(arm.dof), "nominal")
    path.write_text(json.dumps(model_to_dict(model)))
    return str(path)


def test_a_models_robot_is_planned_without_robot(tmp_path, capsys):
    model = _nominal_model("double_pendulum", tmp_path / "MODEL.json")
    assert json.loads((tmp_path / "MODEL.json").read_text())["robot"]["name"] == "double_pendulum"
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", model, "--start", "0.2,0.1", "--goal",
                 "1.0,-0.5", *FAR, "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["robot"] == "double_pendulum" and np.asarray(plan["q"]).shape[1] == 2
    assert "note:" not in capsys.readouterr().err  # its obstacle given: no default-path note


def test_a_ur5_model_without_robot_is_read_on_the_ur5(tmp_path, capsys):
    """The UR5's model plans the UR5 (6 joints: 3 goal angles are the Lynxmotion's count)."""
    model = _nominal_model("ur5", tmp_path / "MODEL.json")
    out = tmp_path / "plan.json"
    assert main(["plan", "--model", model, "--goal", "0.1,0.2,0.3", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--goal must be 6" in err and len(err.splitlines()) == 1 and not out.exists()


def test_a_model_of_another_robot_than_robot_is_one_line_exit_2(tmp_path, capsys):
    model = _nominal_model("ur5", tmp_path / "MODEL.json")
    out = tmp_path / "plan.json"
    assert main(["plan", "--robot", "panda", "--model", model, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not out.exists()
    assert "ur5" in err and "panda" in err and "identified for robot" in err, err
