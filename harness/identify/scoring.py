"""Identification of any robot, scored against the oracle on motions it was not fitted on.

The oracle is two-step weighted least squares on Pinocchio's joint-torque regressor reduced
to base parameters, plus per-joint viscous and armature columns (the joint terms MuJoCo's
inverse dynamics adds): unbiased weighted least squares on the true structure, with no
prior. It is a reference, not a bound: a fit that uses prior knowledge (the consistency LMI,
a nominal model) can have a lower error, and that is not an error.
Models are judged on two motions never used in fitting: a fresh run of `generate`'s own
excitation family (another seed), and a motion of another family (`sines_motion`: a few
sines of random frequency, amplitude and phase per joint), so that no figure rests on the
excitation the project designed alone.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from harness.data.generate import SAMPLE_RATE, generate, inverse_torques
from harness.identify.selection import kept_terms
from harness.robots.arm import Arm
from harness.robots.baseline import PinocchioModel
from identification.identify import identify
from identification.library.kinematic import KinematicLibrary
from identification.metrics import rel_error
from identification.regression.consistent import ConsistentRegressor
from identification.regression.oracle import BaseParameterRegression
from identification.regression.torque import TorqueRegressor

SAMPLES, NOISE, HOLDOUT = 4000, 0.05, 0.25
ORACLE = "unbiased weighted least squares on the true base-parameter structure, no prior"
# the consistent fit pulled toward a URDF whose inertias are off, and without the pull; both
# keep each body inside its link's ellipsoid, which is grown to hold the URDF's own body
# (identification.ellipsoids): where the URDF generated the data, that bound holds the truth
PRIOR = "consistent, perturbed URDF prior"
FLAT = "consistent, no prior (bounds grown to hold the URDF's bodies)"
FILL = 0.85  # of each joint's range the sines motion may sweep


@dataclass(frozen=True)
class Motion:
    """Joint states (n, dof) and the clean torque MuJoCo's inverse dynamics gives there."""

    name: str
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau_clean: np.ndarray


def oracle_design(baseline: PinocchioModel, q, qd, qdd) -> np.ndarray:
    """(n, dof, 10 nb + 2 dof): Pinocchio's regressor, then viscous (qd_j) and armature
    (qdd_j) columns acting on joint j alone."""
    n, dof = q.shape
    joint = np.zeros((n, dof, 2 * dof))
    idx = np.arange(dof)
    joint[:, idx, idx], joint[:, idx, dof + idx] = qd, qdd
    return np.concatenate([baseline.regressor(q, qd, qdd), joint], axis=2)


@dataclass(frozen=True)
class Spectrum:
    """A sum-of-sines family: sines per joint in [count[0], count[1]), frequencies uniform in
    band (Hz), the fraction `fill` of each joint's range swept, and the seed's stream."""

    count: tuple[int, int] = (3, 7)
    band: tuple[float, float] = (0.05, 1.0)
    fill: float = FILL
    stream: int = 7919


def sines_motion(arm: Arm, samples: int, seed: int, rate: float = SAMPLE_RATE,
                 spectrum: Spectrum = Spectrum()) -> Motion:
    """A motion of another family than generate's Fourier series: per joint 3 to 6 sines of
    random frequencies (0.05-1 Hz), amplitudes and phases, scaled into FILL of the joint's
    range (unlimited joints: of [-pi, pi]); torque by mj_inverse on the robot's plant.
    Another spectrum gives another family (harness.identify.generalization)."""
    lower, upper = arm.position_limits
    rng = np.random.default_rng([seed, spectrum.stream])
    t = np.arange(samples) / rate
    q, qd, qdd = (np.zeros((samples, arm.dof)) for _ in range(3))
    for j in range(arm.dof):
        k = int(rng.integers(*spectrum.count))
        w = 2 * np.pi * rng.uniform(*spectrum.band, k)
        a, phi = rng.uniform(0.2, 1.0, k), rng.uniform(0, 2 * np.pi, k)
        s = np.sin(np.outer(t, w) + phi)
        shape = s @ a
        lo, hi = shape.min(), shape.max()
        scale = spectrum.fill * (upper[j] - lower[j]) / (hi - lo)
        centre = 0.5 * (lower[j] + upper[j]) - scale * 0.5 * (lo + hi)
        q[:, j] = centre + scale * shape
        qd[:, j] = scale * (np.cos(np.outer(t, w) + phi) @ (a * w))
        qdd[:, j] = -scale * (s @ (a * w**2))
    return Motion("sines", q, qd, qdd, inverse_torques(arm.mujoco, q, qd, qdd))


def generated_motion(arm: Arm, samples: int, seed: int) -> Motion:
    """A noise-free run of generate's own excitation family."""
    data = generate(arm, samples, 0.0, seed, "inverse")
    return Motion("fresh", data.q, data.qd, data.qdd, data.tau_clean)


def oracle_fit(baseline: PinocchioModel, data, n_train: int) -> tuple[BaseParameterRegression, float]:
    """The oracle fitted on the first n_train samples of data; its CPU seconds."""
    cpu = time.process_time()
    oracle = BaseParameterRegression().fit(
        oracle_design(baseline, data.q[:n_train], data.qd[:n_train], data.qdd[:n_train]),
        data.tau[:n_train])
    return oracle, time.process_time() - cpu


