"""`torquebench replay`: REPLAY.json on good input, one-line errors and no file on bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from tests.test_replay import quintic_plan


def _write(path, payload):
    path.write_text(json.dumps(payload))
    return path


def test_replay_writes_contract_fields(tmp_path):
    plan = _write(tmp_path / "plan.json", {**quintic_plan(), "energy": 0.48})
    out = tmp_path / "replay.json"
    assert main(["replay", "--plan", str(plan), "--out", str(out)]) == 0
    result = json.loads(out.read_text())
    for key in ("energy", "min_clearance", "tracking_rms", "surface_clearance", "energy_planned"):
        assert np.isfinite(result[key])
    assert result["energy_planned"] == 0.48


def _bad_plans():
    good = quintic_plan()
    out_of_limits = dict(good, q=(np.array(good["q"]) + [0.0, 0.0, 1.0]).tolist())
    nan = dict(good, qd=[[float("nan")] * 3] + good["qd"][1:])
    short = dict(good, qdd=good["qdd"][:-1])
    backwards = dict(good, t=good["t"][::-1])
    squeezed = dict(good, t=[0.0, 1.78e-196, *good["t"][2:]])  # found by hypothesis
    return {
        "missing": ({k: v for k, v in good.items() if k not in ("qd", "obstacle")},
                    "missing field(s): qd, obstacle"),
        "limits": (out_of_limits, "limits of joint 3"),
        "nan": (nan, "'qd' contains NaN"),
        "short": (short, "'qdd' has 199 samples"),
        "backwards": (backwards, "must be increasing"),
        "squeezed": (squeezed, "1.78e-196 s apart"),
        "not-object": ([1, 2, 3], "JSON object"),
    }


@pytest.mark.parametrize("case", sorted(_bad_plans()))
def test_bad_plan_is_one_line_exit_2_and_no_file(tmp_path, capsys, case):
    payload, message = _bad_plans()[case]
    plan = _write(tmp_path / "plan.json", payload)
    out = tmp_path / "replay.json"
    assert main(["replay", "--plan", str(plan), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [plan]


def test_unreadable_plan_and_plant(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    plan.write_text("{not json")
    assert main(["replay", "--plan", str(plan), "--out", str(tmp_path / "r.json")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    _write(plan, quintic_plan())
    args = ["replay", "--plan", str(plan), "--plant", str(tmp_path / "no.xml"),
            "--out", str(tmp_path / "r.json")]
    assert main(args) == 2
    assert "plant file not found" in capsys.readouterr().err


def _rendering_works() -> bool:
    """Can this process make an offscreen OpenGL context (MUJOCO_GL, egl under make test)?"""
    import mujoco

    from harness.replay.video import RENDER_ERRORS

    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
    try:
        mujoco.Renderer(model, 32, 32).close()
    except RENDER_ERRORS:
        return False
    return True


def test_video_is_written_where_rendering_works(tmp_path, capsys):
    """Where OpenGL rendering works the replay writes a complete mp4 with one frame per 1/FPS s
    of the plan (decoded back by ffmpeg); elsewhere the video asked for is an error."""
    import imageio_ffmpeg

    from harness.replay.video import FPS
    from tests.result_files import CHECKS

    duration = 0.5
    plan = _write(tmp_path / "plan.json", quintic_plan(samples=50, duration=duration))
    video = tmp_path / "replay.mp4"
    args = ["replay", "--plan", str(plan), "--out", str(tmp_path / "r.json"), "--video", str(video)]
    if not _rendering_works():
        assert main(args) == 2 and not video.exists()
        return
    assert main(args) == 0
    assert video.exists(), capsys.readouterr().err
    CHECKS[".mp4"](video)  # boxes tile the file, moov and mdat present
    reader = imageio_ffmpeg.read_frames(str(video))
    meta = next(reader)
    frames = sum(1 for _ in reader)
    assert meta["size"][0] > 100 and frames == int(duration * FPS) + 1


@pytest.mark.parametrize("error", [RuntimeError("gladLoadGL error"), OSError("libEGL.so.1")])
def test_a_video_that_cannot_be_rendered_is_one_line_exit_2_nothing_written(
        tmp_path, capsys, monkeypatch, error):
    """The renderer fails (no GL context): `replay --video` says so in one line and exits 2
    before writing REPLAY.json (it exited 0 without the video before)."""
    import mujoco

    def broken(*args, **kwargs):
        raise error

    monkeypatch.setattr(mujoco, "Renderer", broken)
    plan = _write(tmp_path / "plan.json", quintic_plan(samples=50, duration=0.5))
    out, video = tmp_path / "r.json", tmp_path / "replay.mp4"
    assert main(["replay", "--plan", str(plan), "--out", str(out), "--video", str(video)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cannot render the video" in err and str(error) in err
    assert not out.exists() and not video.exists()
    assert list(tmp_path.iterdir()) == [plan]


def test_pinocchio_planned_paper_scenario_meets_replay_acceptance(tmp_path):
    # Issue #5 acceptance on the real planner's output, through the public CLI contract.
    plan, out = tmp_path / "plan.json", tmp_path / "replay.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--out", str(plan)]) == 0
    assert main(["replay", "--plan", str(plan), "--out", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["tracking_rms"] <= 1e-3
    assert abs(result["energy"] / result["energy_planned"] - 1) <= 0.02
    assert result["min_clearance"] >= result["threshold"] - 0.005


def test_a_plant_of_the_robot_replays_and_one_of_another_robot_is_one_line_exit_2(tmp_path,
                                                                                   capsys):
    """`--plant` is its own robot file, checked against the plan's arm: the Lynxmotion's own
    scene (motors, obstacle: simulated as it is) replays the plan; the double pendulum's URDF
    (another robot's kinematics) and a scene whose elbow moved are refused in one line."""
    from harness.robots.registry import erd_robots_dir
    from models import MODELS

    plan = _write(tmp_path / "plan.json", quintic_plan())
    out = tmp_path / "r.json"
    scene = MODELS / "lynxmotion" / "scene.xml"
    assert main(["replay", "--plan", str(plan), "--plant", str(scene), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["plant"] == str(scene)
    out.unlink()
    pendulum = erd_robots_dir() / "double_pendulum_description/urdf/double_pendulum.urdf"
    arm = (MODELS / "lynxmotion" / "lynxmotion.xml").read_text()
    moved = tmp_path / "lynxmotion.xml"  # the scene's include, beside it
    moved.write_text(arm.replace('<body name="link3" pos="0.146 0 0">',
                                 '<body name="link3" pos="0.156 0 0">'))
    assert moved.read_text() != arm
    (tmp_path / "scene.xml").write_text(scene.read_text())
    for plant in (pendulum, tmp_path / "scene.xml"):
        capsys.readouterr()
        assert main(["replay", "--plan", str(plan), "--plant", str(plant), "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "is not robot lynxmotion" in err, err
        assert not out.exists()
