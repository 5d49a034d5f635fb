"""`torquebench export`: a consistent fit's bodies in the robot's URDF give the model's
inverse dynamics in Pinocchio (with the joints' damping and friction), in its MJCF in MuJoCo; the csv is
labelled; a model without bodies exports its terms and refuses a URDF in one line."""

from __future__ import annotations

import csv
import json

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from harness.cli import main
from harness.data.generate import generate
from harness.io import write_npz
from harness.robots.arm import Arm
from harness.robots.torque_models import load_torque_model
from identification.library.kinematic import COULOMB_WIDTH

TOL = 1e-3  # relative, on the torque vector's norm


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """A UR5 model fitted consistently with the nominal prior, and the data it came from."""
    folder = tmp_path_factory.mktemp("export")
    write_npz(folder / "d.npz", **generate(Arm.of("ur5"), 1500, 0.02, 1, "inverse").arrays())
    assert main(["identify", "--data", str(folder / "d.npz"), "--prior", "nominal", "--robot",
                 "ur5", "--out", str(folder / "m.json")]) == 0
    return folder


def _export(folder, fmt, model="m.json"):
    out = folder / f"{model.removesuffix('.json')}.{fmt}"
    code = main(["export", "--model", str(folder / model), "--robot", "ur5", "--format", fmt,
                 "--out", str(out)])
    return code, out


def _close(a, b):
    assert np.linalg.norm(a - b) <= TOL * max(np.linalg.norm(b), 1e-9), (a, b)


def test_the_urdf_gives_the_models_gravity(fitted, capsys):
    capsys.readouterr()
    code, out = _export(fitted, "urdf")
    assert code == 0
    # the armature the URDF cannot hold is said to be left out (issue #58)
    line = capsys.readouterr().out
    physical = json.loads((fitted / "m.json").read_text())["metrics"]["physical"]
    armature = physical["joint_parameters"]["armature"]
    assert any(armature) and "armature (" in line and "is not in it" in line
    exported = pin.buildModelFromUrdf(str(out))
    data = exported.createData()
    model = load_torque_model(str(fitted / "m.json"), Arm.of("ur5"))  # its torque leaves offsets out
    rng = np.random.default_rng(3)
    zero = np.zeros(exported.nv)
    for q in rng.uniform(-np.pi, np.pi, (10, exported.nv)):
        _close(pin.computeGeneralizedGravity(exported, data, q), model.torque(q, zero, zero))


def test_the_urdf_gives_the_models_inverse_dynamics(fitted):
    """Pinocchio's full RNEA on the exported URDF, plus its <dynamics damping friction> (the
    friction on the model's smoothed sign) and the armature URDF cannot hold, is the model's
    torque at random states: the inertia's every entry and the joints' friction are written
    where Pinocchio reads them (#56 item 5: gravity alone missed Iyy and Izz swapped)."""
    code, out = _export(fitted, "urdf")
    assert code == 0
    exported = pin.buildModelFromUrdf(str(out))
    data = exported.createData()
    physical = json.loads((fitted / "m.json").read_text())["metrics"]["physical"]
    joints = physical["joint_parameters"]
    armature = np.asarray(joints["armature"])
    assert np.allclose(exported.damping, joints["viscous"], rtol=1e-9, atol=0)
    assert np.allclose(exported.friction, joints["coulomb"], rtol=1e-9, atol=0)
    assert np.all(exported.damping > 0) and np.all(exported.friction > 0)  # both compared
    model = load_torque_model(str(fitted / "m.json"), Arm.of("ur5"))
    rng = np.random.default_rng(5)
    for _ in range(10):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, 6), rng.normal(size=6), rng.normal(size=6)
        tau = (pin.rnea(exported, data, q, qd, qdd) + armature * qdd + exported.damping * qd
               + exported.friction * qd / np.sqrt(qd**2 + COULOMB_WIDTH**2))
        _close(tau, model.torque(q, qd, qdd))


def test_the_joint_frame_is_the_child_links_frame():
    """Why the urdf export can write a body's parameters about its joint's frame as the child
    link's <inertial>: Pinocchio puts the joint's frame at the child link's origin."""
    model = Arm.of("ur5").pinocchio
    data = model.createData()
    q = np.random.default_rng(0).uniform(-1, 1, model.nq)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    for j in range(1, model.njoints):
        link = next(f for f in model.frames if f.parentJoint == j and f.type == pin.FrameType.BODY)
        assert data.oMf[model.getFrameId(link.name)].isApprox(data.oMi[j], 1e-12)


