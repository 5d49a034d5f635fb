"""`predict --rollout`: a model rolled out in MuJoCo from a log's states under its torque.

On a log MuJoCo itself simulated (the Lynxmotion's own MJCF, `generate --mode measured`,
torque noise 0) the same MJCF reproduces the positions to near zero, and a model whose bodies
are 1.2x heavier does not; the exported MJCF stepped in plain MuJoCo through its own motors
gives the figure the command reports; bad input is one line and exit 2, nothing written."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from harness.cli import main
from harness.io import write_npz
from harness.robots.arm import Arm
from identification.kinematic_model import KinematicModel
from identification.model import model_to_dict

ROBOT = "lynxmotion"  # the registered robot with an MJCF of its own (motors, gear 1)
SEED = 3
HEAVIER = 1.2
# the encoder's step, 2 pi / 2**16 rad (harness.data.sensors): the log's angles are read
# through it, so a rollout from them cannot be expected closer than about one step
ENCODER = 2 * np.pi / 2**16


def _model(path, scale: float = 1.0, bodies: bool = True) -> str:
    """A MODEL.json of the robot's own bodies, each (mass, first moment, inertia) x scale."""
    arm = Arm.of(ROBOT)
    parameters = arm.nominal.atom_parameters().copy()
    parameters[:10 * arm.dof] *= scale
    library = arm.library
    model = KinematicModel(library, library.fold @ parameters, np.zeros(arm.dof), "test")
    extra = {"body_parameters": parameters.tolist()} if bodies else {}
    path.write_text(json.dumps({**model_to_dict(model), **extra}))
    return str(path)


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rollout")
    assert main(["generate", "--robot", ROBOT, "--mode", "measured", "--noise", "0",
                 "--samples", "400", "--seed", str(SEED), "--out", str(tmp / "log.npz")]) == 0
    arrays = dict(np.load(tmp / "log.npz"))
    # the simulator's own states: what the log's sensors saw before the encoder
    write_npz(tmp / "true.npz", **{**arrays, **{k: arrays[f"{k}_true"] for k in ("q", "qd", "qdd")}})
    return tmp


def _rollout(tmp, data, model, windows="0.1", name="r"):
    out = tmp / f"{name}.npz"
    code = main(["predict", "--model", model, "--data", str(tmp / data), "--rollout", windows,
                 "--out", str(out)])
    assert code == 0
    return json.loads((tmp / f"{name}.rollout.json").read_text())["windows"]


def test_its_own_mjcf_reproduces_the_log_and_heavier_bodies_do_not(log):
    own = _rollout(log, "log.npz", "pinocchio", name="own")[0]
    truth = _rollout(log, "true.npz", "pinocchio", name="truth")[0]
    heavier = _rollout(log, "log.npz", _model(log / "heavier.json", HEAVIER), name="heavy")[0]
    assert own["windows"] == 19 and own["samples"] == 20  # 400 samples at 200 Hz, 0.1 s
    assert own["diverged"] == heavier["diverged"] == 0
    # from the simulator's own states only the torque between samples (the controller's, at
    # 2 kHz) is not the log's (200 Hz, linear between): within a fraction of an encoder step
    assert max(truth["q_rms"]) < ENCODER / 2
    # from the sensed states, the encoder's reading error carried along the window
    assert max(own["q_rms"]) < 3 * ENCODER
    assert min(np.array(heavier["q_rms"]) / np.array(own["q_rms"])) > 10


def test_the_exported_mjcf_stepped_through_its_motors_gives_the_figure(log):
    """One window, stepped here in plain MuJoCo on the file `export` writes, its torque through
    the motors (ctrl / gear) instead of applied joint forces."""
    model = _model(log / "heavier.json", HEAVIER)
    arrays = dict(np.load(log / "log.npz"))
    window = 20  # samples: 0.1 s at 200 Hz, one window
    write_npz(log / "short.npz", **{k: v[:window + 1] if k != "meta" else v
                                    for k, v in arrays.items()})
    reported = _rollout(log, "short.npz", model, name="short")[0]
    assert reported["windows"] == 1
    assert main(["export", "--model", model, "--robot", ROBOT, "--format", "mjcf",
                 "--out", str(log / "heavier.xml")]) == 0
    plant = mujoco.MjModel.from_xml_path(str(log / "heavier.xml"))
    data = mujoco.MjData(plant)
    q, qd, tau = (arrays[k][:window + 1] for k in ("q", "qd", "tau"))
    data.qpos[:], data.qvel[:] = q[0], qd[0]
    mujoco.mj_forward(plant, data)
    substeps = int(round(0.005 / plant.opt.timestep))
    joints, gear = plant.actuator_trnid[:, 0], plant.actuator_gear[:, 0]
    error = []
    for i in range(window):
        for s in range(substeps):
            torque = tau[i] + s / substeps * (tau[i + 1] - tau[i])
            data.ctrl[:] = torque[joints] / gear
            mujoco.mj_step(plant, data)
        error.append(data.qpos - q[i + 1])
    expected = np.sqrt(np.mean(np.square(error), axis=0))
    assert np.allclose(reported["q_rms"], expected, rtol=1e-9, atol=1e-12)


def test_the_held_out_part_alone(log):
    """--rollout-holdout 0.5: the windows tile the last 200 of the 400 samples."""
    out = log / "half.npz"
    assert main(["predict", "--model", "pinocchio", "--data", str(log / "log.npz"), "--rollout",
                 "0.1", "--rollout-holdout", "0.5", "--out", str(out)]) == 0
    report = json.loads((log / "half.rollout.json").read_text())
    assert report["from_sample"] == 200 and report["windows"][0]["windows"] == 9


BAD = {  # case: (model, extra arguments, words of the error)
    "longer": ("pinocchio", ["--rollout", "0.1,5"], "longer than the log"),
    "longer_than_its_part": ("pinocchio", ["--rollout", "1.5", "--rollout-holdout", "0.5"],
                             "longer than the log"),
    "no_bodies": (None, ["--rollout", "0.1"], "no bodies"),
    "bad_windows": ("pinocchio", ["--rollout", "0.1,-1"], "positive"),
    "bad_holdout": ("pinocchio", ["--rollout", "0.1", "--rollout-holdout", "1.5"], "(0, 1]"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_is_one_line_and_nothing_written(log, capsys, case):
    model, extra, words = BAD[case]
    model = model or _model(log / "bare.json", bodies=False)
    out = log / f"bad_{case}.npz"
    capsys.readouterr()
    code = main(["predict", "--model", model, "--data", str(log / "log.npz"), *extra,
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert words in err, err
    assert not out.exists() and not (log / f"bad_{case}.rollout.json").exists()
