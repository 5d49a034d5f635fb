"""The body a load rides on, chosen by the data (identification.closeloop.candidates.load_body), never by a
joint's name: on example-robot-data's finger_edu (every joint named finger_...) a 0.02 kg load
on its last link is named there within 5 % (the gripper rule put it on the middle link and read
277 kg); on the SO-101, a part held by its jaw is named on the body the jaw turns on; a link
given with --payload-body is obeyed. Logs are Pinocchio's RNEA of the arm with the load (its
10 parameters on the true body) plus white noise. finger_edu's URDF is read as it comes: its
izz = 0, which MuJoCo refuses, is repaired for both engines and recorded."""

from __future__ import annotations

import numpy as np
import pytest

from harness.robots.arm import Arm
from harness.robots.bodies import candidate_bodies, last_body
from identification.closeloop.candidates.payload import BodyTorque, describe, standard
from identification.closeloop.selection.runs import close_loop_runs
from identification.signals import multisine

FINGER = "finger_edu_description/robots/finger_edu.urdf"


def _robot(name: str, tmp_path=None) -> Arm:
    from harness.robots.registry import erd_robots_dir

    return Arm.of(erd_robots_dir() / name)


def test_a_link_inertia_mujoco_refuses_is_repaired_and_recorded(capsys):
    """finger_edu's finger_lower_link has izz = 0 (Pinocchio takes it, MuJoCo refuses it):
    the arm loads in both engines as it comes, the link's inertia raised to the smallest valid
    one (its other moments and axes kept), said on stderr and in the robot's record; the two
    engines' torques agree on it."""
    arm = _robot(FINGER)
    model = arm.mujoco  # compiles: MuJoCo accepts the repaired inertia
    (repair,) = arm.record["repaired_inertias"]
    assert repair["link"] == "finger_lower_link" and repair["before"][5] == 0.0
    assert 0.0 < repair["after"][5] <= 1e-6 * 1e3  # small against ixx = iyy = 1.2e-4
    assert repair["after"][:5] == pytest.approx(repair["before"][:5], abs=1e-15)
    body = model.body("finger_lower_link")
    assert np.all(body.inertia > 0)
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-1, 1, (5, arm.dof)) for _ in range(3))
    from harness.data.generate import inverse_torques

    np.testing.assert_allclose(inverse_torques(model, q, qd, qdd), arm.nominal.torque(q, qd, qdd),
                               atol=1e-8)


def test_an_inertia_repaired_to_the_triangle_inequality_is_one_mujoco_takes(tmp_path):
    """The Allegro hand's link_15.0 (A + B < C): repaired to A + B = C exactly, MuJoCo still
    refused it (its own eigenvalues round below); a one-joint arm carrying that inertia loads
    in both engines, its moments still within 1e-5 of the triangle's equality."""
    import xml.etree.ElementTree as ET

    from harness.robots.registry import erd_robots_dir

    hand = ET.parse(erd_robots_dir() / "allegro_hand_description/urdf/allegro_left_hand.urdf")
    link = next(k for k in hand.getroot().iter("link") if k.get("name") == "link_15.0")
    inertia = ET.tostring(link.find("inertial"), encoding="unicode")
    urdf = tmp_path / "one.urdf"
    urdf.write_text(f"""<robot name="one"><link name="base"/>
      <link name="tip">{inertia}</link>
      <joint name="j" type="revolute"><parent link="base"/><child link="tip"/>
        <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>""")
    arm = Arm.of(urdf)
    moments = np.sort(arm.mujoco.body_inertia[arm.mujoco.body("tip").id])
    assert moments[0] + moments[1] >= moments[2]
    assert moments[0] + moments[1] <= moments[2] * (1 + 1e-5)


def _runs(arm: Arm, body, params, seeds=(21, 22), n=1500):
    lo, hi = arm.position_limits
    centre, amplitude = (lo + hi) / 2, 0.4 * (hi - lo)
    out = []
    for seed in seeds:
        m = multisine(n, arm.dof, seed, centre, amplitude, 15.0)
        tau = arm.nominal.torque(m.q, m.qd, m.qdd) + BodyTorque(body, params).torque(
            m.q, m.qd, m.qdd)
        scale = 1e-3 * np.std(tau, axis=0)
        out.append((m.q, m.qd, m.qdd, tau + scale * np.random.default_rng(seed).normal(
            size=tau.shape)))
    return out


def _payload(loop):
    (term,) = [t for t in loop.terms if t.effect == "payload"]
    return term.body, describe(term.params)


@pytest.mark.parametrize("robot, link, mass, com", [
    (FINGER, "finger_lower_link", 0.02, (0.0, 0.0, -0.15)),
    ("so_arm_description/urdf/so101.urdf", "gripper_link", 0.15, (0.01, 0.0, -0.09)),
])
def test_the_data_choose_the_load_s_body(tmp_path, robot, link, mass, com):
    arm = _robot(robot, tmp_path)
    body = last_body(arm, link)
    params = standard(mass, com, [1e-6, 0.0, 1e-6, 0.0, 0.0, 1e-6])
    loop = close_loop_runs(arm.nominal, _runs(arm, body, params), body=candidate_bodies(arm))
    named, (m, c, _) = _payload(loop)
    assert named == link and loop.body_choice["chosen"] == link, loop.body_choice
    assert m == pytest.approx(mass, rel=0.05)
    assert np.linalg.norm(c - np.asarray(com)) < 0.01
    assert loop.body_choice["margin"] > 0


