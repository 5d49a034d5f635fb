"""Plan, replay and the model agree on an identified model with sensor offsets and Gaz et al.'s
sigmoid friction (issue #56): the planner's energy is the energy the same dynamics spend in
MuJoCo. The sigmoid has no MuJoCo joint counterpart and is applied to the plant as a torque
(harness.replay.friction); the offsets are the runs' and in neither."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from harness.cli import main
from harness.replay.plants import replay_plant
from harness.replay.reference import plan_reference
from harness.replay.simulate import replay
from harness.robots.arm import Arm
from identification.friction import FrictionLaw
from identification.kinematic_model import KinematicModel
from identification.model import model_to_dict

ROBOT = "double_pendulum"  # two joints: plans in seconds without compiling
FAR = ["--obstacle-from", "5,5,5", "--obstacle-to", "5,5,6"]  # out of reach
OFFSETS = (-0.3, 0.4)  # N m, each joint's sensor offset
SIGMOID = (0.5, 0.3)  # N m, phi of each joint's sigmoid (Gaz et al.'s Panda: 0.2-0.6 N m)
AGREE = 0.02


def _model(path) -> str:
    """A consistent model as `identify` writes it: the URDF's bodies, armature and viscous
    friction, a sigmoid friction law on each joint (no Coulomb atom: the sigmoid takes its
    place), per-joint offsets, and its standard parameters for the plant."""
    arm = Arm.of(ROBOT)
    dof = arm.dof
    parameters = arm.nominal.atom_parameters().copy()
    parameters[10 * dof:] = [1e-4] * dof + [0.01] * dof + [0.0] * dof  # armature, viscous, coulomb
    laws = (FrictionLaw("sigmoid", (30.0, 0.03)), FrictionLaw("sigmoid", (10.0, -0.03)))
    library = arm.library
    model = KinematicModel(library, library.fold @ parameters, np.array(OFFSETS), "test", laws,
                           np.array(SIGMOID))
    path.write_text(json.dumps({**model_to_dict(model), "body_parameters": parameters.tolist()}))
    return str(path)


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("friction")
    model, plan, out = _model(tmp / "MODEL.json"), tmp / "plan.json", tmp / "replay.json"
    assert main(["plan", "--no-compile", "--model", model, "--start", "0.2,0.1", "--goal",
                 "1.0,-0.5", *FAR, "--out", str(plan)]) == 0
    assert main(["replay", "--plan", str(plan), "--plant", model, "--out", str(out)]) == 0
    return model, json.loads(plan.read_text()), json.loads(out.read_text())


def test_plan_and_replay_spend_the_same_energy(planned):
    _, plan, replayed = planned
    assert plan["energy"] > 0
    assert abs(replayed["energy"] - plan["energy"]) <= AGREE * plan["energy"], (
        replayed["energy"], plan["energy"])
    # the model's own torque along the plan (its sensor offsets left out) is the plan's figure
    assert replayed["energy_reference"] == pytest.approx(plan["energy"], rel=AGREE)
    assert [line.split(":")[0] for line in replayed["plant_friction"]] == ["joint 1", "joint 2"]
    assert replayed["tracking_rms"] < 1e-3  # the bench's bar: tracked within 1 mrad


def test_the_models_torque_is_what_the_plant_needs(planned):
    """Along the plan, the model's torque (the planner's and the feed-forward) is MuJoCo's
    inverse dynamics of the plant plus the friction applied to it: no sensor offset in it."""
    model, plan, _ = planned
    plant = replay_plant(model, Arm.of(ROBOT))
    q, qd, qdd = (np.asarray(plan[k]) for k in ("q", "qd", "qdd"))
    data = mujoco.MjData(plant.model)
    needed = np.empty_like(q)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(plant.model, data)
        needed[k] = data.qfrc_inverse
    needed += plant.friction.torque(qd)
    assert np.allclose(plant.feedforward.torque(q, qd, qdd), needed, atol=1e-6)


def test_the_sigmoid_is_what_the_plant_would_miss(planned):
    """Without the applied friction the plant spends another energy: the agreement above is
    the friction's doing, not a motion that spends none."""
    model, plan, _ = planned
    arm = Arm.of(ROBOT)
    plant = replay_plant(model, arm)
    bare, _ = replay(plant.model, plan_reference(plan), plant.feedforward, geometry=arm.geometry)
    assert plant.friction is not None
    assert abs(bare.energy - plan["energy"]) > 5 * AGREE * plan["energy"], bare.energy
