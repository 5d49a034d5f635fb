"""Kinematic chains from any arm: the two engines agree, the chain's Newton-Euler recursion
equals Pinocchio's (torque and joint-torque regressor), and the library generated from the
kinematics alone spans the true torque exactly, on every registered arm and random chains."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import ROBOTS
from identification.library.chain import KinematicChain, rnea
from identification.library.kinematic import KinematicLibrary, random_states


def _states_within_limits(model: pin.Model, n: int, seed: int):
    rng = np.random.default_rng(seed)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    bounded = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    q = np.where(bounded, lo + (hi - lo) * rng.uniform(0.05, 0.95, (n, model.nv)),
                 rng.uniform(-np.pi, np.pi, (n, model.nv)))
    return q, rng.normal(size=(n, model.nv)), rng.normal(size=(n, model.nv))


def random_chain(seed: int, dof: int) -> pin.Model:
    """A serial chain of revolute joints about random unit axes, random placements, random
    inertias, damping and armature."""
    rng = np.random.default_rng(seed)
    model = pin.Model()
    parent = 0
    for j in range(dof):
        axis = rng.normal(size=3)
        placement = pin.SE3(pin.exp3(rng.normal(size=3)), rng.uniform(-0.3, 0.3, 3))
        parent = model.addJoint(parent, pin.JointModelRevoluteUnaligned(axis / np.linalg.norm(axis)),
                                placement, f"j{j + 1}")
        model.appendBodyToJoint(parent, pin.Inertia.Random(), pin.SE3.Identity())
    model.damping = rng.uniform(0, 0.1, dof)
    model.armature = rng.uniform(0, 0.01, dof)
    return model


MODELS = [(name, lambda name=name: Arm.of(name).pinocchio) for name in ROBOTS] + [
    (f"random{dof}-{seed}", lambda s=seed, d=dof: random_chain(s, d))
    for seed, dof in ((1, 3), (2, 5), (3, 7))]


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_mujoco_and_pinocchio_agree_on_every_registered_arm(name):
    pm, mm = Arm.of(name).pinocchio, Arm.of(name).mujoco
    assert mm.nv == pm.nv
    data, baseline = mujoco.MjData(mm), PinocchioModel(pm)
    q, qd, qdd = _states_within_limits(pm, 20, 3)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(mm, data)
        expected = baseline.torque(q[k:k + 1], qd[k:k + 1], qdd[k:k + 1])[0]
        assert np.abs(data.qfrc_inverse - expected).max() <= 1e-9


def test_panda_fingers_are_held_fixed():
    assert Arm.of("panda").pinocchio.nv == 7 and Arm.of("panda").mujoco.nv == 7
    assert Arm.of("panda").chain.dof == 7


@pytest.mark.parametrize("name,build", MODELS, ids=[m[0] for m in MODELS])
def test_chain_rnea_and_regressor_equal_pinocchio(name, build):
    import casadi as ca

    model = build()
    data = model.createData()
    chain = KinematicChain.from_pinocchio(model)
    n = chain.dof
    q, qd, qdd, p = (ca.SX.sym(s, k) for s, k in (("q", n), ("qd", n), ("qdd", n), ("p", 10 * n)))
    tau = rnea(chain, q, qd, qdd, p)
    f = ca.Function("f", [q, qd, qdd, p], [tau, ca.jacobian(tau, p)])
    params = np.concatenate([model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)])
    for x in zip(*random_states(n, 10, 5), strict=True):
        torque, regressor = (np.asarray(v) for v in f(*x, params))
        expected = pin.rnea(model, data, *x) - np.asarray(model.armature) * x[2]
        assert np.abs(torque.ravel() - expected).max() <= 1e-9 * max(1.0, np.abs(expected).max())
        assert np.allclose(regressor, pin.computeJointTorqueRegressor(model, data, *x), atol=1e-9)


@pytest.mark.parametrize("name,build", MODELS, ids=[m[0] for m in MODELS])
def test_generated_library_spans_the_true_torque_exactly(name, build):
    """Noise-free least squares of the true torque (rigid body + damping + armature) on the
    base atoms leaves a relative residual <= 1e-9, on states the library never saw."""
    model = build()
    library = KinematicLibrary.generate(KinematicChain.from_pinocchio(model))
    q, qd, qdd = random_states(library.dof, 500, 11)
    tau = PinocchioModel(model).torque(q, qd, qdd)
    atoms = library.evaluate(q, qd, qdd)
    assert atoms.shape == (500, library.dof, len(library))
    coef = np.linalg.lstsq(atoms.reshape(-1, len(library)), tau.reshape(-1), rcond=None)[0]
    assert np.linalg.norm(atoms @ coef - tau) <= 1e-9 * np.linalg.norm(tau)
    # and the atoms are independent: no two names, full column rank
    assert len(set(library.names)) == len(library)
    assert np.linalg.matrix_rank(atoms.reshape(-1, len(library))) == len(library)


ARM = """<robot name="r"><link name="base"/><link name="l1"><inertial><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<link name="l2"><inertial><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j1" type="{t1}"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="j2" type="{t2}"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>
<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


