"""Physically consistent identification relative to a nominal model (convex, cvxpy).

The torque of a chain is linear in its candidate atoms' coefficients x
(identification.library.kinematic.atom_names: 10 standard inertial parameters per body -
m, m c, and the rotational inertia about the joint frame's origin, Pinocchio's
toDynamicParameters order - then armature, viscous and Coulomb per joint), tau = A x,
plus an offset per joint and, per joint, the column of its friction law
(identification.friction). The fit is

    minimize  mean_k,j ((tau - A x - offsets - G g) / s_j)^2 + lam * ||(x - nom) / r||^2
    subject to  J_b(x_b) >= 0 (positive semidefinite) for every body b,
                armature, viscous, Coulomb, the laws' coefficients g >= 0,
                tr(J_b Q_b) >= 0 for every body given a bounding ellipsoid Q_b (plausible:
                its mass inside its link, identification.ellipsoids),

where s_j is joint j's noise scale (joint_weights), r a per-parameter scale of the nominal
values (the body's largest, so a link with no nominal inertia is not pinned), and
J_b = [[tr(I)/2 1 - I, h], [h^T, m]] the pseudo-inertia (Wensing, Wensing & Slotine 2017:
a body's (m, h, I) is physically consistent iff J_b is positive semidefinite). lam = 0 is
least squares under the LMI; lam > 0 pulls what the data leave open toward the nominal
model (metric "entropic": by the LogDet divergence of each body's pseudo-inertia from the
nominal's instead of the ridge, PRIOR_METRICS). lam and each joint's friction law are
chosen by validation inside the training data, never on a scored part: with one run on its
last contiguous block; with several runs by leaving each run out in turn (a block of the
same run shares its errors in the derivatives, offsets and temperature, a new run does
not). Several runs have an offset each. Solved by Clarabel (SCS if it fails).
"""

from __future__ import annotations

from dataclasses import dataclass

import cvxpy as cp
import numpy as np

from identification.conic import solve_conic
from identification.friction import FrictionLaw, choose_law
from identification.regression.base import run_centring

LAMBDAS = (1e-6, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)  # ridge weights tried toward the nominal
# how a body's distance from its nominal is measured: "ridge", the squared deviation of its
# 10 parameters in units of the body's scale (ridge_scale); "entropic", the LogDet divergence
# of its pseudo-inertia from the nominal's (Lee, Wensing & Park 2020), which keeps what the
# data leave open a scaled copy of the nominal body, never a degenerate one
# (docs/identification.md, 'Prior metric')
PRIOR_METRICS = ("ridge", "entropic")
TIE = 0.02  # a larger weight must predict the validation block this much better (relative
# mean square), or a prior wins it by chance (docs/identification.md, 'identification.physical')
SCORES = {False: "mean square of the error in units of each joint's weight (its noise), on the block",
          True: "mean over the runs left out of the mean over joints of the squared relative "
                "error, each run's mean residual (its sensor offset) removed"}
WEIGHT_FLOOR = 1e-3  # smallest noise-to-torque ratio of a joint, x the largest (joint_weights:
# a joint whose residual is nil, noise-free data, stays finite)
CONSISTENT_TOL = 1e-8  # smallest pseudo-inertia eigenvalue still consistent (solver accuracy)


def pseudo_inertia(p) -> list:
    """The 4x4 pseudo-inertia of one body's 10 standard parameters (numbers or cvxpy)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = (p[k] for k in range(10))
    half = (ixx + iyy + izz) / 2
    return [[half - ixx, -ixy, -ixz, hx], [-ixy, half - iyy, -iyz, hy],
            [-ixz, -iyz, half - izz, hz], [hx, hy, hz, m]]


def min_pseudo_eigenvalues(params: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue of each body's pseudo-inertia (>= 0: physically consistent)."""
    return np.array([np.linalg.eigvalsh(np.array(pseudo_inertia(b), float)).min()
                     for b in np.asarray(params).reshape(-1, 10)])


