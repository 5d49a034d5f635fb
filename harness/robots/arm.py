"""An `Arm`: one robot, resolved once per command (harness.robots.resolve) and handed to
everything that needs it.

The Arm carries what every stage asks of a robot, each built on first use and once: its
MuJoCo and Pinocchio models (harness.robots.files, the only parser), its kinematic chain,
the planner's geometry and link capsules, joint, velocity and torque limits, the nominal
(Pinocchio) torque model and parameters, the bodies' bounding ellipsoids and the base atoms
of its kinematics. `Arm.of(reference)` is cached per process: a command that names the same
robot twice gets the same Arm, parsed once. Its models are shared: whoever changes one
(a timestep, a body's inertia) changes a copy (`copy.copy(arm.mujoco)`, `arm.pinocchio.copy()`).
"""

from __future__ import annotations

import dataclasses
import sys
from functools import cache, cached_property
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from harness.errors import UserError
from harness.robots import registry
from harness.robots.registry import ROBOTS, Robot, flange_frame, robot_entry
from identification.library.chain import ChainError, KinematicChain
from planning.formulation.kinematics import ArmGeometry


class Arm:
    """One robot's models and data (module docstring); build with Arm.of or resolve_arm."""

    def __init__(self, entry: Robot):
        self.entry = entry
        # what data, models and plans record: a registered name, or the file's absolute path
        self.reference = entry.name

    @staticmethod
    def of(name_or_path: str | Path) -> Arm:
        """The Arm of a registered name or a URDF/MJCF path (cached: parsed once per process);
        UserError for an unknown name or a missing file."""
        robot, chain = registry.split_reference(str(name_or_path))
        if robot not in ROBOTS and Path(robot).is_file():
            robot = str(Path(robot).resolve())
        return _arm(registry.chain_reference(robot, chain))

    def __repr__(self) -> str:
        return f"Arm({self.reference!r})"

    @property
    def registered(self) -> bool:
        return self.reference in ROBOTS

    @property
    def label(self) -> str:
        """A short name for messages: the registered name, else the file's name; a chain's
        followed by its base and tip links."""
        return registry.reference_name(self.reference, "{name} ({chain})", stem=False)

    # --- the models, parsed once -----------------------------------------------------------
    @cached_property
    def spec(self) -> mujoco.MjSpec:
        """The arm's MuJoCo spec as parsed (no scene): copy it to build on it."""
        from harness.robots.files import parse_spec

        return parse_spec(self.entry)

    @cached_property
    def mujoco(self) -> mujoco.MjModel:
        """The arm's MuJoCo model (no scene); UserError unless an open chain of 1-DOF joints."""
        from harness.robots.files import compile_spec

        model = compile_spec(self.spec, self.entry)
        if model.nq != model.nv or model.nv == 0:
            raise UserError(f"robot {self.reference}: needs 1-DOF joints only "
                            f"(nq={model.nq}, nv={model.nv})")
        if model.neq > 0:
            raise UserError(f"robot {self.reference}: equality constraints close the chain: "
                            "only open serial chains are supported")
        return model

    @cached_property
    def scene(self) -> mujoco.MjModel | None:
        """The registered scene MJCF (the Lynxmotion's hand-written one), else None."""
        from harness.robots.files import compile_spec, parse_spec

        return (compile_spec(parse_spec(self.entry, scene=True), self.entry)
                if self.entry.scene is not None else None)

    @cached_property
    def pinocchio(self) -> pin.Model:
        """The arm's Pinocchio model (non-arm joints held fixed)."""
        from harness.robots.files import parse_pinocchio

        return parse_pinocchio(self.entry)

    @cached_property
    def chain(self) -> KinematicChain:
        """The kinematic chain; UserError unless a fixed-base serial chain of revolute joints
        (an MJCF is also checked for loops in MuJoCo)."""
        if self.entry.urdf is None:
            self.mujoco  # noqa: B018 - an MJCF's equality constraints close a loop
        name = registry.reference_name(self.reference, "{name}:{chain}", stem=True)
        try:
            chain = KinematicChain.from_pinocchio(self.pinocchio, name)
        except ChainError as exc:
            raise UserError(f"robot {self.reference}: {exc}") from None
        branches = [j for j, p in enumerate(chain.parents) if p != j - 1]
        if branches:
            j, names = branches[0], self.pinocchio.names  # chain joint j is Pinocchio's j + 1
            parent = chain.parents[j]
            on = "the base" if parent < 0 else f"joint '{names[parent + 1]}'"
            raise UserError(f"robot {self.reference}: joint '{names[j + 1]}' does not follow "
                            f"joint '{names[j]}' (it hangs on {on}): not a serial chain (one arm "
                            "of a whole robot: --chain BASE_LINK:TIP_LINK)")
        return chain

    @property
    def dof(self) -> int:
        return self.chain.dof

    @cached_property
    def record(self) -> dict:
        """What a MODEL.json records of its robot: name and kinematics hash, and for a robot
        given by its file that file's absolute path (so later commands find it); for a chain
        of a whole robot (--chain) its base and tip links ('BASE:TIP') and the joints held
        fixed (joint, type, position in rad or m)."""
        record = {"name": self.chain.name, "hash": self.chain.digest()}
        from harness.robots.files import chain_record, inertia_repairs

        record.update(chain_record(self.entry))
        if self.entry.urdf is not None:  # a link inertia repaired for MuJoCo (harness.robots.urdf)
            repairs = inertia_repairs(self.entry)
            if repairs:
                record["repaired_inertias"] = repairs
        return record if self.registered else {**record,
                                               "file": registry.split_reference(self.reference)[0]}

    # --- geometry and limits ---------------------------------------------------------------
    @cached_property
    def geometry(self) -> ArmGeometry:
        """The chain of joint placements, axes and flange (m), for planning; the flange is the
        first of registry.FLANGES the model has, else the frame on the last body farthest
        from its joint."""
        chain, model = self.chain, self.pinocchio
        last = model.njoints - 1
        frames = [f for f in model.frames if f.parentJoint == last]
        named = [f for f in frames if f.name == flange_frame(model)]
        tips = named or sorted(frames, key=lambda f: np.linalg.norm(f.placement.translation))
        flange = np.asarray(tips[-1].placement.translation) if tips else np.zeros(3)
        bodies = []
        for j in range(1, model.njoints):
            names = [f.name for f in model.frames
                     if f.parentJoint == j and f.type == pin.FrameType.BODY]
            bodies.append(names[0] if names else model.names[j])
        return ArmGeometry.of(chain.rotations, chain.translations, chain.axes, flange,
                              self.reference, bodies)

    @cached_property
    def _read_geometry(self) -> tuple[dict, tuple]:
        """harness.robots.collision.urdf_geometry, read once; each link whose geometry cannot
        be read is named once on stderr (one line: its files and why)."""
        from harness.robots.collision import urdf_geometry

        if not self.entry.urdf:
            return {}, ()
        found, unread = urdf_geometry(self.entry, self.pinocchio)
        for link in dict.fromkeys(u.link for u in unread):
            files = "; ".join(f"{u.file} ({u.reason})" for u in unread if u.link == link)
            print(f"torquebench: warning: robot {self.label}: link {link}: geometry not read: "
                  f"{files}; its capsule and bounding ellipsoid leave it out", file=sys.stderr)
        return found, unread

    @property
    def body_points(self) -> dict[int, tuple[str, np.ndarray]]:
        """Per arm joint (1-based) whose links carry geometry the harness reads, which kind
        ("collision", else "visual") and its points (harness.robots.collision)."""
        return self._read_geometry[0]

    @property
    def unread_geometry(self) -> tuple:
        """The links' geometry that could not be read (harness.robots.collision
        .UnreadGeometry: link, file, reason), where it would have counted."""
        return self._read_geometry[1]

    def capsules(self, default: float = 0.0) -> ArmGeometry:
        """geometry with each link's capsule fitted to its collision (else visual) geometry
        (harness.robots.capsules); a link without any keeps its joint-origin segment and
        radius default (m); without any geometry the links stay the segments, radius default
        (0: lines)."""
        return self._capsules(float(default))

    @cache  # noqa: B019 - one Arm per robot and process (Arm.of)
    def _capsules(self, default: float) -> ArmGeometry:
        from harness.robots.capsules import fitted_geometry

        return fitted_geometry(self.geometry, self.pinocchio, self.body_points, default)

    @cached_property
    def position_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper joint limits (rad) from MuJoCo; an unlimited hinge gets [-pi, pi]."""
        model = self.mujoco
        ids = model.dof_jntid
        limited = model.jnt_limited[ids].astype(bool)
        return (np.where(limited, model.jnt_range[ids, 0], -np.pi),
                np.where(limited, model.jnt_range[ids, 1], np.pi))

    @property
    def joint_limits(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        lower, upper = self.position_limits
        return tuple(map(float, lower)), tuple(map(float, upper))

    @cached_property
    def speed_bounds(self) -> np.ndarray:
        """Joint speed limits (rad/s) from the URDF's <limit velocity>; inf where none is
        declared (0, non-finite or huge)."""
        v = np.asarray(self.pinocchio.velocityLimit, float)
        return np.where(np.isfinite(v) & (v > 0) & (v < 1e10), v, np.inf)

    @cached_property
    def velocity_limit(self) -> tuple[float, ...] | None:
        """|qd_i| bound (rad/s) per joint, None unless every joint has a finite positive one."""
        velocity = np.asarray(self.pinocchio.velocityLimit, float)
        if not np.all(np.isfinite(velocity) & (velocity > 0)):
            return None
        return tuple(float(v) for v in velocity)

    @cached_property
    def motor_torque_limit(self) -> tuple[float, ...] | None:
        """|tau_i| bound (N m) from the MJCF motors (ctrlrange x gear), in joint order; None if
        a motor is unlimited or the motors do not map 1:1 to joints."""
        model = self.mujoco
        joints = model.actuator_trnid[:, 0]
        if model.nu == 0 or model.nu != model.njnt or sorted(joints) != list(range(model.njnt)) \
                or not all(model.actuator_ctrllimited):
            return None
        reach = np.abs(model.actuator_ctrlrange).min(axis=1) * np.abs(model.actuator_gear[:, 0])
        limit = np.empty(model.njnt)
        limit[joints] = reach
        return tuple(float(v) for v in limit)

    @cached_property
    def torque_limit(self) -> tuple[float, ...] | None:
        """The motors' limits (MJCF), else the model's effort limits (URDF); None if unknown."""
        if self.motor_torque_limit is not None or self.mujoco.nu > 0:
            return self.motor_torque_limit
        effort = np.asarray(self.pinocchio.effortLimit, float)
        if not np.all(np.isfinite(effort) & (effort > 0)):
            return None
        return tuple(float(v) for v in effort)

    # --- what identification and planning start from ---------------------------------------
    @cached_property
    def nominal(self):
        """The closed-form baseline: Pinocchio's RNEA on the arm's model (a TorqueModel)."""
        from harness.robots.baseline import PinocchioModel

        return PinocchioModel(self.pinocchio)

    @cached_property
    def ellipsoids(self) -> tuple:
        """Per body, its bounding ellipsoid (harness.robots.ellipsoids)."""
        from harness.robots.ellipsoids import arm_ellipsoids

        return arm_ellipsoids(self.pinocchio, self.body_points)

    @cached_property
    def library(self):
        """The base atoms generated from the arm's kinematics (KinematicLibrary)."""
        from identification.library.kinematic import KinematicLibrary

        return KinematicLibrary.generate(self.chain)

    def first_difference(self, other: Arm, tolerance: float = 1e-5) -> int | None:
        """The first joint (1-based) where other's kinematics differ from this arm's beyond
        tolerance (m, and unit vectors; an MJCF written by MjSpec keeps 6 digits), 0 for
        another joint count, None when they agree."""
        if other.record["hash"] == self.record["hash"]:
            return None
        mine, theirs = self.chain, other.chain
        if mine.dof != theirs.dof or mine.parents != theirs.parents:
            return 0
        return next((j + 1 for j in range(mine.dof) if not all(
            np.allclose(np.asarray(a)[j], np.asarray(b)[j], atol=tolerance)
            for a, b in ((mine.rotations, theirs.rotations),
                         (mine.translations, theirs.translations), (mine.axes, theirs.axes)))),
            None)

    def check_joints(self, dof: int, what: str) -> None:
        """UserError unless what (data, a model, an excitation) has the arm's joint count."""
        if dof != self.dof:
            raise UserError(f"{what} has {dof} joints, robot {self.label} has {self.dof}")


@cache
def _arm(name: str) -> Arm:
    entry = robot_entry(name)
    return Arm(dataclasses.replace(entry, name=name) if name not in ROBOTS else entry)
