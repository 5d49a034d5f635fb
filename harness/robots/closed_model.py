"""DIR/model.json of `closeloop --data`: the declared model with the named effects.

{"kind": "closeloop", "dof", "robot": {"name", "hash"}, "declared": "pinocchio" (the
robot's nominal URDF/MJCF model) or the declared MODEL.json's content, "inertial": the
rigid-body correction (a MODEL.json on the robot's base atoms) or null, "offsets": a
constant torque per joint the model adds (N m; 0 as written by the loop), "effects": [{"joint",
"effect", "coefficient", "unit", shape...}], "sensor_offsets": {"training", "heldout": per
run, per joint (N m); "new_run": per joint, the offset a run the model was not trained on
is scored with (identification.closeloop.closed.offsets.held_out_offset: `predict` adds it on a
measured log); "rule"}}: read by `predict` and `plan` through
harness.robots.torque_models.torque_model. A sensor offset is a property of a run, not of
the robot: reported under "sensor_offsets", never added to the torque a planner uses.
"""

from __future__ import annotations

from pathlib import Path

from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from harness.robots.resolve import resolve_arm
from identification.closeloop.candidates.effects import UNITS, EffectTerm
from identification.closeloop.candidates.payload import standard
from identification.closeloop.closed.extended import closed_model
from identification.closeloop.closed.offsets import RULE
from identification.errors import IdentificationError
from identification.kinematic_model import KinematicModel
from identification.model import model_from_dict, model_to_dict

KIND = "closeloop"
SHAPE = ("lead", "eps", "steepness", "shift")


def model_payload(arm: Arm, declared: dict | str, inertial: KinematicModel | None,
                  terms: tuple[EffectTerm, ...], training_offsets,
                  heldout_offsets=(), new_run=None) -> dict:
    """The content of model.json (declared: 'pinocchio' or a MODEL.json's content); the
    runs' sensor offsets ((runs, dof) N m, training and held out) and a new run's ((dof,),
    none: not recorded) reported, not added."""
    return {"kind": KIND, "dof": arm.dof, "robot": arm.record,
            "declared": declared, "inertial": None if inertial is None else model_to_dict(inertial),
            "offsets": [0.0] * arm.dof, "effects": [t.to_json() for t in terms],
            "sensor_offsets": {"training": [[float(o) for o in c] for c in training_offsets],
                               "heldout": [[float(o) for o in c] for c in heldout_offsets],
                               **({} if new_run is None else
                                  {"new_run": [float(o) for o in new_run], "rule": RULE})}}


def declared_model(spec: dict | str, arm: Arm):
    """The declared model of a payload on arm: 'pinocchio' or a MODEL.json's content."""
    if spec == "pinocchio":
        return arm.nominal
    if not isinstance(spec, dict):
        raise IdentificationError("'declared' must be 'pinocchio' or a model")
    if spec.get("kind") == KIND:  # a closed loop's model declared for another loop
        return closeloop_model(spec, arm, Path("declared"))
    return model_from_dict(spec, lambda: arm.library)


def _term(entry: dict) -> EffectTerm:
    if not isinstance(entry, dict) or entry.get("effect") not in UNITS:
        raise IdentificationError(f"malformed effect {str(entry):.60}")
    try:
        body = {}
        if entry["effect"] == "payload" and "com" in entry:  # a payload on the last body
            params = standard(float(entry["mass"]), [float(c) for c in entry["com"]],
                              [float(i) for i in entry["inertia"]])
            body = {"params": tuple(map(float, params)), "body": str(entry.get("body", ""))}
        return EffectTerm(str(entry["effect"]), int(entry["joint"]), float(entry["coefficient"]),
                          **{k: float(entry[k]) for k in SHAPE if k in entry}, **body)
    except (KeyError, TypeError, ValueError) as exc:
        raise IdentificationError(f"malformed effect {str(entry):.60}: {exc}") from None


def closeloop_model(payload: dict, arm: Arm, path: Path):
    """The model a closeloop model.json describes, on arm (checked against the robot it
    records)."""
    recorded = payload.get("robot") if isinstance(payload.get("robot"), dict) else {}
    resolve_arm(arm.reference, model=(str(path), recorded))
    dof = arm.dof
    declared = declared_model(payload.get("declared"), arm)
    inertial = payload.get("inertial")
    inertial = None if inertial is None else model_from_dict(inertial, lambda: arm.library)
    terms = tuple(_term(e) for e in payload.get("effects", []))
    offsets = payload.get("offsets", [0.0] * dof)
    if len(offsets) != dof or any(t.joint < 1 or t.joint > dof for t in terms):
        raise IdentificationError(f"offsets and effect joints must fit the robot's {dof}")
    if inertial is None and any(t.effect == "inertial" for t in terms):
        raise IdentificationError("an 'inertial' effect needs the 'inertial' correction")
    carrier = next((t.body for t in terms if t.effect == "payload" and t.body), None)
    return closed_model(declared, [float(o) for o in offsets], terms, inertial,
                        last_body(arm, carrier))
