"""Bounding ellipsoids of bodies: physically plausible identified bodies.

A body of pseudo-inertia J (identification.physical.pseudo_inertia) has all its mass inside
the ellipsoid {x : (x - c)^T S^-2 (x - c) <= 1} if tr(J Q) >= 0 with

    Q = [[-S^-2, S^-2 c], [c^T S^-2, 1 - c^T S^-2 c]]

(Wensing, Kim & Slotine 2017, "Linear matrix inequalities for physically consistent inertial
parameter identification", the density realizability of the second moment on the
ellipsoid). It is linear in the body's standard parameters, so it joins the consistent
fit's LMI as one more convex row. Here: Q of an ellipsoid, the smallest ellipsoid holding a
set of points (the link's geometry), and an ellipsoid grown to hold a nominal body.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from identification.conic import solve_conic

MARGIN = 0.05  # a nominal body at least this fraction of its mass inside (tr(J Q) / m)
MAX_POINTS = 400  # hull vertices the enclosing ellipsoid is fitted on
GROWTH = 1.1  # semi-axes' factor per step while growing an ellipsoid to hold a body


@dataclass(frozen=True)
class Ellipsoid:
    """{centre + axes @ diag(semi_axes) u : |u| <= 1} (m, in the body's joint frame); source
    says where it comes from (the link's geometry, its growth to hold a body)."""

    centre: np.ndarray
    semi_axes: np.ndarray
    axes: np.ndarray
    source: str = ""

    @property
    def matrix(self) -> np.ndarray:
        """Q (4x4): the body is inside iff tr(J Q) >= 0 (module docstring)."""
        c = np.asarray(self.centre, float)
        s2 = self.axes @ np.diag(1.0 / np.asarray(self.semi_axes, float) ** 2) @ self.axes.T
        return np.block([[-s2, (s2 @ c)[:, None]], [(s2 @ c)[None, :], np.array([[1 - c @ s2 @ c]])]])

    def scaled(self, factor: float, note: str = "") -> Ellipsoid:
        return Ellipsoid(self.centre, self.semi_axes * factor, self.axes,
                         f"{self.source}; {note}" if note and self.source else note or self.source)

    def to_dict(self) -> dict:
        return {"centre": np.asarray(self.centre).tolist(), "semi_axes": np.asarray(self.semi_axes).tolist(),
                "axes": np.asarray(self.axes).tolist(), "unit": "m", "source": self.source}


def inside(pseudo: np.ndarray, ellipsoid: Ellipsoid) -> float:
    """tr(J Q) for a body's 4x4 pseudo-inertia J: >= 0 iff its mass can lie inside (kg)."""
    return float(np.trace(np.asarray(pseudo, float) @ ellipsoid.matrix))


def enclosing(points: np.ndarray, thickness: float = 0.01) -> Ellipsoid:
    """The smallest-volume ellipsoid holding the points (n, 3) grown by `thickness` (m) in
    every direction (so that flat or thin geometry gives a bounded ellipsoid): max log det A
    s.t. |A p + b| <= 1 on the points' convex hull vertices (Boyd & Vandenberghe 8.4.1)."""
    pts = _hull(np.asarray(points, float).reshape(-1, 3))
    pad = thickness * np.vstack([np.eye(3), -np.eye(3)])
    pts = _hull((pts[:, None, :] + pad[None]).reshape(-1, 3))
    # a mesh's hull may have thousands of vertices: the ellipsoid is fitted on an even
    # subset, then scaled to hold every point
    fitted = pts[np.linspace(0, len(pts) - 1, min(len(pts), MAX_POINTS)).astype(int)]
    centre0, spread = fitted.mean(axis=0), max(float(np.ptp(fitted, axis=0).max()), thickness)
    unit = (fitted - centre0) / spread  # conditioned for the solver
    a, b = cp.Variable((3, 3), PSD=True), cp.Variable(3)
    problem = cp.Problem(cp.Maximize(cp.log_det(a)), [cp.norm(unit @ a + b[None, :], axis=1) <= 1])
    with warnings.catch_warnings():  # an inaccurate optimum is still an ellipsoid: held below
        warnings.filterwarnings("ignore", "the bounding ellipsoid: Clarabel stopped short")
        solve_conic(problem, "the bounding ellipsoid", stacklevel=4)
    if a.value is None:
        raise ValueError(f"no enclosing ellipsoid ({problem.status})")
    values, vectors = np.linalg.eigh(np.asarray(a.value))
    centre = -np.linalg.solve(np.asarray(a.value), np.asarray(b.value))
    found = Ellipsoid(centre0 + spread * centre, spread / np.maximum(values, 1e-12), vectors)
    reach = np.linalg.norm((pts - found.centre) @ found.axes / found.semi_axes, axis=1).max()
    return found.scaled(max(1.0, float(reach)))  # every point inside, whatever the accuracy


def _hull(points: np.ndarray) -> np.ndarray:
    """The vertices of the points' convex hull (the points themselves if they are flat)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return points[ConvexHull(points).vertices]
    except QhullError:
        return points


def holding(ellipsoid: Ellipsoid, pseudo: np.ndarray, whose: str = "the nominal body",
            margin: float = MARGIN) -> Ellipsoid:
    """The ellipsoid grown about its centre until the body of pseudo-inertia J is inside with
    `margin` of its mass to spare (a nominal model outside its own bound is a wrong bound,
    not a wrong model: the bound must let the prior be feasible)."""
    mass = float(np.asarray(pseudo)[3, 3])
    for step in range(200):
        grown = ellipsoid.scaled(GROWTH ** step)
        if inside(pseudo, grown) >= margin * mass:
            return ellipsoid if step == 0 else ellipsoid.scaled(
                GROWTH ** step, f"grown {GROWTH ** step:.3g}x to hold {whose}")
    raise ValueError("a body's ellipsoid cannot be grown to hold its nominal inertia")
