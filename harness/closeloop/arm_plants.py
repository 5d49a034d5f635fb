"""Plants of any registered arm with effects its declared model lacks.

The arm's MuJoCo model (Arm.mujoco: the URDF's arm joints, no meshes, or its MJCF) is
edited as a MuJoCo spec (mujoco.MjSpec): joint damping, frictionloss, armature and
stiffness added on chosen joints, a spring on a fixed tendon q2 + q3 (an effect outside
the close-the-loop dictionary, as the Lynxmotion's coupled plant), and a point payload
fixed at the flange (the first of registry.FLANGES the model has, else the body
harness.robots.bodies.last_body names: the last joint's, or the one a gripper's jaw turns
on), then written as MJCF. The
payload point is the one harness.robots.bodies puts its unit mass at
(the Pinocchio frame of the same link), so the dictionary's payload column is exact.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import mujoco

from harness.closeloop.plants import Variant
from harness.errors import UserError
from harness.io import write_text
from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from harness.robots.registry import flange_frame
from harness.robots.scene import robot_spec

VECTOR_ATTRIBUTES = ("damping", "stiffness")  # polynomial coefficients in MuJoCo >= 3.3


@dataclass(frozen=True)
class LoadedVariant(Variant):
    """A variant whose payload's centre of mass is offset from the flange (m, in the frame of
    the flange's body) and has a rotational inertia (principal moments about it, kg m^2)."""

    payload_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    payload_inertia: tuple[float, float, float] = (1e-9, 1e-9, 1e-9)


def arm_variant_xml(arm: Arm, variant: Variant) -> str:
    """MJCF text of the arm plus the variant's joint effects and flange payload."""
    from harness.closeloop.plants import JOINT_ATTRIBUTES

    spec = robot_spec(arm)
    hinges = [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    for effect, joint, value in variant.joint_effects:
        if not 1 <= joint <= len(hinges):
            raise UserError(f"{arm.label} has joints 1..{len(hinges)}, not {joint}")
        attr = JOINT_ATTRIBUTES[effect]
        target = hinges[joint - 1]
        if attr in VECTOR_ATTRIBUTES:
            current = list(getattr(target, attr))
            setattr(target, attr, [current[0] + value, *current[1:]])
        else:
            setattr(target, attr, getattr(target, attr) + value)
    if variant.coupling > 0:  # a fixed tendon q2 + q3 with a spring: outside the dictionary
        if len(hinges) < 3:
            raise UserError(f"a tendon coupling joins joints 2 and 3; {arm.label} has "
                            f"{len(hinges)}")
        tendon = spec.add_tendon(name="coupling", stiffness=[variant.coupling, 0.0, 0.0],
                                 springlength=[0.0, 0.0])
        for joint in hinges[1:3]:
            tendon.wrap_joint(joint.name, 1.0)
    if variant.payload > 0:
        frame = flange_frame(arm.pinocchio)
        body, pos = (spec.body(frame) if frame else None), [0.0, 0.0, 0.0]
        site = spec.site(frame) if frame and body is None else None
        if site is not None:  # an MJCF's flange is a site on the last body
            body, pos = site.parent, list(site.pos)
        offset = getattr(variant, "payload_offset", (0.0, 0.0, 0.0))
        carrier = last_body(arm).joint or len(hinges)  # no flange: where closeloop looks
        (body or hinges[carrier - 1].parent).add_body(
            name="payload", pos=[p + o for p, o in zip(pos, offset, strict=True)])
    # a massless frame body (a flange, a tool frame) gets an explicit zero inertial, which
    # Pinocchio's MJCF reader needs on every body; MjSpec.to_xml drops an inertial it did not
    # read (the payload's too): both are written into the text here
    frames = [b.name for b in spec.bodies[1:] if not b.explicitinertial and not b.geoms
              and b.name != "payload"]
    spec.compile()
    text = spec.to_xml()
    inertials = {name: '<inertial pos="0 0 0" mass="0" diaginertia="0 0 0"/>' for name in frames}
    if variant.payload > 0:
        diag = " ".join(f"{i:.10g}" for i in getattr(variant, "payload_inertia", (1e-9,) * 3))
        inertials["payload"] = (f'<inertial pos="0 0 0" mass="{variant.payload:.10g}" '
                                f'diaginertia="{diag}"/>')
    for name, inertial in inertials.items():
        text, n = re.subn(rf'<body name="{re.escape(name)}"([^>]*?)\s*/>',
                          rf'<body name="{name}"\1>{inertial}</body>', text)
        if n != 1 and name == "payload":
            raise RuntimeError("payload body not written by MjSpec.to_xml")
    return text


def write_arm_variant(arm: Arm, variant: Variant, directory: Path) -> Path:
    """Write the variant MJCF to directory/<robot>_<name>.xml; returns its path."""
    directory.mkdir(parents=True, exist_ok=True)
    # a robot file: its file's stem
    path = directory / f"{Path(arm.reference).stem}_{variant.name}.xml"
    write_text(path, arm_variant_xml(arm, variant))
    return path
