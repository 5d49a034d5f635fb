"""Torque data for identification, from MuJoCo.

`inverse`: MuJoCo inverse dynamics (mj_inverse) along an excitation trajectory,
plus non-zero-mean Gaussian torque noise.
`measured`: MuJoCo forward simulation through the plant's actuators under a
tracking controller; the user sees encoder angles and noisy actuator torques
and estimates qd, qdd from the angles (harness.data.sensors).
"""

from __future__ import annotations

import mujoco
import numpy as np

from harness.data.dataset import Dataset
from harness.data.excitation_file import Trajectory
from harness.data.sensors import SensorConfig, torque_noise
from harness.data.tracking import simulate_measured
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.extras import published_library
from identification.excitation.fourier import FourierExcitation, design_excitation, normalized_condition
from identification.regression.oracle import base_columns

MIN_SAMPLES = 10
SAMPLE_RATE = 200.0  # Hz, rate of the data handed to identification
CONDITION_POINTS = 200  # instants of a motion its condition number is computed at
CONDITION_WORDS = "excitation condition number"  # as generate and excite print it
CONDITION_MEANING = ("of the identification's base atoms and offsets, columns normalized, at "
                     f"{CONDITION_POINTS} instants")



def _condition_fn(arm: Arm, robot: Arm, rate: float, samples: int):
    """Excitation quality: the worse of the normalized conditions of arm's base regressor
    (Pinocchio) and of the library robot's registry entry declares for its data
    (Robot.excitation_library), if any."""
    pmodel = arm.pinocchio
    declared = declared_library(robot)
    t = np.linspace(0.0, samples / rate, min(samples, 400), endpoint=False)
    baseline = arm.nominal
    base: list[np.ndarray] = []  # base-parameter columns: structural, found on the first candidate

    def condition(exc: FourierExcitation) -> float:
        states = exc.evaluate(t)
        conds = [library_condition(declared, *states).condition] if declared else []
        Y = baseline.regressor(*states).reshape(-1, 10 * (pmodel.njoints - 1))
        if not base:
            base.append(base_columns(Y))
        conds.append(normalized_condition(Y[:, base[0]]))
        return max(conds)

    return condition


def default_excitation(arm: Arm, samples: int, seed: int, robot: Arm | None = None
                       ) -> tuple[FourierExcitation, float]:
    """generate's own excitation of arm for `samples` points at SAMPLE_RATE: the
    best-conditioned of seeded random Fourier series in the joint limits and the URDF's speed
    limits (robot: whose declared library also judges it, default arm)."""
    lo, hi = arm.position_limits
    return design_excitation(lo, hi, seed, _condition_fn(arm, robot or arm, SAMPLE_RATE, samples),
                             velocity=arm.speed_bounds)


def _along(excitation: Trajectory, dof: int, samples: int, mode: str) -> tuple[np.ndarray, float]:
    """The times of a given excitation's first `samples` states and its rate (Hz); UserError
    unless it fits the plant, is evenly sampled and, tracked in measured mode (whose
    simulation starts at rest at t = 0), starts at t = 0."""
    if excitation.q.shape[1] != dof:
        raise UserError(f"the excitation has {excitation.q.shape[1]} joints, the robot {dof}")
    if samples > len(excitation.t):
        raise UserError(f"--samples {samples} exceeds the excitation's {len(excitation.t)} rows")
    t = excitation.t[:samples]
    step = np.diff(t)
    if np.ptp(step) > 1e-6 * np.mean(step):
        raise UserError("the excitation's samples must be evenly spaced in t")
    if mode == "measured" and abs(t[0]) > 1e-6 * np.mean(step):
        raise UserError(f"--mode measured tracks an excitation from t = 0, got {t[0]:g} s")
    return t, float(1.0 / np.mean(step))


def _validate(samples: int, noise: float, bias: float) -> None:
    if samples < MIN_SAMPLES:
        raise UserError(f"--samples must be at least {MIN_SAMPLES}, got {samples}")
    if not np.isfinite(noise) or noise < 0:
        raise UserError(f"--noise must be a finite fraction >= 0, got {noise}")
    if not np.isfinite(bias):
        raise UserError(f"--bias must be finite, got {bias}")


def inverse_torques(model: mujoco.MjModel, q, qd, qdd) -> np.ndarray:
    """mj_inverse generalized forces (n, nv) along a trajectory."""
    data = mujoco.MjData(model)
    tau = np.empty_like(q)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        tau[k] = data.qfrc_inverse
    return tau


