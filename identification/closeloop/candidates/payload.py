"""A payload rigidly attached to the last body (or the body a gripper's jaw turns on,
harness.robots.bodies.last_body): its 10 inertial parameters, fitted physically
consistent and plausible, as one candidate of the close-the-loop dictionary.

The torque of a chain is linear in the last body's standard parameters
pi = (m, m c, I_O) (identification.library.chain: PARAMETERS order, the rotational inertia
about the last joint frame's origin), so a payload adds Y(q, qd, qdd) pi, Y the last body's
columns of the joint-torque regressor (the Jacobian of the chain's RNEA in pi, LastBody).
A fit of pi is

    minimize  ||W (target - base b - effects c - Y pi)||^2
    subject to  J(pi) >= 0 (the pseudo-inertia positive semidefinite: Wensing, Wensing &
                Slotine 2017) and ||m c|| <= reach m (the centre of mass within `reach` m of
                the last joint's origin), m >= 0,

a convex problem (cvxpy, Clarabel) on the QR-reduced design, so solving it is cheap however
many samples there are. As a selection candidate the payload is one column, Y pi / m with pi
fitted on all the training runs (its shape, as a Coulomb term's is fitted), its coefficient
the mass in kg; once named, its 10 parameters are refitted jointly with the other named
effects and the runs' offsets (consistent_fit).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import cvxpy as cp
import numpy as np

from identification.conic import solve_conic
from identification.library.chain import KinematicChain, rnea
from identification.physical import pseudo_inertia
from identification.torque_model import as_states

REACH = 0.4  # m, default bound on the payload's centre of mass from the last joint
MIN_MASS = 1e-6  # kg: a fitted payload lighter than that is no candidate


@dataclass(frozen=True)
class LastBody:
    """The body a payload rides on, the chain's last by default: the torque regressor of its
    10 standard parameters (in its joint's frame)."""

    chain: KinematicChain
    name: str  # the link's name (the body a payload is reported on)
    joint: int = 0  # the joint (1..dof) that moves the body; 0: the last

    @cached_property
    def function(self) -> ca.Function:
        dof = self.chain.dof
        at = self.joint or dof
        q, qd, qdd = (ca.SX.sym(s, dof) for s in ("q", "qd", "qdd"))
        p = ca.SX.sym("p", 10)
        tau = rnea(self.chain, q, qd, qdd, ca.vertcat(ca.SX.zeros(10 * (at - 1)), p,
                                                      ca.SX.zeros(10 * (dof - at))))
        return ca.Function("last_body", [q, qd, qdd], [ca.jacobian(tau, p)])

    def __call__(self, q, qd, qdd) -> np.ndarray:
        """(n, dof, 10) torque per unit parameter at states (n, dof)."""
        n, dof = np.shape(q)
        out = self.function.map(n)(np.asarray(q, float).T, np.asarray(qd, float).T,
                                   np.asarray(qdd, float).T)
        return np.asarray(out).reshape(dof, n, 10).transpose(1, 0, 2)

    def symbolic(self, q, qd, qdd):
        """(dof, 10) CasADi regressor at column vectors."""
        return self.function(q, qd, qdd)


class BodyTorque:
    """The torque model of a payload with parameters params on body (a TorqueModel)."""

    def __init__(self, body: LastBody, params):
        self.body, self.params, self.dof = body, np.asarray(params, float), body.chain.dof

    def torque(self, q, qd, qdd) -> np.ndarray:
        q, qd, qdd = as_states(q, qd, qdd, self.dof)
        return self.body(q, qd, qdd) @ self.params

    def symbolic_torque(self, q, qd, qdd):
        return self.body.symbolic(q, qd, qdd) @ ca.DM(self.params)


def describe(params) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass kg, centre of mass (3,) m, rotational inertia about the centre of mass
    (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) kg m^2) of standard parameters, in the body's frame."""
    p = np.asarray(params, float)
    m = float(p[0])
    c = p[1:4] / m if m > 0 else np.zeros(3)
    about_com = p[4:] - m * np.array([c[1]**2 + c[2]**2, -c[0] * c[1], c[0]**2 + c[2]**2,
                                      -c[0] * c[2], -c[1] * c[2], c[0]**2 + c[1]**2])
    return m, c, about_com


def standard(mass: float, com, inertia) -> np.ndarray:
    """Standard parameters of a mass, centre of mass and inertia about it (describe's inverse)."""
    c, i = np.asarray(com, float), np.asarray(inertia, float)
    shift = mass * np.array([c[1]**2 + c[2]**2, -c[0] * c[1], c[0]**2 + c[2]**2,
                             -c[0] * c[2], -c[1] * c[2], c[0]**2 + c[1]**2])
    return np.concatenate([[mass], mass * c, i + shift])


