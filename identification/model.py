"""MODEL.json: read and written here, for both model kinds.

A model on a feature library (identification.feature_model.IdentifiedModel) and a model on
a robot's base atoms (identification.kinematic_model.KinematicModel, `"library":
"kinematic"`) share the CLI contract: {"dof", "joints": [{"terms", "coefficients",
"offset"}], "library", "method"} (beside, for people: each joint's "coefficient_units",
identification.units); a kinematic model also records the robot it was identified
for (`robot`: name and a hash of its kinematics), the base atoms (`atoms`) and, when chosen,
each joint's friction law (`friction`). Reading a kinematic model needs that robot's
KinematicLibrary (another robot is an error). `model_payload` adds what `identify` measured.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from identification.errors import IdentificationError
from identification.feature_model import IdentifiedModel, JointModel
from identification.friction import FrictionLaw
from identification.kinematic_model import KinematicModel
from identification.library.kinematic import KinematicLibrary
from identification.units import (
    COEFFICIENT_UNITS,
    atom_coefficient_unit,
    feature_unit,
    standard_parameter_labels,
)

KINEMATIC = "kinematic"  # the "library" of a model on a robot's base atoms


MAX_DOF = 64
MAX_COEFFICIENT = 1e9  # |c| in the units of its term; beyond it a file is corrupt, not a robot


def finite_number(x, where: str) -> float:
    """x as a float if it is a JSON number (not a bool or a string), finite and within
    MAX_COEFFICIENT; IdentificationError naming `where` otherwise."""
    if isinstance(x, bool) or not isinstance(x, int | float):
        raise IdentificationError(f"malformed model: {where} must be a number, got {x!r:.40}")
    value = float(x)
    if not np.isfinite(value) or abs(value) > MAX_COEFFICIENT:
        raise IdentificationError(f"malformed model: {where} = {value:.3g} is not a finite number "
                                  f"within +/-{MAX_COEFFICIENT:g}")
    return value


def joint_entries(payload: dict, dof: int | None = None) -> list[dict]:
    """payload['joints'] checked: a list of dof objects, each with lists 'terms' (strings) and
    'coefficients' (numbers, see finite_number) of one length and an optional numeric 'offset'."""
    if not isinstance(payload, dict):
        raise IdentificationError("malformed model: not a JSON object")
    if dof is None:
        raw = payload.get("dof")
        if isinstance(raw, bool) or not isinstance(raw, int) or not 1 <= raw <= MAX_DOF:
            raise IdentificationError(f"malformed model: 'dof' must be an integer in 1..{MAX_DOF}, "
                                      f"got {raw!r:.40}")
        dof = raw
    joints = payload.get("joints")
    if not isinstance(joints, list) or len(joints) != dof:
        got = f"{len(joints)} entries" if isinstance(joints, list) else repr(joints)[:40]
        raise IdentificationError(f"malformed model: 'joints' must list {dof} joints, got {got}")
    for j, joint in enumerate(joints, start=1):
        if not isinstance(joint, dict) or not isinstance(joint.get("terms"), list) \
                or not isinstance(joint.get("coefficients"), list):
            raise IdentificationError(f"malformed model: joint {j} needs lists 'terms' and "
                                      "'coefficients'")
        if len(joint["terms"]) != len(joint["coefficients"]):
            raise IdentificationError(f"malformed model: joint {j} has {len(joint['terms'])} terms "
                                      f"and {len(joint['coefficients'])} coefficients")
        if not all(isinstance(t, str) for t in joint["terms"]):
            raise IdentificationError(f"malformed model: joint {j}'s terms must be strings")
        for k, c in enumerate(joint["coefficients"]):
            finite_number(c, f"joint {j} coefficient {k + 1}")
        finite_number(joint.get("offset", 0.0), f"joint {j} offset")
    return joints


def _feature_dict(model: IdentifiedModel) -> dict:
    return {"dof": model.dof, "library": model.library, "method": model.method,
            "joints": [{"terms": list(jm.terms), "coefficients": list(jm.coefficients),
                        "offset": jm.offset,
                        "coefficient_units": [feature_unit(t, model.dof) for t in jm.terms]}
                       for jm in model.joints],
            "units": COEFFICIENT_UNITS}


def _kinematic_dict(model: KinematicModel) -> dict:
    chain = model.library.chain
    return {"dof": model.dof, "library": KINEMATIC, "method": model.method,
            "robot": {"name": chain.name, "hash": chain.digest()},
            "atoms": model.library.names,
            **({"friction": [law.to_dict() for law in model.laws]} if model.laws else {}),
            "joints": [{"terms": [n for n, _ in model.joint_terms(j)],
                        "coefficients": [c for _, c in model.joint_terms(j)],
                        "offset": float(model.offsets[j]),
                        "coefficient_units": [atom_coefficient_unit(n)
                                              for n, _ in model.joint_terms(j)]}
                       for j in range(model.dof)],
            "units": COEFFICIENT_UNITS}


_WRITERS = {IdentifiedModel: _feature_dict, KinematicModel: _kinematic_dict}


def model_to_dict(model) -> dict:
    """The MODEL.json entries of an identified model (either kind)."""
    return _WRITERS[type(model)](model)


def model_payload(result, robot: dict, heldout: dict, scored_against: str) -> dict:
    """The whole MODEL.json of an Identification (identification.identify): the robot record
    (name, hash), the model, its metrics with how it was held out and what it was scored
    against, and the Lagrangian of a coupled fit."""
    payload = {"robot": robot, **model_to_dict(result.model),
               "metrics": {**result.metrics(), "heldout": heldout,
                           "scored_against": scored_against}}
    payload["robot"] = robot  # the caller's record (a robot file's path too), not the chain's
    if result.lagrangian():
        payload["lagrangian"] = result.lagrangian()
    if isinstance(result.model, KinematicModel):  # readable: bodies, what each atom sums
        from identification.bodies import base_parameters, bodies_payload

        if result.physical and "standard_parameters" in result.physical:
            payload.update(bodies_payload(result.physical))
            physical = payload["metrics"].get("physical")
            if isinstance(physical, dict):  # the flat list labelled: names, units, frame
                payload["metrics"]["physical"] = {
                    **physical, **standard_parameter_labels(result.model.dof)}
        payload["base_parameters"] = base_parameters(result.model.library)
    return payload


def model_from_dict(payload: dict, library: Callable[[], KinematicLibrary] | None = None):
    """Inverse of model_to_dict (extra keys such as metrics are ignored); a kinematic model
    is read on library() (the robot's base atoms, computed only then).
    IdentificationError naming what is malformed."""
    if isinstance(payload, dict) and payload.get("library") == KINEMATIC:
        if library is None:
            raise IdentificationError("a model on a robot's base atoms needs that robot's "
                                      "kinematic library to be read")
        return _kinematic_from_dict(payload, library())
    return _feature_from_dict(payload)


def load_model(path: str | Path, library: Callable[[], KinematicLibrary] | None = None):
    """Read a MODEL.json written by `torquebench identify`."""
    try:
        payload = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise IdentificationError(f"cannot read model {path}: {exc}") from None
    return model_from_dict(payload, library)


def sensor_offsets(model) -> np.ndarray:
    """The fitted per-joint intercepts (sensor offsets, N m) of a model, which its torque
    leaves out; zeros for a model that fits none (the closed form)."""
    offsets = getattr(model, "offsets", None)
    return np.zeros(model.dof) if offsets is None else np.asarray(offsets, float)


def _feature_from_dict(payload: dict) -> IdentifiedModel:
    joints = joint_entries(payload)
    dof = len(joints)
    model = IdentifiedModel(dof, tuple(JointModel(tuple(j["terms"]), tuple(float(c) for c in
                                                  j["coefficients"]), float(j.get("offset", 0.0)))
                                       for j in joints),
                            str(payload.get("library", "")), str(payload.get("method", "")))
    for j in range(dof):
        try:
            model.features(j)
        except ValueError as exc:
            raise IdentificationError(f"malformed model: joint {j + 1}: {exc}") from None
    return model


def _kinematic_from_dict(payload: dict, library: KinematicLibrary) -> KinematicModel:
    """IdentificationError if the model was identified for another robot or is malformed."""
    robot = payload.get("robot") if isinstance(payload.get("robot"), dict) else {}
    chain = library.chain
    if robot.get("hash") != chain.digest():
        raise IdentificationError(
            f"model was identified for robot '{robot.get('name')}' (kinematics "
            f"{robot.get('hash')}), not '{chain.name}' ({chain.digest()})")
    if payload.get("atoms") != library.names:
        raise IdentificationError("model atoms differ from this robot's base atoms "
                                  "(generated by another version?)")
    index = {n: k for k, n in enumerate(library.names)}
    laws = payload.get("friction", [])
    if not isinstance(laws, list) or laws and len(laws) != library.dof:
        raise IdentificationError(f"malformed model: 'friction' must list {library.dof} laws")
    laws = tuple(FrictionLaw.from_dict(law) for law in laws)
    own = {law.term(j + 1): j for j, law in enumerate(laws) if law.has_column}
    coef, offsets = np.zeros(len(library)), np.zeros(library.dof)
    law_coef = np.zeros(library.dof)
    for j, joint in enumerate(joint_entries(payload, library.dof)):
        offsets[j] = float(joint.get("offset", 0.0))
        for name, c in zip(joint["terms"], joint["coefficients"], strict=True):
            if own.get(name) == j:
                law_coef[j] = float(c)
            elif name in index:
                coef[index[name]] = float(c)
            else:
                raise IdentificationError(f"malformed model: joint {j + 1} term '{name:.40}' "
                                          "is not one of the robot's base atoms")
    return KinematicModel(library, coef, offsets, str(payload.get("method", "coupled")), laws,
                          law_coef if laws else None)
