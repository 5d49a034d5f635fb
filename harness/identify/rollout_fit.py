"""mujoco.sysid fitting a model (harness.identify.rollout_model) to a log as its own examples
do: its residual (the rollout's joint positions and velocities against the log's, each window
started from the log's state and driven by its torque, each signal normalized by its norm over
the window), its default optimizer (mujoco.minimize's Levenberg-Marquardt, finite-difference
Jacobian).

Worked around here (docs/identification.md, "mujoco.sysid as a peer"): its optimizer has no
time limit: the residual stops it before a call that would end past the budget
(BudgetedResidual) and the best point it evaluated is kept; its joint sensors lag the state
they are stamped with by a timestep: the rollout's state is compared instead.
"""

from __future__ import annotations

import contextlib
import io
import logging
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from harness.identify.rollout_model import (
    WIDE,
    Region,
    biases,
    joint_names,
    peer_parameters,
    peer_spec,
    standard_parameters,
    toolbox,
)
from harness.robots.arm import Arm


@dataclass(frozen=True)
class Windows:
    """A log's part cut into rollouts of `samples` log steps, as the toolbox's ModelSequences
    wants them: each window's initial state, torque and measured q, qd, its time from 0."""

    start: int  # first sample
    stop: int  # one past the last
    samples: int


def model_sequences(spec: mujoco.MjSpec, model: mujoco.MjModel, t, q, qd, tau,
                    windows: list[Windows]):
    """The toolbox's ModelSequences of spec on the log's windows (each part's: a run's)."""
    sysid = toolbox()
    names = joint_names(model)
    # the rollout's state, not joint sensors: a sensor after mj_step holds the state before
    # it, one timestep behind the state's time stamp (0.5 ms late on the Lynxmotion: 1 % of a
    # perturbed model's residual on a log MuJoCo made)
    signals = [f"{n}_qpos" for n in names] + [f"{n}_qvel" for n in names]
    starts = [(k, w.samples) for w in windows
              for k in range(w.start, w.stop - w.samples, w.samples)]
    states, controls, measured = [], [], []
    for k, samples in starts:
        part = slice(k, k + samples + 1)
        times = t[part] - t[k]
        states.append(sysid.create_initial_state(model, q[k], qd[k]))
        controls.append(sysid.TimeSeries(times, tau[part]))
        measured.append(sysid.TimeSeries.from_names(times, np.c_[q[part], qd[part]], model,
                                                    signals))
    return sysid.ModelSequences("arm", spec, [f"window_{k}" for k, _ in starts], states,
                                controls, measured)


class Budget(Exception):
    """The fit's time budget is spent (raised from inside the toolbox's residual)."""


@dataclass
class BudgetedResidual:
    """The toolbox's residual function, stopped at `seconds` of wall time (a call that would
    end past it, its time taken as the last call's with as many columns, else as many times a
    point's, raises Budget) or at
    `rollouts` evaluations of every window (a finite-difference column counts one; None: no
    such limit, a limit the same on every machine); keeps the best point evaluated (its cost:
    half the sum of squared residuals), counts rollouts."""

    residual_fn: object
    seconds: float
    rollouts: int | None = None
    clock: object = time.perf_counter
    started: float | None = None
    best: tuple = (np.inf, None)
    evaluations: int = 0
    took: dict = field(default_factory=dict)  # columns -> seconds of the last such call

    def __post_init__(self) -> None:
        if self.started is None:
            self.started = self.clock()

    def __call__(self, x, params, **kwargs):
        columns = 1 if np.ndim(x) == 1 else np.shape(x)[1]
        begun = self.clock()
        expected = self.took.get(columns, columns * self.took.get(1, 0.0))
        late = (begun + expected - self.started > self.seconds
                or self.rollouts is not None and self.evaluations + columns > self.rollouts)
        if late and self.best[1] is not None:  # the first point is evaluated whatever the budget
            raise Budget
        out = self.residual_fn(x, params, **kwargs)
        self.took[columns] = self.clock() - begun
        self.evaluations += columns
        if columns == 1:  # a point (mujoco.minimize passes it as one column), not a Jacobian
            r = np.concatenate([np.ravel(part) for part in out[0]])
            cost = 0.5 * float(r @ r) if np.all(np.isfinite(r)) else np.inf
            if cost < self.best[0]:
                self.best = (cost, np.array(x, float).ravel())
        return out


