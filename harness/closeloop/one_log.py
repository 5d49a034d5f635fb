"""Closing the loop on a given dataset (`closeloop --data FILE.npz --robot R`): a measured
log (`ingest`) or any dataset of the contract, on an arm's rigid-body base atoms.

The loop is identification.closeloop.pipeline.close_the_log: the external torques found with
the robot's nominal model and left out, then identification.closeloop.selection.one_log; here the
robot's rigid-body library is built from its kinematics and the outcome written as
closeloop.json. Errors are against the
measured torque `tau` (and, where the file has one, also against `tau_clean`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

from harness.data.dataset import load_arrays
from harness.data.derivatives import state_smoothing
from harness.data.runs import run_times
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from harness.robots.scales import robot_scales
from identification.closeloop.events.detect import Events
from identification.closeloop.events.runs import events_json
from identification.closeloop.pipeline import close_the_log
from identification.closeloop.selection.one_log import (
    EXPLAINED,
    MIN_GAIN,
    STRUCTURE,
    VALIDATION_BLOCKS,
    MeasuredLoop,
)
from identification.errors import IdentificationError
from identification.library.kinematic import KinematicLibrary
from identification.metrics import error_measure, rel_error


@cache
def rigid_library(arm: Arm) -> KinematicLibrary:
    """The arm's rigid-body base atoms (no armature, viscous or Coulomb atom)."""
    return KinematicLibrary.generate(arm.chain, joint_atoms=False)


@dataclass(frozen=True)
class MeasuredRun:
    """The loop closed on a dataset, with what it was run on."""

    robot: str
    source: str
    arrays: dict
    meta: dict
    holdout: float
    loop: MeasuredLoop  # on the samples outside the events
    events: Events  # external torques found with the robot's nominal model

    def clean_errors(self) -> tuple[list[float], list[float]] | None:
        """Held-out errors before/after against tau_clean, if the dataset has it."""
        if "tau_clean" not in self.arrays:
            return None
        a, held = self.arrays, slice(self.loop.split, None)
        states = (a["q"][held], a["qd"][held], a["qdd"][held])
        return tuple(rel_error(m.torque(*states), a["tau_clean"][held]).tolist()
                     for m in (self.loop.declared, self.loop.model))

    def to_json(self) -> dict:
        r = self.loop
        out = {"effects": [t.to_json() for t in r.terms],
               "error_before": r.error_before.tolist(), "error_after": r.error_after.tolist(),
               "unexplained": r.unexplained, "unexplained_joints": list(r.unexplained_joints),
               "declared": "rigid-body identification on the training part (the robot's "
                           "rigid-body base atoms, coupled sparse regression, per-joint offset)",
               "explained": r.explained.tolist(), "power_removed": r.power_removed.tolist(),
               "structure_before": r.structure_before.tolist(),
               "structure_after": r.structure_after.tolist(), "noise_sigma": r.noise.tolist(),
               "validation_before": r.validation_before.tolist(),
               "validation_after": r.validation_after.tolist(),
               "sensor_offsets": r.model.declared.bias.tolist(),
               "selection": {"path": [list(p) for p in r.path],
                             "not_named": [{"joint": j, "effect": e, "validation_gain": g,
                                            "reason": why} for j, e, g, why in r.not_named],
                             "rule": f"forward selection on {VALIDATION_BLOCKS} validation "
                                     f"blocks of the training part; named if it cuts its "
                                     f"joint's validation error power by >= {MIN_GAIN:.0%}; a "
                                     f"joint is unexplained if its residual has structure "
                                     f"(> {STRUCTURE} noise sigmas RMS above the white noise) "
                                     f"and the effects remove < {EXPLAINED:.0%} of that "
                                     "structured power"},
               "error_measure": error_measure(
                   "measured", f"the last {self.holdout:.0%} of the samples (time order)"),
               "error_definition": "held-out relative RMS ||tau_hat - tau|| / ||tau|| per joint "
                                   f"on the last {self.holdout:.0%} of the samples (time order), "
                                   "against the measured torque",
               "robot": self.robot, "data": {"file": self.source, **{
                   k: self.meta[k] for k in ("mode", "source", "samples", "derivatives")
                   if k in self.meta}}}
        out.update(events_json([Path(self.source).name], [self.events]))  # its name: the
        # same report wherever the log was written
        clean = self.clean_errors()
        if clean is not None:
            out["error_before_clean"], out["error_after_clean"] = clean
        return out


def run_measured(data: str | Path, arm: Arm, holdout: float = 0.25) -> MeasuredRun:
    """Close the loop on the dataset at data of arm (resolved by the caller from the data's
    meta: harness.robots.arm.resolve_arm)."""
    arrays, meta = load_arrays(data, ("q", "qd", "qdd", "tau"), optional=("tau_clean", "t"))
    library = rigid_library(arm)
    dof = arrays["q"].shape[1]
    if dof != library.dof:
        raise UserError(f"data have {dof} joints, robot {arm.label} has {library.dof}")
    keys = [k for k in ("q", "qd", "qdd", "tau", "tau_clean") if k in arrays]
    try:
        loop, kept, found = close_the_log(arm.nominal, library, tuple(arrays[k] for k in keys),
                                          run_times(data, arrays, meta), holdout, last_body(arm),
                                          lambda runs: robot_scales(arm, runs),
                                          state_smoothing(meta))
    except IdentificationError as exc:
        raise UserError(f"{data}: {exc}") from None
    arrays = dict(zip(keys, kept, strict=True))
    return MeasuredRun(arm.reference, str(data), arrays, meta, holdout, loop, found)