@pytest.mark.parametrize("t1,t2,message", [
    ("floating", "revolute", "moving base"),
    ("prismatic", "revolute", "prismatic arm joint"),
    ("fixed", "fixed", "no moving joint"),
])
def test_bad_arms_are_one_clear_error(tmp_path, t1, t2, message):
    path = tmp_path / "arm.urdf"
    path.write_text(ARM.format(t1=t1, t2=t2))
    with pytest.raises(UserError, match=message):
        _ = Arm.of(path).chain


def test_a_gripper_jaw_is_held_fixed(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ARM.format(t1="revolute", t2="prismatic"))
    assert Arm.of(path).chain.dof == 1 and Arm.of(path).mujoco.nv == 1


def test_a_closed_chain_is_one_clear_error(tmp_path):
    path = tmp_path / "closed.xml"
    path.write_text("""<mujoco><worldbody>
      <body name="a"><joint name="j1" axis="0 0 1"/><geom size="0.05" mass="1"/>
        <body name="b" pos="0.3 0 0"><joint name="j2" axis="0 1 0"/><geom size="0.05" mass="1"/>
        </body></body></worldbody>
      <equality><joint joint1="j1" joint2="j2"/></equality></mujoco>""")
    with pytest.raises(UserError, match="close the chain"):
        _ = Arm.of(path).chain


def test_model_json_records_its_robot_and_refuses_another(tmp_path, capsys):
    """A prior-library MODEL.json (the Lynxmotion's) records the robot too: planning or
    predicting with it on another robot is one clear error."""
    import json

    from harness.cli import main

    data, model = tmp_path / "d.npz", tmp_path / "MODEL.json"
    assert main(["generate", "--samples", "1200", "--noise", "0.01", "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0
    record = json.loads(model.read_text())["robot"]
    assert record == {"name": "lynxmotion", "hash": Arm.of("lynxmotion").chain.digest()}
    out = tmp_path / "p.npz"
    assert main(["predict", "--model", str(model), "--data", str(data), "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["predict", "--model", str(model), "--data", str(data), "--robot", "ur5",
                 "--out", str(tmp_path / "q.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "identified for robot 'lynxmotion'" in err[0]


BAD_ROBOTS = [
    ("floating.urdf", ARM.format(t1="floating", t2="revolute"), "moving base"),
    ("prismatic.urdf", ARM.format(t1="prismatic", t2="revolute"), "prismatic arm joint"),
    ("binary.urdf", "\udcff", "not UTF-8 text"),
    ("closed.xml", """<mujoco><worldbody>
      <body name="a"><joint name="j1" axis="0 0 1"/><geom size="0.05" mass="1"/>
        <body name="b" pos="0.3 0 0"><joint name="j2" axis="0 1 0"/><geom size="0.05" mass="1"/>
        </body></body></worldbody>
      <equality><joint joint1="j1" joint2="j2"/></equality></mujoco>""", "close the chain"),
    ("empty.xml", '<mujoco><worldbody><body name="a"><geom size="0.05" mass="1"/></body>'
                  "</worldbody></mujoco>", "joint"),
]


@pytest.mark.parametrize("command", ["generate", "closeloop"])
@pytest.mark.parametrize("file,text,message", BAD_ROBOTS)
def test_a_bad_robot_is_one_line_on_every_command(tmp_path, capsys, command, file, text, message):
    from harness.cli import main

    path = tmp_path / file
    path.write_bytes(text.encode("utf-8", "surrogateescape"))
    out = tmp_path / ("data.npz" if command == "generate" else "cl")
    args = {"generate": ["generate", "--robot", str(path), "--samples", "300", "--out", str(out)],
            "closeloop": ["closeloop", "--robot", str(path), "--plant", str(path),
                          "--samples", "300", "--out", str(out)]}[command]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and str(path) in err[0], err
    assert err[0].count(str(path)) == 1  # said once, not wrapped in a second error
    assert not out.exists()