def consistent_fit(base, target, effects, regressor, w, reach: float = REACH,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients of the base (p,), the effects (k,) and the payload's parameters (10,)
    fitted jointly by weighted least squares, the payload consistent and within reach.

    base (n, dof, p), effects (n, dof, k), regressor (n, dof, 10), target (n, dof), w (dof,)."""
    p, k = base.shape[2], effects.shape[2]
    design = np.concatenate([base, effects, regressor], axis=2) * w[None, :, None]
    scale = np.maximum(np.linalg.norm(design.reshape(-1, design.shape[2]), axis=0), 1e-12)
    a = design.reshape(-1, design.shape[2]) / scale
    qm, r = np.linalg.qr(a)
    z = qm.T @ (target * w).ravel()
    v = cp.Variable(a.shape[1])
    x = cp.multiply(v[p + k:], 1.0 / scale[p + k:])
    j = cp.bmat(pseudo_inertia(x))
    problem = cp.Problem(cp.Minimize(cp.sum_squares(r @ v - z)),
                         [(j + j.T) / 2 >> 0, cp.norm(x[1:4]) <= reach * x[0]])
    solve_conic(problem, "the payload fit")
    if v.value is None:
        raise ValueError(f"payload fit failed ({problem.status})")
    coef = np.asarray(v.value) / scale
    return coef[:p], coef[p:p + k], coef[p + k:]


def payload_column(base, target, regressor, w, reach: float = REACH, beside=None) -> tuple | None:
    """The payload candidate: (its unit-mass torque column (n, dof), its parameters per kg,
    its parameters as fitted), the shape fitted beside the base alone (and the columns beside
    (n, dof, k) when given); None if the fit gives no mass."""
    beside = np.zeros((*target.shape, 0)) if beside is None else beside
    _, _, params = consistent_fit(base, target, beside, regressor, w, reach)
    if params[0] < MIN_MASS:
        return None
    unit = params / params[0]
    return regressor @ unit, unit, params


def com_spread(base, target, effects, regressor, w, rows: list[np.ndarray], blocks: int,
               reach: float = REACH) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per run (rows: its sample indices): the payload's mass (kg), centre of mass (3,) m and
    the centre of mass's standard error (3,) m from its spread over `blocks` blocks of the run,
    each fitted jointly with the effects (their coefficients free) and the offsets."""
    mass, com, std = [], [], []
    for run in rows:
        m, c, _ = describe(consistent_fit(base[run], target[run], effects[run], regressor[run],
                                          w, reach)[2])
        parts = [describe(consistent_fit(base[b], target[b], effects[b], regressor[b], w,
                                         reach)[2])[1] for b in np.array_split(run, blocks)]
        mass.append(m)
        com.append(c)
        std.append(np.std(parts, axis=0, ddof=1) / np.sqrt(blocks))
    return np.array(mass), np.array(com), np.array(std)


def com_agreement(com: np.ndarray, std: np.ndarray, within: float) -> bool:
    """Whether the runs' centres of mass (runs, 3) m agree within `within` combined standard
    errors (the measured loop holds them to the runs' coefficients' rule,
    identification.closeloop.verdicts.agreement.AGREE: within one, two runs of one load would disagree
    one time in three)."""
    diff = np.abs(com[:, None] - com[None, :])
    return bool(np.all(diff <= within * np.hypot(std[:, None], std[None, :]) + 1e-12))


def named_payload(base, target, cols, regressor, w, chosen: list[int], k: int,
                  rows: list[np.ndarray], blocks: int, within: float, reach: float = REACH,
                  ) -> tuple:
    """The joint fit once the payload (candidate k of cols) is among the chosen: the base's
    coefficients, the chosen effects' (the payload's = its mass) in chosen order, its 10
    parameters and, with several runs, what each run alone gives (mass, centre of mass and
    its standard error) and whether the centres of mass agree (com_agreement)."""
    others = [i for i in chosen if i != k]
    coef_base, coef, params = consistent_fit(base, target, cols[:, :, others], regressor, w,
                                             reach)
    values = dict(zip(others, coef, strict=True))
    values[k] = params[0]
    detail: dict = {}
    if len(rows) > 1:
        mass, com, std = com_spread(base, target, cols[:, :, others], regressor, w, rows,
                                    blocks, reach)
        agree = com_agreement(com, std, within)
        detail = {"per_run_mass": mass.tolist(), "per_run_com": com.tolist(),
                  "per_run_com_std": std.tolist(), "com_agrees": agree,
                  "com_note": (f"the runs' centres of mass agree within {within:g} combined standard errors"
                               if agree else "the runs' centres of mass disagree beyond their "
                               "standard errors: each run's is reported (per_run_com), the "
                               "joint fit's is a compromise, not a measurement")}
    return coef_base, np.array([values[i] for i in chosen]), params, detail
