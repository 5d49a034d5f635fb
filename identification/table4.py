"""The benchmark systems of Table IV, simulated with the paper's true coefficients.

Each system is a set of torque (force) equations given as {feature name:
coefficient}, exactly as printed in the paper (the double-pendulum pair is
used as printed, although as a Lagrangian system it is not self-consistent:
eq. 1 carries theta1-dot^2 where physics has theta2-dot^2). Joint order:
mass-spring-damper q1 = x; double pendulum q1, q2 = theta1, theta2;
spherical pendulum q1 = theta (polar), q2 = phi (azimuth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.features import parse_feature
from identification.libraries import generic_library
from identification.signals import Motion, multisine


@dataclass(frozen=True)
class System:
    """A Table IV row: true and paper-identified equations, and how to excite it."""

    name: str
    dof: int
    true: tuple[dict[str, float], ...]
    paper: tuple[dict[str, float], ...]
    centre: tuple[float, ...]
    amplitude: tuple[float, ...]
    order: int  # trig order of its generic library (0: polynomial only)

    def library(self) -> Library:
        return generic_library(self.dof, self.order)

    def motion(self, n: int = 4000, seed: int = 7) -> Motion:
        """Slow multi-sine (60 s, <= 0.6 Hz) so gravity is not drowned by inertia."""
        return multisine(n, self.dof, seed, self.centre, self.amplitude, 60.0, base_hz=0.03)

    def torque(self, m: Motion) -> np.ndarray:
        cols = []
        for eq in self.true:
            cols.append(sum(c * parse_feature(n, self.dof).evaluate(m.q, m.qd, m.qdd)
                            for n, c in eq.items()))
        return np.column_stack(cols)


SYSTEMS = (
    System("mass-spring-damper", 1, ({"qdd1": 1.0, "qd1": 2.0, "q1": 100.0},),
           ({"qdd1": 1.0, "qd1": 2.02, "q1": 100.67},), (0.0,), (0.5,), 0),
    System("double pendulum", 2,
           ({"qdd1": 3.0, "qdd2*cos(q1-q2)": 2.0, "qd1^2*sin(q1-q2)": 2.0, "sin(q1)": 29.4},
            {"qdd2": 2.0, "qdd1*cos(q1-q2)": 1.0, "qd1^2*sin(q1-q2)": -1.0, "sin(q2)": 9.8}),
           ({"qdd1": 2.99, "qdd2*cos(q1-q2)": 2.04, "qd1^2*sin(q1-q2)": 2.02, "sin(q1)": 29.47},
            {"qdd2": 2.03, "qdd1*cos(q1-q2)": 0.99, "qd1^2*sin(q1-q2)": -0.99, "sin(q2)": 9.78}),
           (0.0, 0.0), (1.2, 1.2), 1),
    System("spherical pendulum", 2,
           ({"qdd2*sin(q1)^2": 2.0, "qd1*qd2*sin(q1)*cos(q1)": 4.0},
            {"qdd1": 2.0, "qd2^2*sin(q1)*cos(q1)": -2.0, "sin(q1)": 19.6}),
           ({"qdd2*sin(q1)^2": 1.99, "qd1*qd2*sin(q1)*cos(q1)": 3.97},
            {"qdd1": 1.98, "qd2^2*sin(q1)*cos(q1)": -2.05, "sin(q1)": 19.53}),
           (1.0, 0.0), (0.7, 2.0), 2),
)