def test_the_mjcf_gives_the_models_inverse_dynamics(fitted):
    """Coulomb friction compared off: MuJoCo's frictionloss is a constraint, not a torque of
    qd, so the model's Coulomb terms are zeroed and the MJCF's frictionloss too."""
    code, out = _export(fitted, "mjcf")
    assert code == 0
    assert "frictionloss" in out.read_text() and "armature" in out.read_text()
    exported = mujoco.MjModel.from_xml_path(str(out))
    exported.dof_frictionloss[:] = 0.0
    payload = json.loads((fitted / "m.json").read_text())
    for joint in payload["joints"]:
        joint["coefficients"] = [0.0 if t.startswith("coulomb") else c
                                 for t, c in zip(joint["terms"], joint["coefficients"], strict=True)]
    (fitted / "no_coulomb.json").write_text(json.dumps(payload))
    model = load_torque_model(str(fitted / "no_coulomb.json"), Arm.of("ur5"))
    data = mujoco.MjData(exported)
    rng = np.random.default_rng(4)
    for _ in range(10):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, 6), rng.normal(size=6), rng.normal(size=6)
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(exported, data)
        _close(data.qfrc_inverse.copy(), model.torque(q, qd, qdd))


def test_the_csv_is_labelled(fitted):
    code, out = _export(fitted, "csv")
    assert code == 0
    rows = list(csv.reader(out.read_text().splitlines()))
    assert rows[0] == ["item", "parameter", "value", "unit", "nominal", "about"]
    table = {(r[0], r[1]): r for r in rows[1:]}
    assert len(rows) == 1 + 13 * 6 and all(len(r) == 6 for r in rows)
    assert table[("shoulder_link", "mass")][3] == "kg"
    assert table[("shoulder_link", "Ixx")][3] == "kg m^2"
    # which frame (issue #58): the link's, not the centre of mass MODEL.json's bodies are at
    assert "about the origin of the link frame" in table[("shoulder_link", "Ixx")][5]
    assert "not about the centre of mass" in table[("shoulder_link", "Iyz")][5]
    assert table[("shoulder_link", "mc_x")][5].startswith("in the link frame")
    assert table[("shoulder_link", "mass")][5] == table[("shoulder_pan_joint", "coulomb")][5] == ""
    assert table[("shoulder_pan_joint", "viscous")][3] == "N m s/rad"
    assert table[("shoulder_pan_joint", "coulomb")][3] == "N m"
    physical = json.loads((fitted / "m.json").read_text())["metrics"]["physical"]
    assert float(table[("shoulder_link", "mass")][2]) == pytest.approx(
        physical["standard_parameters"][0], rel=1e-9)


def test_a_model_without_bodies_exports_terms_and_refuses_a_urdf(fitted, capsys):
    assert main(["identify", "--data", str(fitted / "d.npz"), "--prior", "none", "--robot",
                 "ur5", "--out", str(fitted / "sparse.json")]) == 0
    capsys.readouterr()
    code, out = _export(fitted, "urdf", "sparse.json")
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "no bodies" in err and not out.exists()
    code, out = _export(fitted, "csv", "sparse.json")
    rows = list(csv.reader(out.read_text().splitlines()))
    assert code == 0 and rows[0] == ["joint", "term", "coefficient", "unit"] and len(rows) > 7


