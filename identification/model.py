"""The identified torque model: per joint, named terms and coefficients.

Implements TorqueModel. The fitted intercept (a constant sensor bias in the
data) is stored as `offset` but is NOT part of the torque: the model predicts
the torque the robot needs, not what a biased sensor reads. MODEL.json
follows the CLI contract: {"dof", "joints": [{"terms", "coefficients",
"offset"}], "metrics", "library", "method"} (+ "lagrangian" for the coupled method).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from identification.errors import IdentificationError
from identification.library.features import Feature, parse_feature
from identification.torque_model import as_states


@dataclass(frozen=True)
class JointModel:
    """tau_j = sum_k coefficients[k] * terms[k](q, qd, qdd)  (N m)."""

    terms: tuple[str, ...]
    coefficients: tuple[float, ...]
    offset: float = 0.0  # fitted sensor bias, N m (not in the torque)

    def equation(self, joint: int, digits: int = 6) -> str:
        body = " + ".join(f"{c:.{digits}g}*{t}" for c, t in zip(self.coefficients, self.terms,
                                                                 strict=True))
        return f"tau{joint} = {body or '0'}".replace("+ -", "- ")


@dataclass(frozen=True)
class IdentifiedModel:
    """A sparse torque model; `torque` on arrays, `symbolic_torque` on CasADi vectors."""

    dof: int
    joints: tuple[JointModel, ...]
    library: str = ""
    method: str = ""  # "coupled" (one Lagrangian, shared atoms) or "per-joint" (the paper)

    def _features(self, j: int) -> list[Feature]:
        return [parse_feature(t, self.dof) for t in self.joints[j].terms]

    def torque(self, q, qd, qdd) -> np.ndarray:
        """Torques (n, dof) in N m at states of shape (n, dof)."""
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        tau = np.zeros_like(q)
        for j, joint in enumerate(self.joints):
            for f, c in zip(self._features(j), joint.coefficients, strict=True):
                tau[:, j] += c * f.evaluate(q, qd, qdd)
        return tau

    def symbolic_torque(self, q, qd, qdd):
        """CasADi (dof, 1) expression of the same model (SX or MX inputs)."""
        import casadi

        rows = []
        for j, joint in enumerate(self.joints):
            expr = 0
            for f, c in zip(self._features(j), joint.coefficients, strict=True):
                expr = expr + c * f.evaluate(q, qd, qdd, lib=casadi)
            rows.append(expr)
        return casadi.vertcat(*rows)

    def equations(self) -> list[str]:
        return [jm.equation(j + 1) for j, jm in enumerate(self.joints)]

    def to_dict(self) -> dict:
        return {"dof": self.dof, "library": self.library, "method": self.method,
                "joints": [{"terms": list(jm.terms), "coefficients": list(jm.coefficients),
                            "offset": jm.offset} for jm in self.joints]}


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


def model_from_dict(payload: dict) -> IdentifiedModel:
    """Inverse of IdentifiedModel.to_dict (extra keys such as metrics are ignored);
    IdentificationError naming what is malformed."""
    joints = joint_entries(payload)
    dof = len(joints)
    model = IdentifiedModel(dof, tuple(JointModel(tuple(j["terms"]), tuple(float(c) for c in
                                                  j["coefficients"]), float(j.get("offset", 0.0)))
                                       for j in joints),
                            str(payload.get("library", "")), str(payload.get("method", "")))
    for j in range(dof):
        try:
            model._features(j)
        except ValueError as exc:
            raise IdentificationError(f"malformed model: joint {j + 1}: {exc}") from None
    return model


def load_model(path: str | Path) -> IdentifiedModel:
    """Read a MODEL.json written by `torquebench identify`."""
    try:
        payload = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise IdentificationError(f"cannot read model {path}: {exc}") from None
    return model_from_dict(payload)