@dataclass(frozen=True)
class Fit:
    """A library and the regressor fitted on a draw (by the draw's seed), for score_draw."""

    library: object
    regressor: Callable[[int], TorqueRegressor]

    @property
    def parameters(self) -> int:
        """Candidate coefficients the fit chooses among."""
        return self.regressor(0).parameters(self.library)


def fixed_fit(library, regressor: TorqueRegressor) -> Fit:
    """The same regressor on every draw."""
    return Fit(library, lambda seed: regressor)


def perturbed_prior_fit(library: KinematicLibrary, baseline: PinocchioModel,
                        ellipsoids=None, regressor: ConsistentRegressor | None = None) -> Fit:
    """The physically consistent fit on a robot's atoms with the nominal prior, its inertias
    perturbed per draw (perturbed_nominal, seeded by the draw), so that no figure comes from
    reading the truth; ellipsoids: the bodies' bounds (plausible, as identify's default).
    regressor: the consistent fit to give the perturbed prior (`identify --prior nominal`'s,
    arm_identification; its own ellipsoids then), by default ConsistentRegressor's."""
    regressor = regressor or ConsistentRegressor(ellipsoids=ellipsoids)
    return Fit(library, lambda seed: replace(regressor, nominal=perturbed_nominal(baseline, seed)))


def score_draw(data, fits: dict[str, Fit], baseline: PinocchioModel, judges: list[Motion]) -> dict:
    """Each fit's identification and the oracle on one dataset (the first 1 - HOLDOUT
    trains), scored on every judge motion against its clean torque: relative RMS error per
    joint (a coupled sparse fit's kept terms under 'kept'); the model of each fit kept under
    'models'."""
    n = int(round(len(data.q) * (1 - HOLDOUT)))
    seed = int(data.meta["seed"])
    out: dict = {"seed": seed, "models": {}}
    for name, fit in fits.items():
        cpu = time.process_time()
        result = identify(data.q, data.qd, data.qdd, data.tau, fit.library, HOLDOUT,
                          data.tau_clean, fit.regressor(seed))
        cpu = time.process_time() - cpu
        out["models"][name] = result.model
        out[name] = {m.name: rel_error(result.model.torque(m.q, m.qd, m.qdd), m.tau_clean).tolist()
                     for m in judges}
        out[name]["timing"] = {"cpu_s": cpu}
        kept = kept_terms(result)
        if kept is not None:  # a coupled sparse fit: the terms its selection kept
            out[name]["kept"] = kept
        if result.physical and "plausible" in result.physical:  # each body inside its link
            out[name]["plausible"] = [bool(p) for p in result.physical["plausible"]]
    oracle, cpu = oracle_fit(baseline, data, n)
    out["oracle"] = {m.name: rel_error(oracle.predict(oracle_design(baseline, m.q, m.qd, m.qdd)),
                                       m.tau_clean).tolist() for m in judges}
    out["oracle"]["timing"] = {"cpu_s": cpu}
    out["oracle_parameters"] = len(oracle.columns_)
    return out


def ratios(draws: list[dict], method: str, judge: str) -> np.ndarray:
    """(draws, dof) error ratios of method to the oracle on the judge motion."""
    return np.array([np.array(d[method][judge]) / np.maximum(np.array(d["oracle"][judge]), 1e-300)
                     for d in draws])


def ratio_summary(draws: list[dict], method: str, judge: str) -> dict:
    """The ratios to the oracle on judge: median over draws per joint, the worst draw's
    median over joints, the worst joint of any draw."""
    r = ratios(draws, method, judge)
    return {"median_ratio_per_joint": np.median(r, axis=0).tolist(),
            "worst_median": float(np.median(r, axis=1).max()), "worst_joint": float(r.max())}


def closed_form_gap(arm: Arm, motion: Motion) -> float:
    """Largest |Pinocchio RNEA (+ damping) - MuJoCo inverse dynamics| over the motion,
    relative to the largest torque: two independent implementations of the same model."""
    model = arm.nominal
    tau = model.torque(motion.q, motion.qd, motion.qdd)
    return float(np.max(np.abs(tau - motion.tau_clean)) / max(np.max(np.abs(motion.tau_clean)),
                                                               1e-300))


def perturbed_nominal(baseline: PinocchioModel, seed: int, spread: float = 0.3,
                      shift: float = 0.02) -> np.ndarray:
    """A nominal model as a roboticist's URDF is wrong: every body's mass and rotational
    inertia (about its centre of mass) scaled by factors drawn in [1 - spread, 1 + spread],
    its centre of mass moved by `shift` m in a random direction; armature, damping and
    friction as declared. Every body stays physical; atom_parameters' order."""
    import pinocchio as pin

    rng = np.random.default_rng([seed, 4049])
    nominal = baseline.atom_parameters().copy()
    for j in range(1, baseline.model.njoints):
        body = baseline.model.inertias[j]
        direction = rng.normal(size=3)
        moved = pin.Inertia(body.mass * rng.uniform(1 - spread, 1 + spread),
                            body.lever + shift * direction / np.linalg.norm(direction),
                            body.inertia * rng.uniform(1 - spread, 1 + spread))
        nominal[10 * (j - 1):10 * j] = moved.toDynamicParameters()
    return nominal