@dataclass(frozen=True)
class PhysicalFit:
    """Identified candidate-atom coefficients (13 per joint, atom_names order), offsets, each
    joint's friction law and its column's coefficient, the ridge weight chosen, each body's
    smallest pseudo-inertia eigenvalue, and the validation errors the choices were made on."""

    params: np.ndarray
    offsets: np.ndarray
    laws: tuple[FrictionLaw, ...]
    law_coefficients: np.ndarray
    lam: float
    min_eigenvalues: np.ndarray
    validation: dict

    @property
    def consistent(self) -> bool:
        return bool(np.all(self.min_eigenvalues >= -CONSISTENT_TOL))

    @property
    def dof(self) -> int:
        return len(self.offsets)

    def torque(self, atoms: np.ndarray, qd: np.ndarray, offsets: bool = True) -> np.ndarray:
        """(n, dof) torque from every atom's torque (n, dof, 13 dof) and the velocities;
        offsets False: the robot's torque without the sensor's constant."""
        out = atoms @ self.params + law_columns(self.laws, qd) * self.law_coefficients
        return out + self.offsets if offsets else out


def law_columns(laws, qd: np.ndarray) -> np.ndarray:
    """(n, dof): each joint's own friction column (zeros for viscous-coulomb)."""
    return np.column_stack([law.column(qd[:, j]) if law.has_column else np.zeros(len(qd))
                            for j, law in enumerate(laws)])


def ridge_scale(nominal: np.ndarray, dof: int) -> np.ndarray:
    """Per coefficient, the size a deviation from the nominal is measured in: body b's mass m,
    first moments m rho and inertias m rho^2, rho = sqrt(tr(I_O) / m) its nominal radius of
    gyration about the joint; its joint's armature as its inertias. A body with no nominal
    mass (a frame) is measured by the robot's largest body."""
    bodies = nominal[:10 * dof].reshape(dof, 10)
    mass = np.abs(bodies[:, 0])
    trace = np.abs(bodies[:, 4] + bodies[:, 6] + bodies[:, 9])
    heavy = int(np.argmax(mass))
    if mass[heavy] <= 0:
        mass, trace = np.ones(dof), np.ones(dof)
    light = mass < 1e-3 * mass[heavy]
    mass[light], trace[light] = mass[heavy], trace[heavy]
    rho2 = np.maximum(trace / mass, 1e-6)
    per_body = np.column_stack([mass, *(3 * [mass * np.sqrt(rho2)]), *(6 * [mass * rho2])])
    return np.concatenate([per_body.ravel(), mass * rho2, np.ones(2 * dof)])


def _prior_cost(x, y, nominal: np.ndarray, dof: int, metric: str):
    """The prior's distance of the inertial and armature coefficients from the nominal (not
    the friction's): PRIOR_METRICS. The entropic one, per body whose nominal pseudo-inertia
    J0 is positive definite, tr(S J S) - log det(S J S) with S = J0^(-1/2) (the LogDet
    divergence up to a constant; the body's ridge otherwise), the armature's ridge beside."""
    if metric == "ridge":
        return cp.sum_squares(y[:11 * dof])
    cost = cp.sum_squares(y[10 * dof:11 * dof])
    for k in range(dof):
        j0 = np.array(pseudo_inertia(nominal[10 * k:10 * k + 10]), float)
        w, v = np.linalg.eigh(j0)
        if w.min() <= 1e-12 * max(1.0, w.max()):
            cost = cost + cp.sum_squares(y[10 * k:10 * k + 10])
            continue
        root = (v / np.sqrt(w)) @ v.T  # J0^(-1/2): the nominal body becomes the identity
        body = root @ cp.bmat(pseudo_inertia(x[10 * k:10 * k + 10])) @ root
        body = (body + body.T) / 2
        cost = cost + cp.trace(body) - cp.log_det(body)
    return cost