@dataclass(frozen=True)
class RolloutFit:
    """The toolbox's fit: 13 dof standard parameters (armature, damping, frictionloss as the
    joint terms), each motor's bias (N m), the compiled model, and how it ran."""

    parameters: np.ndarray
    bias: np.ndarray
    model: mujoco.MjModel
    seconds: float  # wall
    evaluations: int  # rollouts of every window, finite-difference columns counted
    stopped: str  # "converged" or "budget"
    cost_start: float  # half the sum of squared residuals
    cost: float
    count: int  # parameters fitted
    windows: int

    def to_json(self) -> dict:
        return {"parameters_fitted": self.count, "windows": self.windows,
                "evaluations": self.evaluations, "stopped": self.stopped,
                "cost_start": self.cost_start, "cost": self.cost,
                "standard_parameters": self.parameters.tolist(), "bias": self.bias.tolist(),
                "timing": {"seconds": self.seconds}}


def fit_peer(arm: Arm, t, q, qd, tau, windows: list[Windows], seconds: float,
             rollouts: int | None = None) -> RolloutFit:
    """The toolbox's fit (module docstring) of the arm's file on the log's windows, stopped
    at `seconds` of wall time or `rollouts` (BudgetedResidual)."""
    return fit_rollout(peer_spec(arm, arm.nominal.atom_parameters()), t, q, qd, tau, windows,
                       seconds, True, rollouts)


def fit_rollout(spec: mujoco.MjSpec, t, q, qd, tau, windows: list[Windows], seconds: float,
                off_bounds: bool, rollouts: int | None = None, region: Region = WIDE,
                threads: int = 2) -> RolloutFit:
    """The toolbox's fit (module docstring) of spec (drive_and_sense's) from its own values
    within region (off_bounds: peer_parameters') on the log's windows, stopped at `seconds`
    of wall time or `rollouts` (BudgetedResidual)."""
    sysid = toolbox()
    model = spec.compile()
    params = peer_parameters(spec, model, off_bounds, region)
    sequences = model_sequences(spec, model, np.ravel(t), q, qd, tau, windows)
    residual = BudgetedResidual(sysid.build_residual_fn(models_sequences=[sequences],
                                                        n_threads=threads), seconds,
                                rollouts)
    x0 = params.as_vector()
    residual(x0, params.copy())
    cost_start = residual.best[0]
    stopped = "converged"
    try:
        with _quiet(not off_bounds):
            fitted, _ = sysid.optimize(params, residual, optimizer="mujoco", verbose=False,
                                       output=io.StringIO())  # its per-iteration table
        x = fitted.as_vector()
    except Budget:
        stopped, x = "budget", residual.best[1]
    fitted = params.copy()
    fitted.update_from_vector(x)
    final = sysid.apply_param_modifiers(fitted, spec)
    cost = residual.best[0] if stopped == "budget" else _cost(residual.residual_fn, x, fitted)
    return RolloutFit(standard_parameters(fitted, model), biases(fitted, model), final,
                      residual.clock() - residual.started, residual.evaluations, stopped,
                      cost_start, cost, x.size, len(sequences.measured_rollout))


@contextlib.contextmanager
def _quiet(start_at_bounds: bool):
    """The toolbox's advice to move a start off its bounds (absl's warning) silenced where the
    start is kept at them on purpose (a refinement's: refine's docstring)."""
    logger = logging.getLogger("absl")
    level = logger.level
    if start_at_bounds:
        logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def _cost(residual_fn, x, params) -> float:
    r = np.concatenate(residual_fn(x, params)[0])
    return 0.5 * float(r @ r)
