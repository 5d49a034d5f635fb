"""Variant plants of the Lynxmotion arm with effects its declared model lacks.

`write_variant` edits the declared MJCF as text (joint attributes, a payload
body at the end-effector site, a stiff tendon coupling two joints) so tests and
the bench can build any combination; `true_effects` reads back, from a plant's
compiled MuJoCo model, what it carries beyond the declared model - for scoring
only, never for estimation.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from harness.io import write_text
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from identification.closeloop.candidates.effects import EffectTerm
from models import MODELS

DECLARED_MJCF = MODELS / "lynxmotion" / "lynxmotion.xml"
JOINT_ATTRIBUTES = {"viscous": "damping", "coulomb": "frictionloss", "armature": "armature",
                    "spring": "stiffness"}


@dataclass(frozen=True)
class Variant:
    """Effects to add: joint effects as (effect, joint 1..3, value); payload mass in kg;
    `coupling` = stiffness (N m/rad) of a fixed tendon q2 + q3 (outside the dictionary)."""

    joint_effects: tuple[tuple[str, int, float], ...] = ()
    payload: float = 0.0
    coupling: float = 0.0
    name: str = field(default="variant")


def variant_text(variant: Variant, base: str | None = None) -> str:
    """MJCF text of the declared arm plus the variant's effects."""
    text = base if base is not None else DECLARED_MJCF.read_text()
    for effect, joint, value in variant.joint_effects:
        attr = JOINT_ATTRIBUTES[effect]
        pattern = rf'(<joint name="joint{joint}")'
        text, n = re.subn(pattern, rf'\1 {attr}="{value:.10g}"', text)
        if n != 1:
            raise ValueError(f"joint{joint} not found in the MJCF")
    if variant.payload > 0:
        body = (f'<body name="payload" pos="0.187 0 0"><inertial pos="0 0 0" '
                f'mass="{variant.payload:.10g}" diaginertia="1e-9 1e-9 1e-9"/></body>\n'
                '            <site name="end_effector"')
        text = text.replace('<site name="end_effector"', body, 1)
    if variant.coupling > 0:
        tendon = (f'<tendon><fixed name="coupling" stiffness="{variant.coupling:.10g}" '
                  'springlength="0"><joint joint="joint2" coef="1"/>'
                  '<joint joint="joint3" coef="1"/></fixed></tendon>\n  <actuator>')
        text = text.replace("<actuator>", tendon, 1)
    return text


def write_variant(variant: Variant, directory: Path) -> Path:
    """Write the variant MJCF to directory/lynxmotion_<name>.xml; returns its path."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"lynxmotion_{variant.name}.xml"
    write_text(path, variant_text(variant))
    return path


def friction_shape(plant: mujoco.MjModel, dof: int, friction: float) -> tuple[float, float]:
    """(lead s, eps rad/s) of MuJoCo's regularized frictionloss on a dof
    (identification.closeloop.candidates.effects): lead = 1 / b, b = 2 / (dmax timeconst);
    eps = R f / b, R = (1 - dmin) / dmin * invweight0."""
    dmin, dmax = plant.dof_solimp[dof, :2]
    timeconst = max(plant.dof_solref[dof, 0], 2 * plant.opt.timestep)  # MuJoCo's lower bound
    b = 2.0 / (dmax * timeconst)
    return 1.0 / b, float((1 - dmin) / dmin * plant.dof_invweight0[dof] * friction / b)


def true_effects(plant: mujoco.MjModel, declared: mujoco.MjModel | None = None,
                 ) -> tuple[tuple[EffectTerm, ...], bool]:
    """Effects the plant carries beyond the declared MJCF (Coulomb terms with MuJoCo's own
    friction shape), and whether any lies outside the dictionary (tendon springs/dampers,
    gravity compensation)."""
    declared = declared or Arm.of(DEFAULT_ROBOT).mujoco
    terms = []
    pairs = (("viscous", plant.dof_damping, declared.dof_damping),
             ("coulomb", plant.dof_frictionloss, declared.dof_frictionloss),
             ("armature", plant.dof_armature, declared.dof_armature),
             ("spring", plant.jnt_stiffness, declared.jnt_stiffness))
    for effect, have, base in pairs:
        for j in np.flatnonzero(np.abs(have - base) > 0):
            value = float(have[j] - base[j])
            shape = friction_shape(plant, int(j), value) if effect == "coulomb" else ()
            terms.append(EffectTerm(effect, int(j) + 1, value, *shape))
    extra_mass = float(plant.body_mass.sum() - declared.body_mass.sum())
    if extra_mass > 0:
        terms.append(EffectTerm("payload", plant.nv, extra_mass))
    outside = bool(np.any(plant.tendon_stiffness > 0) or np.any(plant.tendon_damping > 0)
                   or np.any(plant.body_gravcomp > 0))
    return tuple(terms), outside
