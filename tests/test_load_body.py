"""The body a load rides on, chosen by the data (identification.closeloop.load_body), never by a
joint's name: on example-robot-data's finger_edu (every joint named finger_...) a 0.02 kg load
on its last link is named there within 5 % (the gripper rule put it on the middle link and read
277 kg); on the SO-101, a part held by its jaw is named on the body the jaw turns on; a link
given with --payload-body is obeyed. Logs are Pinocchio's RNEA of the arm with the load (its
10 parameters on the true body) plus white noise: finger_edu's URDF does not compile in
MuJoCo (izz = 0), so its copy here gives that link a small izz, as its user did by hand."""

from __future__ import annotations

import numpy as np
import pytest

from harness.closeloop.payload import candidate_bodies, last_body
from harness.robots.arm import Arm
from identification.closeloop.payload import BodyTorque, describe, standard
from identification.closeloop.runs import close_loop_runs
from identification.signals import multisine

FINGER = "finger_edu_description/robots/finger_edu.urdf"


def _robot(name: str, tmp_path=None) -> Arm:
    from harness.robots.registry import erd_robots_dir

    path = erd_robots_dir() / name
    if name == FINGER:  # MuJoCo refuses izz = 0 on finger_lower_link: as its user did
        copy = tmp_path / "finger_edu.urdf"
        copy.write_text(path.read_text().replace('iyz="0.00000" izz="0.00000"',
                                                  'iyz="0.00000" izz="0.00001"'))
        path = copy
    return Arm.of(path)


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