def _solve(A, tau, law_cols, laws, scale, nominal, lam: float, used: list[str], bounds=None,
           metric: str = "ridge"):
    """The fit at ridge weight lam; the solver it took appended to used. bounds: per body a
    4x4 ellipsoid matrix Q (identification.ellipsoids) its mass must lie inside, or None."""
    n, dof, p = A.shape
    # in units of the nominal's scale about the nominal (x = nominal + ref y): a light arm's
    # 1e-4 kg m^2 inertias and its ridge's 1e8 weights otherwise stall the interior point
    ref = ridge_scale(nominal, dof)
    y, off, g = cp.Variable(p), cp.Variable(dof), cp.Variable(dof)
    x = nominal + cp.multiply(ref, y)
    eye = np.broadcast_to(np.eye(dof), (n, dof, dof))
    cols = np.concatenate([A * ref, eye, law_cols[:, :, None] * np.eye(dof)], axis=2)
    a = (cols / scale[None, :, None]).reshape(n * dof, -1)
    b = ((tau - A @ nominal) / scale).reshape(-1)
    # the squared error through a's QR factors (the problem's size is its columns'; R may
    # be singular: parameters the data do not excite, held by the LMI and the ridge)
    q, r = np.linalg.qr(a / np.sqrt(len(b)))
    c = q.T @ (b / np.sqrt(len(b)))
    cost = cp.sum_squares(r @ cp.hstack([y, off, g]) - c)
    if lam > 0:
        cost = cost + lam * _prior_cost(x, y, nominal, dof, metric)
    constraints = [(j + j.T) / (2 * ref[10 * k]) >> 0 for k, j in
                   enumerate(cp.bmat(pseudo_inertia(x[10 * k:10 * k + 10])) for k in range(dof))]
    constraints += [x[10 * dof:] >= 0, g >= 0]
    for k, q in enumerate(bounds or ()):  # plausible: the mass inside its link's ellipsoid
        if q is not None:
            body = cp.bmat(pseudo_inertia(x[10 * k:10 * k + 10]))
            constraints.append(cp.trace(body @ q) / ref[10 * k] >= 0)
    for j, law in enumerate(laws):
        if not law.has_column:
            constraints.append(g[j] == 0)
        if not law.keeps_coulomb:
            constraints.append(x[12 * dof + j] == 0)
    problem = cp.Problem(cp.Minimize(cost), constraints)
    used.append(solve_conic(problem, "the consistent fit", stacklevel=4))
    if y.value is None:
        raise ValueError(f"the consistent fit did not solve ({problem.status})")
    # armature, friction and the laws' coefficients are >= 0 only to the solver's tolerance
    # (-1.5e-11 N m seen): exactly, or an exported model is refused (Pinocchio reads a
    # negative <dynamics friction> as min > max dry friction)
    fitted = np.asarray(x.value)
    fitted[10 * dof:] = np.maximum(fitted[10 * dof:], 0.0)
    return fitted, np.asarray(off.value), np.maximum(np.asarray(g.value), 0.0)


def _predict(A, law_cols, fitted) -> np.ndarray:
    x, off, g = fitted
    return A @ x + off + law_cols * g


def choose_weight(lambdas, errors, tie: float = TIE) -> float:
    """The smallest weight whose validation error is within `tie` (relative) of the best:
    where validation cannot tell, the data and not the nominal decide."""
    return float(min(w for w, e in zip(lambdas, errors, strict=True) if e <= (1 + tie) * min(errors)))


def _relative(pred: np.ndarray, tau: np.ndarray) -> float:
    """A run left out, its data centred: the mean over joints of the squared relative error
    once the run's mean residual (its own sensor offset) is removed."""
    error = pred - tau
    error = error - error.mean(axis=0)
    return float(np.mean(np.mean(error**2, axis=0) / np.maximum(np.mean(tau**2, axis=0), 1e-300)))


def _rows(runs, n: int, validation: float) -> np.ndarray:
    """True on the samples the validation predicts: the last `validation` fraction of each
    run (of the whole set without runs), so that every run is both fitted and judged."""
    runs = np.zeros(n, int) if runs is None else np.asarray(runs)
    held = np.zeros(n, bool)
    for r in np.unique(runs):
        at = np.flatnonzero(runs == r)
        held[at[int(round(len(at) * (1 - validation))):]] = True
    return held


