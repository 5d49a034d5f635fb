"""Forward kinematics of any serial arm of revolute joints, given as data.

ArmGeometry holds what the planner needs of a robot's kinematics: for each joint j its
frame's placement in the previous joint's frame (the base for joint 1) at q = 0 (rotation
R_j, translation p_j in m), its unit axis a_j in its own frame, and the flange point in the
last joint's frame. The harness builds it from the robot's model (planning never reads
models); the paper's Lynxmotion arm is `paper_arm()`, one chain like any other (its eqs. 9
and 10 are a cross-check in the tests).

The link points are the joint origins and the flange; a link is the segment between two
consecutive points, kept when it has length (or its body has a fitted capsule: `covered`)
and moves (an endpoint off an earlier joint's axis). Its capsule's axis (`link_ends`) is
that segment, or, where `ends` gives them, two points fixed in the frame of the joint that
moves the link (a capsule fitted to the body's meshes by the harness). One
forward-kinematics recursion (`_points`) serves numpy arrays (vectorized over samples) and
CasADi expressions (exact derivatives for the NLP).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property

import casadi as ca
import numpy as np

AXIS_TOLERANCE = 1e-9  # m: a point this close to a joint axis does not move with that joint


def _tuple(x) -> tuple:
    return tuple(_tuple(v) for v in x) if np.ndim(x) else float(x)


@dataclass(frozen=True)
class ArmGeometry:
    """A fixed-base serial chain of revolute joints (m, rad); hashable, as plain tuples.

    rotations (dof, 3, 3) and translations (dof, 3): joint j's frame in joint j-1's frame
    (joint 1: in the world) at q = 0; axes (dof, 3): unit joint axes in their own frames;
    flange (3,): the flange point in the last joint's frame; bodies: the name of the body
    each joint moves (for reports); radii: each link's capsule (m); ends: each link's capsule
    axis ((a, b) points, m) in the frame of the joint moving it (link (i, i + 1): joint i + 1);
    covered: joints kept as links though their segment has no length.
    """

    rotations: tuple
    translations: tuple
    axes: tuple
    flange: tuple
    name: str = "arm"
    bodies: tuple[str, ...] = ()
    # radius (m) of the capsule around each link (links order; empty: every link a line):
    # clearance is measured to the capsules' surfaces (planning.formulation.clearance)
    radii: tuple[float, ...] = ()
    # the capsules' axes, body-fixed (links order; empty: the segments between the link points)
    ends: tuple = ()
    # joints i (0-based) whose zero-length segment (i, i + 1) is a link all the same: a
    # capsule fitted to the body they move gives it extent
    covered: tuple[int, ...] = ()

    @classmethod
    def of(cls, rotations, translations, axes, flange, name: str = "arm",
           bodies=()) -> ArmGeometry:
        """From array-likes; axes are normalized."""
        axes = np.asarray(axes, float)
        axes = axes / np.linalg.norm(axes, axis=1, keepdims=True)
        return cls(_tuple(rotations), _tuple(translations), _tuple(axes), _tuple(flange), name,
                   tuple(bodies))

    @property
    def dof(self) -> int:
        return len(self.axes)

    def points(self, q) -> np.ndarray:
        """Link points (n, dof + 1, 3) in m: joint origins 1..dof and the flange, at joint
        angles q (n, dof) or (dof,)."""
        q = np.atleast_2d(np.asarray(q, float))
        if q.shape[1] != self.dof:
            raise ValueError(f"q has {q.shape[1]} joints, the arm {self.dof}")
        c, s = np.cos(q)[:, :, None, None], np.sin(q)[:, :, None, None]
        points = _points(self, lambda j: (c[:, j], s[:, j]), np.eye(3), np.zeros(3))
        return np.stack([np.broadcast_to(p, (len(q), 3)) for p in points], axis=1)

    def symbolic_points(self, q) -> list:
        """Link points (dof + 1 CasADi 3 x 1 expressions, m) at a CasADi joint vector q."""
        return _points(self, lambda j: (ca.cos(q[j]), ca.sin(q[j])), ca.DM.eye(3),
                       ca.DM.zeros(3, 1))

    def link_ends(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Both ends (n, links, 3 each) in m of every link's capsule axis at joint angles q
        (n, dof) or (dof,)."""
        first, second = (list(index) for index in zip(*self.links, strict=True))
        if not self.ends:
            points = self.points(q)
            return points[:, first], points[:, second]
        origins, rotations = self.joint_frames(q)
        a, b = (np.asarray([end[k] for end in self.ends], float) for k in (0, 1))
        return (origins[:, first] + np.einsum("nlij,lj->nli", rotations[:, first], a),
                origins[:, first] + np.einsum("nlij,lj->nli", rotations[:, first], b))

    def joint_frames(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Joint frames at joint angles q (n, dof) or (dof,): origins (n, dof, 3) in m and
        rotations (n, dof, 3, 3) to the world."""
        q = np.atleast_2d(np.asarray(q, float))
        c, s = np.cos(q)[:, :, None, None], np.sin(q)[:, :, None, None]
        frames: list = []
        points = _points(self, lambda j: (c[:, j], s[:, j]), np.eye(3), np.zeros(3), frames)
        return (np.stack([np.broadcast_to(p, (len(q), 3)) for p in points[:-1]], axis=1),
                np.stack([np.broadcast_to(r, (len(q), 3, 3)) for r in frames], axis=1))

    def symbolic_link_ends(self, q) -> list:
        """Both ends (CasADi 3 x 1 expressions, m) of every link's capsule axis at a CasADi
        joint vector q."""
        frames = []
        points = _points(self, lambda j: (ca.cos(q[j]), ca.sin(q[j])), ca.DM.eye(3),
                         ca.DM.zeros(3, 1), frames)
        if not self.ends:
            return [(points[i], points[j]) for i, j in self.links]
        return [tuple(points[i] + _apply(frames[i], end) for end in ends)
                for (i, _), ends in zip(self.links, self.ends, strict=True)]

    @cached_property
    def origin_ends(self) -> tuple:
        """The `ends` of the segments between the link points (m): each link's capsule axis
        when no capsule is fitted."""
        nxt = [*self.translations[1:], self.flange]
        return tuple(((0.0, 0.0, 0.0), tuple(nxt[i])) for i, _ in self.links)

    @cached_property
    def links(self) -> tuple[tuple[int, int], ...]:
        """Index pairs (i, i + 1) into `points` of the links checked for clearance."""
        home = self.points(np.zeros(self.dof))[0]
        fixed = [self._fixed(i, home) for i in range(self.dof + 1)]
        return tuple((i, i + 1) for i in range(self.dof)
                     if (np.linalg.norm(home[i + 1] - home[i]) > AXIS_TOLERANCE
                         or i in self.covered)
                     and not (fixed[i] and fixed[i + 1]))

    @cached_property
    def fixed_points(self) -> tuple[int, ...]:
        """Indices into `points` of the link ends no joint moves (on the axes of every joint
        before them): an obstacle within the threshold of one cannot be avoided."""
        home = self.points(np.zeros(self.dof))[0]
        ends = sorted({i for link in self.links for i in link})
        return tuple(i for i in ends if self._fixed(i, home))

    def _fixed(self, i: int, home: np.ndarray) -> bool:
        """Point i stays put iff it lies on the axes of all joints before it (at q = 0)."""
        rotation = np.eye(3)
        for j in range(i):
            rotation = rotation @ np.asarray(self.rotations[j])
            axis = rotation @ np.asarray(self.axes[j])
            offset = home[i] - home[j]
            if np.linalg.norm(offset - axis * (offset @ axis)) > AXIS_TOLERANCE:
                return False
        return True

    @cached_property
    def link_lengths(self) -> tuple[float, ...]:
        """Length (m) of each link's capsule axis (constant: the chain is rigid between
        joints)."""
        if self.ends:
            return tuple(float(np.linalg.norm(np.subtract(b, a))) for a, b in self.ends)
        home = self.points(np.zeros(self.dof))[0]
        return tuple(float(np.linalg.norm(home[j] - home[i])) for i, j in self.links)

    @property
    def link_radii(self) -> np.ndarray:
        """Capsule radius (m) of each link, zeros when none is given."""
        return np.asarray(self.radii, float) if self.radii else np.zeros(len(self.links))

    @property
    def link_names(self) -> tuple[str, ...]:
        """'link j' for the segment moved by joint j, with its body's name when known."""
        names = []
        for i, _ in self.links:
            body = self.bodies[i] if i < len(self.bodies) else ""
            names.append(f"link {i + 1}" + (f" ({body})" if body else ""))
        return tuple(names)

    def flange_position(self, q) -> np.ndarray:
        """Flange (n, 3) in m at joint angles q (n, dof)."""
        return self.points(q)[:, -1]


