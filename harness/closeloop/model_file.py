"""DIR/model.json of `closeloop --data`: the declared model with the named effects.

{"kind": "closeloop", "dof", "robot": {"name", "hash"}, "declared": "pinocchio" (the
robot's nominal URDF/MJCF model) or the declared MODEL.json's content, "inertial": the
rigid-body correction (a MODEL.json on the robot's base atoms) or null, "offsets": a
constant torque per joint the model adds (N m; 0 as written by the loop), "effects": [{"joint",
"effect", "coefficient", "unit", shape...}], "sensor_offsets": {"training", "heldout": per
run, per joint (N m)}}: read by `predict` and `plan` through
harness.robots.torque_models.load_torque_model. A sensor offset is a property of a run, not of
the robot: reported under "sensor_offsets", never added to the torque a planner uses.
"""

from __future__ import annotations

from pathlib import Path

from harness.robots.baseline import PinocchioModel
from harness.robots.registry import identified_robot, load_chain, load_pinocchio
from identification.closeloop.effects import UNITS, EffectTerm
from identification.closeloop.runs import closed_model
from identification.errors import IdentificationError
from identification.kinematic_model import KinematicModel
from identification.model import model_from_dict, model_to_dict

KIND = "closeloop"
SHAPE = ("lead", "eps", "steepness", "shift")


def model_payload(robot: str, declared: dict | str, inertial: KinematicModel | None,
                  terms: tuple[EffectTerm, ...], training_offsets,
                  heldout_offsets=()) -> dict:
    """The content of model.json (declared: 'pinocchio' or a MODEL.json's content); the
    runs' sensor offsets ((runs, dof) N m, training and held out) reported, not added."""
    chain = load_chain(robot)
    return {"kind": KIND, "dof": chain.dof, "robot": {"name": chain.name, "hash": chain.digest()},
            "declared": declared, "inertial": None if inertial is None else model_to_dict(inertial),
            "offsets": [0.0] * chain.dof, "effects": [t.to_json() for t in terms],
            "sensor_offsets": {"training": [[float(o) for o in c] for c in training_offsets],
                               "heldout": [[float(o) for o in c] for c in heldout_offsets]}}


def declared_model(spec: dict | str, robot: str, robot_library):
    """The declared model of a payload: 'pinocchio' or a MODEL.json's content;
    robot_library(robot): its base atoms (harness.robots.torque_models, which reads us)."""
    if spec == "pinocchio":
        return PinocchioModel(load_pinocchio(robot))
    if not isinstance(spec, dict):
        raise IdentificationError("'declared' must be 'pinocchio' or a model")
    if spec.get("kind") == KIND:  # a closed loop's model declared for another loop
        return closeloop_model(spec, robot, Path("declared"), robot_library)
    return model_from_dict(spec, lambda: robot_library(robot))


def _term(entry: dict) -> EffectTerm:
    if not isinstance(entry, dict) or entry.get("effect") not in UNITS:
        raise IdentificationError(f"malformed effect {str(entry):.60}")
    try:
        return EffectTerm(str(entry["effect"]), int(entry["joint"]), float(entry["coefficient"]),
                          **{k: float(entry[k]) for k in SHAPE if k in entry})
    except (KeyError, TypeError, ValueError) as exc:
        raise IdentificationError(f"malformed effect {str(entry):.60}: {exc}") from None


def closeloop_model(payload: dict, robot: str | None, path: Path, robot_library):
    """The model a closeloop model.json describes, for robot (default: the one it records);
    robot_library(robot): its base atoms."""
    recorded = payload.get("robot") if isinstance(payload.get("robot"), dict) else {}
    robot = identified_robot(recorded, robot, path)
    chain = load_chain(robot)
    declared = declared_model(payload.get("declared"), robot, robot_library)
    inertial = payload.get("inertial")
    inertial = None if inertial is None else model_from_dict(inertial,
                                                             lambda: robot_library(robot))
    terms = tuple(_term(e) for e in payload.get("effects", []))
    offsets = payload.get("offsets", [0.0] * chain.dof)
    if len(offsets) != chain.dof or any(t.joint < 1 or t.joint > chain.dof for t in terms):
        raise IdentificationError(f"offsets and effect joints must fit the robot's {chain.dof}")
    if inertial is None and any(t.effect == "inertial" for t in terms):
        raise IdentificationError("an 'inertial' effect needs the 'inertial' correction")
    return closed_model(declared, [float(o) for o in offsets], terms, inertial)