def joint_weights(A: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Per joint, the scale its residual is measured in: its noise (the residual std of the
    joint's own least squares on every atom with an offset, which no other joint's noise
    enters; the oracle weighs by its residual too), normalized so that the joints'
    noise-to-torque-std ratios have an RMS of one (the ridge weights keep their meaning); a
    ratio at least WEIGHT_FLOOR of the largest. Each joint's torque std instead let a sensor
    noise of one size on every joint weigh a loaded joint's residual tens of times too little
    (docs/identification.md, 'identification.physical')."""
    spread = np.maximum(tau.std(axis=0), 1e-9)
    ratio = np.empty(len(spread))
    for j in range(len(spread)):
        design = np.column_stack([A[:, j], np.ones(len(A))])
        coef = np.linalg.lstsq(design, tau[:, j], rcond=None)[0]
        ratio[j] = np.std(tau[:, j] - design @ coef) / spread[j]
    if ratio.max() <= 1e-12:  # noise-free: no noise to weigh by
        return spread
    ratio = np.maximum(ratio, WEIGHT_FLOOR * ratio.max())
    return spread * ratio / np.sqrt(np.mean(ratio**2))


def fit_physical(atoms: np.ndarray, qd: np.ndarray, tau: np.ndarray, nominal: np.ndarray,
                 lambdas=LAMBDAS, validation: float = 0.2, choose_friction: bool = True,
                 runs=None, bounds=None, metric: str = "ridge") -> PhysicalFit:
    """The consistent fit of tau (n, dof) on every atom's torque (n, dof, 13 dof), offsets and
    friction, pulled toward the nominal coefficients (13 dof) with the lam of `lambdas` that
    predicts best what it was not fitted on: with one run, its last `validation` fraction
    fitted on the rest; with several runs, each run left out in turn, fitted on the others
    (SCORES); each joint's friction law chosen on the same split (choose_friction, with
    several runs on the rigid body fitted on them all); refitted on all. validation records
    what was chosen on ("chosen_on"). runs: (n,) run labels of several runs, each with its
    own sensor offset (the fit's offsets are their mean over the samples); None: one run.
    bounds: per body an ellipsoid matrix Q (identification.ellipsoids) or None: the body's
    mass held inside (plausible).
    metric: the prior's distance from the nominal (PRIOR_METRICS)."""
    A, qd, tau, nominal = (np.asarray(x, float) for x in (atoms, qd, tau, nominal))
    n, dof, _ = A.shape
    several, centred = run_centring(runs)
    raw_A, raw_tau, A, tau = A, tau, centred(A), centred(tau)
    scale = joint_weights(A, tau)
    used, laws = [], (FrictionLaw(),) * dof
    cols = centred(law_columns(laws, qd))

    def solve(rows, lam, cols):  # viscous-Coulomb on every joint
        return _solve(A[rows], tau[rows], cols[rows], laws, scale, nominal, lam, used, bounds, metric)

    if several:  # leave one run out: fitted on the others, scored on it
        labels = np.asarray(runs)
        folds = [labels == r for r in np.unique(labels)]
        errors = [float(np.mean([_relative(_predict(A[out], cols[out], solve(~out, lam, cols)),
                                           tau[out]) for out in folds])) for lam in lambdas]
        fit, on = np.ones(n, bool), f"leave one run out over {len(folds)} runs"
    else:  # the last `validation` of the run predicted from the rest
        held = _rows(None, n, validation)
        fit, on = ~held, f"blocks of one run (the last {validation:.0%} predicted from the rest)"
        errors = [float(np.mean(((_predict(A[held], cols[held], solve(fit, lam, cols))
                                  - tau[held]) / scale) ** 2)) for lam in lambdas]
    lam = choose_weight(lambdas, errors)
    chosen = {}
    if choose_friction:
        x = solve(fit, lam, cols)[0]
        rigid = A[:, :, :11 * dof] @ x[:11 * dof]  # the rigid body and the armature
        coulomb = A[:, :, 12 * dof:].diagonal(axis1=1, axis2=2)
        picks = [choose_law(tau[:, j] - rigid[:, j], qd[:, j], coulomb[:, j],
                            runs=labels if several else None) for j in range(dof)]
        laws = tuple(p[0] for p in picks)
        rigid_on = " (the rigid body fitted on every run)" if several else ""
        chosen = {"friction_chosen_on": on + rigid_on,
                  "friction_errors": [{law.name: min(e for other, e in p[1] if other.name == law.name)
                                       for law, _ in p[1]} for p in picks]}
        cols = centred(law_columns(laws, qd))
    x, off, g = _solve(A, tau, cols, laws, scale, nominal, lam, used, bounds, metric)
    if several:  # one offset for the model: the runs' mean
        off = np.mean(raw_tau - raw_A @ x - law_columns(laws, qd) * g, axis=0)
    return PhysicalFit(x, off, laws, g, lam, min_pseudo_eigenvalues(x[:10 * dof]),
                       {"chosen_on": on, "score": SCORES[several], "lambdas": list(lambdas),
                        "lambda_errors": errors, **chosen,
                        "solver": "SCS" if "SCS" in used else "CLARABEL"})