def _points(geometry: ArmGeometry, cos_sin, identity, origin, frames: list | None = None) -> list:
    """World positions of the joint origins and the flange: one recursion for numpy
    batches (cos/sin of shape (n, 1, 1)) and CasADi scalars; frames, if given, gets each
    joint frame's world rotation."""
    rotation, position, out = identity, origin, []
    for j in range(geometry.dof):
        position = position + _apply(rotation, geometry.translations[j])
        out.append(position)
        c, s = cos_sin(j)
        rotation = rotation @ _constant(geometry.rotations[j], identity) @ _rodrigues(
            geometry.axes[j], c, s, identity)
        if frames is not None:
            frames.append(rotation)
    out.append(position + _apply(rotation, geometry.flange))
    return out


def _constant(matrix, like):
    return ca.sparsify(ca.DM(_array(matrix))) if isinstance(like, ca.DM) else _array(matrix)


def _apply(rotation, vector):
    """rotation @ vector for a numpy batch (n, 3, 3) or a CasADi 3 x 3."""
    if isinstance(rotation, np.ndarray):
        return rotation @ _array(vector)
    return rotation @ ca.sparsify(ca.DM(_array(vector)))


def _rodrigues(axis, c, s, identity):
    """Rotation by angle (cos c, sin s) about a constant unit axis: c I + s K + (1 - c) a a^T."""
    k, outer = _axis_matrices(axis)
    if isinstance(identity, ca.DM):
        return c * ca.DM.eye(3) + s * ca.sparsify(ca.DM(k)) + (1 - c) * ca.sparsify(ca.DM(outer))
    return c * _EYE + s * k + (1 - c) * outer


_EYE = np.eye(3)


@cache
def _array(values: tuple) -> np.ndarray:
    """A geometry constant (nested tuples) as a read-only array, converted once."""
    array = np.asarray(values, float)
    array.flags.writeable = False
    return array


@cache
def _axis_matrices(axis: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The cross-product matrix K and the outer product a a^T of a unit axis."""
    a = _array(axis)
    return (np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]), np.outer(a, a))


def paper_arm(d1: float = 0.086, l2: float = 0.146, l3: float = 0.187) -> ArmGeometry:
    """The paper's simplified Lynxmotion arm (distal DH, eqs. 9 and 10): joint 1 about the
    vertical at the base, joint 2 at height d1 and joint 3 at the elbow about -y (a positive
    angle lifts the link), the end effector l3 beyond the elbow; m."""
    eye = np.eye(3)
    return ArmGeometry.of([eye, eye, eye], [[0, 0, 0], [0, 0, d1], [l2, 0, 0]],
                          [[0, 0, 1], [0, -1, 0], [0, -1, 0]], [l3, 0, 0], "lynxmotion",
                          ("link1", "link2", "link3"))