def test_a_named_link_is_obeyed(tmp_path):
    arm = _robot(FINGER, tmp_path)
    truth = last_body(arm, "finger_lower_link")
    params = standard(0.02, (0.0, 0.0, -0.15), [1e-6, 0.0, 1e-6, 0.0, 0.0, 1e-6])
    told = last_body(arm, "finger_middle_link")
    loop = close_loop_runs(arm.nominal, _runs(arm, truth, params), body=told)
    assert loop.body_choice == {}
    assert all(t.body == "finger_middle_link" for t in loop.terms if t.effect == "payload")


# --- the link a user names, through the commands ----------------------------------------

def _lynx_log(path, body_link: str, mass: float, seed: int = 3, n: int = 800) -> str:
    """A log of the Lynxmotion carrying mass kg on body_link (Pinocchio RNEA plus the load's
    torque, white noise), as `closeloop --data` reads it."""
    import json

    from tests.helpers import lynxmotion_motion

    arm = Arm.of("lynxmotion")
    m = lynxmotion_motion(n, seed=seed)
    load = standard(mass, (0.05, -0.01, 0.03), [2e-4, 0.0, 3e-4, 0.0, 0.0, 2e-4])
    tau = arm.nominal.torque(m.q, m.qd, m.qdd) + BodyTorque(last_body(arm, body_link), load).torque(
        m.q, m.qd, m.qdd)
    tau += 0.002 * np.random.default_rng(seed).normal(size=tau.shape)
    np.savez(path, t=m.t, q=m.q, qd=m.qd, qdd=m.qdd, tau=tau,
             meta=np.array(json.dumps({"robot": "lynxmotion"})))
    return str(path)


def test_closeloop_obeys_payload_body(tmp_path):
    """`closeloop --data --payload-body link2` on a log whose 0.3 kg load rides on link3 (the
    body the data choose left to themselves, and the last): the payload, if one is named,
    is on link2 only, and closeloop.json says the link was named."""
    import json

    from harness.cli import main

    data = _lynx_log(tmp_path / "loaded.npz", "link3", 0.3)
    out = tmp_path / "cl"
    assert main(["closeloop", "--data", data, "--payload-body", "link2", "--out", str(out)]) == 0
    result = json.loads((out / "closeloop.json").read_text())
    bodies = {e["body"] for e in result["effects"] if e["effect"] == "payload"}
    assert bodies <= {"link2"}, result["effects"]
    assert result["payload_body"] == {"chosen": "link2", "rule": "--payload-body"}


def test_identify_loaded_takes_the_load_on_load_body(tmp_path):
    """`identify --loaded --load-mass --load-body wrist_2_link` on logs of motor currents of
    the UR5 whose 2.5 kg load rides on wrist_2_link (not the last link, the default): the
    gains are the true ones within 1 % and MODEL.json's load is on that link (read on the last
    link, the same logs give gains 5 % and more off). Logs: Pinocchio RNEA on random states
    with viscous and Coulomb friction and 1 % noise, currents = torque / known gains."""
    import json

    from harness.cli import main
    from identification.library.kinematic import COULOMB_WIDTH

    arm, link = Arm.of("ur5"), "wrist_2_link"
    gains = np.array([7.3, 11.0, 5.2, 2.9, 1.7, 0.9])
    load = standard(2.5, (0.02, 0.06, 0.04), [0.01, 0.0, 0.012, 0.0, 0.0, 0.008])
    rng = np.random.default_rng(7)
    meta = np.array(json.dumps({"robot": "ur5", "robot_hash": arm.record["hash"]}))
    files = {}
    for name, carried in (("unloaded", None), ("loaded", load)):
        q, qd, qdd = (rng.uniform(-a, a, (1000, 6)) for a in (3.0, 2.0, 5.0))
        tau = arm.nominal.torque(q, qd, qdd) + 0.3 * qd + 0.5 * qd / np.hypot(qd, COULOMB_WIDTH)
        if carried is not None:
            tau += BodyTorque(last_body(arm, link), carried).torque(q, qd, qdd)
        tau += 0.01 * tau.std(0) * rng.standard_normal(tau.shape)
        files[name] = str(tmp_path / f"{name}.npz")
        np.savez(files[name], q=q, qd=qd, qdd=qdd, current=tau / gains, meta=meta)
    out = tmp_path / "MODEL.json"

    def identify(*body):
        assert main(["identify", "--data", files["unloaded"], "--loaded", files["loaded"],
                     "--load-mass", "2.5", *body, "--out", str(out)]) == 0
        return json.loads(out.read_text())["drive_gains"]

    reported = identify("--load-body", link)
    assert reported["load"]["body"] == link
    np.testing.assert_allclose(reported["gains"], gains, rtol=0.01)
    # without the option the data choose the same link; a wrong link named is obeyed all the
    # same (the load read there, the gains off): the option decides, not the data
    assert identify()["load"]["body"] == link
    wrong = identify("--load-body", "wrist_1_link")
    assert wrong["load"]["body"] == "wrist_1_link"
    assert wrong["load"]["body_choice"]["rule"] == "--load-body"
    assert np.max(np.abs(np.asarray(wrong["gains"]) / gains - 1)) > 0.02