def test_bad_input_is_one_line(fitted, capsys):
    out = fitted / "bad.urdf"
    assert main(["export", "--model", str(fitted / "missing.json"), "--robot", "ur5",
                 "--format", "urdf", "--out", str(out)]) == 2
    assert main(["export", "--model", str(fitted / "m.json"), "--robot", "panda",
                 "--format", "urdf", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and not out.exists()
    assert Arm.of("ur5").entry.urdf is not None


def test_replay_simulates_the_consistent_fits_bodies(fitted):
    """`replay --plant MODEL.json` reads metrics.physical as it reads 'body_parameters'."""
    from harness.replay.plants import replay_plant

    payload = json.loads((fitted / "m.json").read_text())
    physical = payload["metrics"]["physical"]
    plant = replay_plant(str(fitted / "m.json"), Arm.of("ur5")).model
    masses = physical["standard_parameters"][::10]
    bodies = [plant.jnt_bodyid[j] for j in range(plant.njnt)]
    assert np.allclose(plant.body_mass[bodies], masses, rtol=1e-9)
    assert np.allclose(plant.dof_damping, physical["joint_parameters"]["viscous"], rtol=1e-9)
    explicit = {**payload, "body_parameters": [*physical["standard_parameters"], *(
        v for k in ("armature", "viscous", "coulomb") for v in physical["joint_parameters"][k])]}
    (fitted / "explicit.json").write_text(json.dumps(explicit))
    again = replay_plant(str(fitted / "explicit.json"), Arm.of("ur5")).model
    assert np.array_equal(again.body_inertia, plant.body_inertia)



def test_replay_simulates_an_exported_mjcf_named_mjcf(fitted):
    """`replay --plant FILE.mjcf` on the export: the scene built around it has the bodies
    MuJoCo's own loader reads from the file (MjSpec.from_file knew no `.mjcf` decoder)."""
    from harness.replay.plants import replay_plant

    code, _ = _export(fitted, "mjcf")
    out = fitted / "exported.mjcf"
    out.write_text((fitted / "m.mjcf").read_text())
    plant = replay_plant(str(out), Arm.of("ur5")).model
    own = mujoco.MjModel.from_xml_path(str(out))
    names = [own.body(b).name for b in range(1, own.nbody)]
    assert code == 0 and names
    assert np.allclose([plant.body(n).mass[0] for n in names], own.body_mass[1:], rtol=1e-12)
    assert np.allclose([plant.body(n).inertia for n in names], own.body_inertia[1:], rtol=1e-12)


def test_an_mjcf_of_any_suffix_keeps_its_includes(tmp_path, monkeypatch):
    """The Lynxmotion's scene (it includes its arm's file) read as `.mjcf` from another folder
    compiles to what MuJoCo's loader makes of it."""
    from harness.robots.files import mjcf_spec
    from models import MODELS

    for name, target in (("lynxmotion.xml", "lynxmotion.xml"), ("scene.xml", "scene.mjcf")):
        (tmp_path / target).write_text((MODELS / "lynxmotion" / name).read_text())
    monkeypatch.chdir(tmp_path.parent)
    spec = mjcf_spec(tmp_path / "scene.mjcf").compile()
    own = mujoco.MjModel.from_xml_path(str(tmp_path / "scene.mjcf"))
    assert (spec.nbody, spec.ngeom, spec.nu) == (own.nbody, own.ngeom, own.nu) and own.nu
    assert np.allclose(spec.body_mass, own.body_mass, rtol=1e-12)


def test_a_model_of_other_kinematics_is_refused(fitted, capsys):
    out = fitted / "other.csv"
    assert main(["export", "--model", str(fitted / "m.json"), "--robot", "lynxmotion",
                 "--format", "csv", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "identified for robot" in err and not out.exists()


def test_a_gripper_held_fixed_is_left_massless(tmp_path):
    """The Panda's fingers were held fixed (their mass is in the hand's parameters): its URDF
    with the nominal parameters written back gives the nominal gravity, fingers moving or not."""
    from harness.robots.export import export_model

    arm = Arm.of("panda")
    nominal = arm.pinocchio
    out = tmp_path / "panda.urdf"
    export_model({"body_parameters": arm.nominal.atom_parameters().tolist()}, arm, "urdf", out)
    exported = pin.buildModelFromUrdf(str(out))
    assert exported.nv == nominal.nv + 2
    q = np.random.default_rng(5).uniform(-1, 1, exported.nq)
    _close(pin.computeGeneralizedGravity(exported, exported.createData(), q)[:nominal.nv],
           pin.computeGeneralizedGravity(nominal, nominal.createData(), q[:nominal.nq]))


def test_a_thin_body_on_the_edge_of_consistency_loads_in_plain_mujoco(tmp_path):
    """A consistent fit leaves thin links on the edge of the triangle inequality: the Panda
    log's identified link 5 has principal moments A + B - C = 9e-9 of C = 0.018 kg m^2, which
    MuJoCo's 6-digit XML writer breaks ('inertia must satisfy A + B >= C'). The export is read
    back by plain MuJoCo with the moments as given."""
    from harness.robots.export import export_model

    arm = Arm.of("panda")
    parameters = arm.nominal.atom_parameters().copy()
    moments = (3.64837983e-07, 1.84853302e-02, 1.84856859e-02)  # the fit's link 5, kg m^2
    mass = parameters[40]
    parameters[40:50] = [mass, 0, 0, 0, moments[0], 0, moments[1], 0, 0, moments[2]]
    out = tmp_path / "thin.xml"
    export_model({"body_parameters": parameters.tolist()}, arm, "mjcf", out)
    exported = mujoco.MjModel.from_xml_path(str(out))
    body = exported.jnt_bodyid[4]
    assert np.allclose(np.sort(exported.body_inertia[body]), moments, rtol=1e-12, atol=0)


def test_the_mjcf_says_what_its_friction_costs_on_a_log(fitted, capsys):
    """--data: the mjcf export's torque gap on the log's states is on stderr and in the file;
    with another format it is refused in one line, nothing written."""
    out = fitted / "costed.xml"
    assert main(["export", "--model", str(fitted / "m.json"), "--robot", "ur5", "--format", "mjcf",
                 "--data", str(fitted / "d.npz"), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    gap = [line for line in err.splitlines() if "torque RMS gap per joint" in line]
    assert len(gap) == 1 and gap[0].split(": ")[-1] in out.read_text()
    csv_out = fitted / "costed.csv"
    assert main(["export", "--model", str(fitted / "m.json"), "--robot", "ur5", "--format", "csv",
                 "--data", str(fitted / "d.npz"), "--out", str(csv_out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--format mjcf" in err and not csv_out.exists()
