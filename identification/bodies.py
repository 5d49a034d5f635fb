"""MODEL.json a person can read: a consistent fit's bodies, and what each base atom sums.

bodies: per body (its joint's index, 1-based), the mass (kg), centre of mass (m, in the
joint's frame) and rotational inertia about the centre of mass (kg m^2), each with the
nominal value the fit was pulled toward (zeros without a prior), and whether the body is
physically consistent (its pseudo-inertia positive semidefinite) and, when fitted with
bounding ellipsoids, plausible (its mass inside its link's ellipsoid, also given). joints_dynamics: per joint
armature (kg m^2), viscous (N m s/rad), Coulomb (N m), with nominal. base_parameters: each
base atom's coefficient is this sum of standard parameters (KinematicLibrary.fold).
"""

from __future__ import annotations

import numpy as np

from identification.library.kinematic import KinematicLibrary, atom_names, atom_unit
from identification.physical import CONSISTENT_TOL

AT_COM = ("the centre of mass, along the joint frame's axes (the standard parameters and the "
          "CSV export's inertias are about the joint frame's origin)")
JOINT_DYNAMICS = (("armature", "kg m^2"), ("viscous", "N m s/rad"), ("coulomb", "N m"))


def inertials(p) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass and inertia about it of one body's 10 standard parameters."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (float(v) for v in p)
    c = np.array([hx, hy, hz]) / m if m > 0 else np.zeros(3)
    origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return m, c, origin - m * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axis theorem


def bodies_payload(physical: dict) -> dict:
    """The 'bodies' and 'joints_dynamics' keys of a consistent fit's MODEL.json (its
    TorqueFit.physical: standard_parameters, joint_parameters, nominal)."""
    params = np.asarray(physical["standard_parameters"], float)
    dof = params.size // 10
    nominal = np.asarray(physical.get("nominal") or np.zeros(13 * dof), float)
    eig = physical.get("min_pseudo_eigenvalues", [0.0] * dof)
    bodies = []
    for j in range(dof):
        m, c, inertia = inertials(params[10 * j:10 * j + 10])
        m0, c0, inertia0 = inertials(nominal[10 * j:10 * j + 10])
        bodies.append({"joint": j + 1,
                       "mass": {"value": m, "unit": "kg", "nominal": m0},
                       "com": {"value": c.tolist(), "unit": "m", "nominal": c0.tolist(),
                               "frame": "the joint's frame"},
                       "inertia_at_com": {"value": inertia.tolist(), "unit": "kg m^2",
                                          "nominal": inertia0.tolist(), "about": AT_COM},
                       "consistent": bool(eig[j] >= -CONSISTENT_TOL)})
        if physical.get("plausible"):  # fitted inside its link's bounding ellipsoid
            bodies[-1]["plausible"] = bool(physical["plausible"][j])
            bodies[-1]["ellipsoid"] = physical["ellipsoids"][j]
    dynamics = []
    for j in range(dof):
        dynamics.append({"joint": j + 1, **{
            name: {"value": float(physical["joint_parameters"][name][j]), "unit": unit,
                   "nominal": float(nominal[(10 + i) * dof + j])}
            for i, (name, unit) in enumerate(JOINT_DYNAMICS)}})
    return {"bodies": bodies, "joints_dynamics": dynamics}


def base_parameters(library: KinematicLibrary) -> dict:
    """Each base atom's meaning: the standard parameters (atom_names, numbered by joint)
    its coefficient sums, with their factors, and its unit."""
    every = atom_names(library.dof)
    fold = library.fold
    out = {"explanation": "each base atom's coefficient is the sum of these standard parameters "
           "times their factors (the rest are not identifiable apart); a primed name sums more "
           "than itself"}
    for name, row in zip(library.names, fold, strict=True):
        terms = [(every[k], float(row[k])) for k in np.flatnonzero(row)]
        out[name] = {"sums": {n: round(f, 12) for n, f in terms}, "unit": atom_unit(name)}
    return out
