"""Units and labels MODEL.json gives its numbers (written beside them, never read back).

- A coefficient's unit: the joint torque (N m) per unit of its term. A feature's angles are
  in rad, its velocities in rad/s and accelerations in rad/s^2 (trigonometric factors have
  none): 'qd1^2*sin(q2)' -> 'N m s^2/rad^2'. A base atom's is the atom's (kg, kg m,
  kg m^2, N m s/rad, N m); a friction law's own column's, N m.
- The standard parameters (TorqueFit.physical['standard_parameters']): per body m, mcx,
  mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz (Pinocchio's order), numbered by joint, first
  moments and inertias about the body's joint frame (not its centre of mass: MODEL.json's
  bodies give the inertia at the centre of mass).
"""

from __future__ import annotations

from identification.library.chain import PARAMETERS, UNITS
from identification.library.features import parse_feature
from identification.library.kinematic import JOINT_ATOMS, atom_unit

STANDARD_FRAME = ("about the body's joint frame (its origin and axes): first moments m*c and "
                  "inertias there, not at the centre of mass (bodies[].inertia_at_com is)")
COEFFICIENT_UNITS = ("joints[].coefficient_units: each coefficient's unit, the joint torque "
                     "(N m) per unit of its term (angles rad, velocities rad/s, accelerations "
                     "rad/s^2); joints[].offset in N m")


def _power(unit: str, n: int) -> str:
    return "" if n == 0 else unit if n == 1 else f"{unit}^{n}"


def feature_unit(term: str, dof: int) -> str:
    """The unit of a feature's coefficient: N m over the term's unit."""
    kinds = [kind for kind, _ in parse_feature(term, dof).motion]
    rad = len(kinds)
    seconds = kinds.count("qd") + 2 * kinds.count("qdd")
    text = " ".join(p for p in ("N m", _power("s", seconds)) if p)
    return f"{text}/{_power('rad', rad)}" if rad else text


def atom_coefficient_unit(term: str) -> str:
    """The unit of a kinematic model's coefficient: its base atom's, or N m for a friction
    law's own column (stribeck<j>, sigmoid<j>)."""
    try:
        return atom_unit(term)
    except KeyError:
        return "N m"


def standard_parameter_labels(dof: int) -> dict:
    """Names and units of the 10 dof standard parameters, and the frame they are about."""
    names = [f"{p}{j + 1}" for j in range(dof) for p in PARAMETERS]
    return {"standard_parameter_names": names,
            "standard_parameter_units": [UNITS[p] for _ in range(dof) for p in PARAMETERS],
            "standard_parameters_frame": STANDARD_FRAME,
            "joint_parameter_units": dict(JOINT_ATOMS)}
