"""`--chain BASE_LINK:TIP_LINK`: the arm between two links of a whole robot's URDF, every
other joint held fixed. Its dynamics are cross-checked against Pinocchio's own reduction of
the whole model (buildReducedModel, the joints off the chain locked at the same positions),
in Pinocchio and in MuJoCo; the chain is recorded with the data and the model."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.cli import main
from harness.errors import UserError
from harness.robots.arm import Arm

URDF = Path(__file__).resolve().parent / "data" / "two_arm_robot.urdf"
LEFT, RIGHT = "torso_link:left_tool", "torso_link:right_tool"
# what the file's limits make of a hold at 0 (its comment): the lift's, the torso's pitch's and
# the head's lower limits, the right arm's joint 2's upper limit
HELD = {"torso_lift_joint": 0.1, "torso_pitch_joint": 0.1, "head_joint": 0.2,
        "arm_right_2_joint": -0.5}


def reduced(path: Path, arm: Arm, held: dict[str, float]) -> pin.Model:
    """Pinocchio's reduction of the whole model to the arm's joints, the others locked at
    held (0 elsewhere; a continuous joint's neutral)."""
    full = pin.buildModelFromUrdf(str(path))
    q = pin.neutral(full)
    for name, value in held.items():
        q[full.joints[full.getJointId(name)].idx_q] = value
    names = set(arm.pinocchio.names[1:])
    lock = [j for j in range(1, full.njoints) if full.names[j] not in names]
    return pin.buildReducedModel(full, lock, q)


def configuration(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration of one angle per joint: (cos, sin) for a continuous joint."""
    return np.concatenate([[np.cos(a), np.sin(a)] if joint.nq == 2 else [a]
                           for joint, a in zip(model.joints[1:], q, strict=True)])


def cross_check(path: Path, chain: str, seed: int, held: dict[str, float]) -> float:
    """The largest torque difference (N m) of the chain's arm from the reduced whole model, over
    random states: Pinocchio's RNEA and MuJoCo's inverse dynamics (damping zeroed) on the
    arm, Pinocchio's RNEA on the reduction."""
    arm = Arm.of(f"{path}#{chain}")
    truth = reduced(path, arm, held)
    assert list(truth.names) == list(arm.pinocchio.names)
    rng = np.random.default_rng(seed)
    model = arm.mujoco.__copy__()
    model.dof_damping[:] = 0
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT  # states past the limits
    data = mujoco.MjData(model)
    worst = 0.0
    for _ in range(5):
        q, qd, qdd = (rng.uniform(-1.5, 1.5, arm.dof) for _ in range(3))
        expected = pin.rnea(truth, truth.createData(), configuration(truth, q), qd, qdd)
        ours = pin.rnea(arm.pinocchio, arm.pinocchio.createData(), q, qd, qdd)
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(model, data)
        scale = max(1.0, np.max(np.abs(expected)))
        worst = max(worst, np.max(np.abs(ours - expected)) / scale,
                    np.max(np.abs(data.qfrc_inverse - expected)) / scale)
    return worst


def test_the_chain_holds_every_other_joint_at_its_stated_position():
    arm = Arm.of(f"{URDF}#{LEFT}")
    assert arm.dof == 3 and list(arm.pinocchio.names[1:]) == [
        f"arm_left_{k}_joint" for k in (1, 2, 3)]
    held = {h["joint"]: h["position"] for h in arm.record["held"]}
    assert held == pytest.approx({**{n: 0.0 for n in (
        "arm_right_1_joint", "arm_right_3_joint", "left_finger_joint")}, **HELD}, abs=1e-15)
    assert arm.record["chain"] == LEFT


def test_the_chain_has_the_reduced_whole_models_dynamics():
    assert cross_check(URDF, LEFT, 1, HELD) <= 1e-9
    assert cross_check(URDF, RIGHT, 2, HELD) <= 1e-9


def test_whole_robots_from_example_robot_data():
    """TIAGo Pro's, TALOS's and PR2's left arms (the torso, the head, the other arm, the
    wheels and the grippers held)."""
    from harness.robots.registry import erd_robots_dir

    robots = erd_robots_dir()
    # TALOS's right arm joint 2 is limited to [-pi/2 - ..., -0.0087] rad: held at its upper
    # limit (the URDF's number, read here apart from the code under test)
    talos = robots / "talos_data/robots/talos_full_v2.urdf"
    upper = float(next(j for j in ET.parse(talos).getroot().iter("joint")
                       if j.get("name") == "arm_right_2_joint").find("limit").get("upper"))
    assert upper < 0
    for path, chain, held in ((robots / "tiago_pro_description/robots/tiago_pro.urdf",
                               "torso_lift_link:arm_left_7_link", {}),
                              (talos, "torso_2_link:arm_left_7_link",
                               {"arm_right_2_joint": upper}),
                              (robots / "pr2_description/urdf/pr2.urdf",  # its materials'
                               "torso_lift_link:l_wrist_roll_link", {})):  # value: a name
        assert Arm.of(f"{path}#{chain}").dof == 7
        assert cross_check(path, chain, 3, held) <= 1e-9


def test_stated_holds_are_kept_and_checked():
    """--hold: the torso pitched to 0.3 rad and the right arm's joint 2 at -1.0 rad; the
    chain's dynamics are the reduction's at those positions (the pitch tilts gravity in the
    arm's frame: not the default hold's)."""
    stated = {"torso_pitch_joint": 0.3, "arm_right_2_joint": -1.0}
    hold = ",".join(f"{k}={v}" for k, v in stated.items())
    arm = Arm.of(f"{URDF}#{LEFT}@{hold}")
    assert {h["joint"]: h["position"] for h in arm.record["held"]}["torso_pitch_joint"] == 0.3
    assert arm.record["hold"] == stated
    assert cross_check(URDF, f"{LEFT}@{hold}", 4, {**HELD, **stated}) <= 1e-9
    assert cross_check(URDF, f"{LEFT}@{hold}", 4, HELD) > 1e-3  # the default's is another
    for bad, message in (("torso_pitch_joint=0.9", "outside its limits"),
                         ("arm_left_2_joint=0.1", "not a moving joint off the chain"),
                         ("torso_pitch_joint=x", "--hold must be JOINT=POSITION")):
        with pytest.raises(UserError, match=message):
            Arm.of(f"{URDF}#{LEFT}@{bad}").dof  # noqa: B018


def test_a_chain_through_a_prismatic_joint_or_of_unknown_links_is_one_clear_error():
    with pytest.raises(UserError, match="prismatic arm joint 'torso_lift_joint'"):
        Arm.of(f"{URDF}#base_link:left_tool").dof  # noqa: B018
    with pytest.raises(UserError, match="tip link 'nose' is not a link"):
        Arm.of(f"{URDF}#torso_link:nose").dof  # noqa: B018
    with pytest.raises(UserError, match="does not hang below base link 'arm_right_1_link'"):
        Arm.of(f"{URDF}#arm_right_1_link:left_tool").dof  # noqa: B018
    with pytest.raises(UserError, match="prismatic arm joint 'torso_lift_joint'.*--chain"):
        Arm.of(str(URDF)).dof  # noqa: B018


def test_excite_generate_identify_plan_on_a_chain(tmp_path):
    traj, data, model, plan = (tmp_path / n for n in ("t.csv", "d.npz", "m.json", "p.json"))
    robot = ["--robot", str(URDF), "--chain", LEFT, "--hold", "torso_pitch_joint=0.3"]
    assert main(["excite", *robot, "--duration", "4", "--rate", "100", "--iterations", "2",
                 "--harmonics", "5", "--floor", "none", "--out", str(traj)]) == 0
    assert main(["generate", *robot, "--excitation", str(traj), "--noise", "0",
                 "--out", str(data)]) == 0
    meta = json.loads(str(np.load(data)["meta"]))
    assert meta["chain"] == LEFT and meta["plant"].endswith(f"#{LEFT}@torso_pitch_joint=0.3")
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0  # the data's arm
    record = json.loads(model.read_text())["robot"]
    assert record["chain"] == LEFT and record["file"] == str(URDF)
    assert record["hold"] == {"torso_pitch_joint": 0.3}
    assert main(["plan", "--no-compile", "--model", str(model), "--start", "0.3,0.5,-0.5",
                 "--goal", "-0.3,0.8,-1.0", "--duration", "1", "--obstacle-from", "3,3,3",
                 "--obstacle-to", "3,3,4", "--out", str(plan)]) == 0
    assert json.loads(plan.read_text())["q"][-1] == pytest.approx([-0.3, 0.8, -1.0], abs=1e-6)
    # the same file's other arm: another arm's kinematics, refused in one line
    assert main(["plan", "--no-compile", "--model", str(model), "--robot", str(URDF),
                 "--chain", RIGHT, "--out", str(tmp_path / "other.json")]) == 2
    assert not (tmp_path / "other.json").exists()