def generate(
    arm: Arm,
    samples: int = 4000,
    noise: float = 0.05,
    seed: int = 0,
    mode: str = "inverse",
    bias: float = 0.2,
    sensors: SensorConfig | None = None,
    excitation: Trajectory | None = None,
    robot: Arm | None = None,
    pushes=(),
) -> Dataset:
    """One dataset of arm (the plant) of `samples` points at SAMPLE_RATE Hz; noise is a
    fraction of torque std. With an excitation: along its first `samples` states, at its rate
    (measured: tracked from its state at t = 0, its samples linearly interpolated between).
    robot: the registered robot arm is a variant of, whose entry's declared library the
    excitation and the report use (default: arm's own entry); pushes: external forces on the
    plant's links in measured mode (harness.data.pushes), recorded in meta."""
    _validate(samples, noise, bias)
    robot = robot or arm
    rate = SAMPLE_RATE
    if excitation is None:
        exc, cond = default_excitation(arm, samples, seed, robot)
        t = np.arange(samples) / SAMPLE_RATE
    else:
        exc = excitation
        t, rate = _along(excitation, arm.dof, samples, mode)
        cond = _condition_fn(arm, robot, rate, samples)(exc)
    rng = np.random.default_rng(seed + 1)
    meta = dict(plant=arm.reference, robot_hash=arm.record["hash"],
                **{k: arm.record[k] for k in ("chain", "held", "hold") if k in arm.record},
                mode=mode, noise=noise, bias=bias, seed=seed, dof=arm.dof, samples=samples, rate=rate,
                excitation_condition=cond)
    if pushes and mode != "measured":
        raise UserError("pushes act on a simulated plant: --mode measured")
    if mode == "inverse":
        q, qd, qdd = exc.evaluate(t)
        tau_clean = inverse_torques(arm.mujoco, q, qd, qdd)
        truth: dict = {}
    elif mode == "measured":
        q, qd, qdd, tau_clean, truth, stats = simulate_measured(arm, exc, t, rate,
                                                                sensors or SensorConfig(), rng,
                                                                pushes)
        meta.update(stats)
        if pushes:
            meta["pushes"] = [p.to_json() for p in pushes]
    else:
        raise UserError(f"--mode must be 'inverse' or 'measured', got '{mode}'")
    meta.update(library_report(robot, q, qd, qdd, arm.pinocchio))
    meta["condition_number"] = condition_number(arm, q, qd, qdd)
    tau = tau_clean + torque_noise(tau_clean, noise, bias, rng)
    return Dataset(t, q, qd, qdd, tau, tau_clean, meta, truth)


def condition_number(arm: Arm, q, qd, qdd) -> float:
    """The excitation's condition number, as `generate` and `excite` both print it: that of
    the identification's regressor (the arm's base atoms, with armature, viscous and Coulomb,
    and one torque offset per joint: AtomRegressor), its columns scaled to unit norm, at
    CONDITION_POINTS instants spread evenly over the motion's samples (docs/data.md)."""
    from identification.excitation.criteria import log_condition
    from identification.excitation.regressor import AtomRegressor

    n = len(q)
    rows = np.arange(min(CONDITION_POINTS, n)) * n // min(CONDITION_POINTS, n)
    return float(np.exp(log_condition(AtomRegressor(arm.library), q[rows], qd[rows], qdd[rows])))


def declared_library(arm: Arm):
    """The library arm's registry entry declares for its data (Robot.excitation_library:
    the Lynxmotion's is the paper's published 75 features), or None."""
    name = arm.entry.excitation_library
    return published_library(name) if name else None


def report_library(arm: Arm, dof: int, pmodel=None):
    """The library whose conditioning is reported for arm's data: the one its registry
    entry declares (declared_library); otherwise the base atoms generated from the plant's
    kinematics (identification.library.kinematic), or, with no Pinocchio model of the plant,
    the generic polynomial x trig library.
    """
    from identification.library.chain import ChainError, KinematicChain
    from identification.library.generic import generic_library
    from identification.library.kinematic import KinematicLibrary

    declared = declared_library(arm)
    if declared is not None:
        return declared
    if pmodel is not None and pmodel.nv == dof:
        try:
            return KinematicLibrary.generate(KinematicChain.from_pinocchio(pmodel))
        except ChainError:
            pass  # not a revolute chain: the generic library below
    return generic_library(dof) if dof <= 2 else generic_library(dof, trig_joints=(1, 2))


def library_condition(library, q, qd, qdd):
    """Rank and normalized condition of library's columns on this motion."""
    from identification.library.base import conditioning

    columns = library.evaluate(q, qd, qdd)
    return conditioning(columns.reshape(-1, columns.shape[-1]), library.names)


def library_report(arm: Arm, q, qd, qdd, pmodel=None) -> dict:
    """Rank and normalized condition of arm's report library on this data (pmodel: the
    Pinocchio model of the plant that made it)."""
    library = report_library(arm, q.shape[1], pmodel)
    cond = library_condition(library, q, qd, qdd)
    return {"library": library.name, "library_rank": cond.rank, "library_size": cond.size,
            "library_condition": cond.condition}
