"""Development runs of the refinement on the real Panda log alone, beside the study (the
study's log, split, start and scoring; without the peer's fit before it in the process):
`python -m harness.studies.sysid_peer.variants [near|joints-wide|peer] [ROLLOUTS]`.

- near: the refinement as `identify --refine rollout` runs it (rollout_model.NEAR);
- joints-wide: the same with each joint's armature, damping and frictionloss free over the
  toolbox's bounds (rollout_model.BOUNDS, the peer's), the bodies and the bias held near;
- peer: the study's peer (default PEER_ROLLOUTS), alone in its process.

Prints the fit's cost, the held-out torque error and rollout q RMS per joint, and each joint
term where it ended against its bounds (docs/identification.md, "mujoco.sysid as a peer").
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

from harness.identify.refine import WINDOW, refine_rollout
from harness.identify.rollout_fit import Windows, fit_peer
from harness.identify.rollout_model import BOUNDS, JOINT_FIELDS, NEAR, WIDE
from harness.studies.sysid_peer.scoring import held_slice, score_mujoco
from harness.studies.sysid_peer.section import (
    HELD,
    HOLDOUT,
    PEER_ROLLOUTS,
    REFINE_ROLLOUTS,
    _offset,
    _panda,
    nominal_and_identified,
)
from identification.model import model_payload

REGIONS = {"near": NEAR, "joints-wide": dataclasses.replace(NEAR, joint=None)}


def refine_variant(name: str, rollouts: int) -> list[str]:
    """The refinement of region REGIONS[name] (or the peer) on the Panda log, stopped after
    rollouts: its figures as lines."""
    a, arm, _ = _panda()
    split = held_slice(len(a["q"]), HOLDOUT).start
    if name == "peer":
        samples = int(round(WINDOW / np.median(np.diff(np.ravel(a["t"])))))
        fit = fit_peer(arm, a["t"], a["q"], a["qd"], a["tau"], [Windows(0, split, samples)],
                       np.inf, rollouts)
    else:
        _, result = nominal_and_identified(arm, a)
        fit, _ = refine_rollout(model_payload(result, arm.record, HELD, "tau"), arm, a["t"],
                                a["q"], a["qd"], a["tau"], [(0, split)], _offset(result),
                                np.inf, None, rollouts, REGIONS[name])
    s = score_mujoco(name, fit.model, fit.bias, a, HOLDOUT, fit.parameters, fit.seconds)
    dof = arm.dof

    def row(x) -> str:
        return " ".join(f"{v:.3g}" for v in x)
    lines = [f"{name}: {fit.evaluations} rollouts of a window, cost {fit.cost_start:.4g} -> "
             f"{fit.cost:.4g}", f"torque error: {row(s.torque_error)}"]
    lines += [f"rollout {w['seconds']:g} s q RMS (rad): {row(w['q_rms'])}" for w in s.rollout]
    for k, field_name in enumerate(JOINT_FIELDS):
        values = fit.parameters[(10 + k) * dof:(11 + k) * dof]
        top = BOUNDS[field_name][1] if REGIONS.get(name, WIDE).joint is None else None
        lines.append(f"{field_name}: {row(values)}" + (
            "" if top is None else f" (bounds {BOUNDS[field_name][0]:g}-{top:g})"))
    lines.append(f"bias (N m): {row(fit.bias)}")
    return lines


if __name__ == "__main__":
    variant = sys.argv[1] if len(sys.argv) > 1 else "near"
    budget = int(sys.argv[2]) if len(sys.argv) > 2 else (
        PEER_ROLLOUTS if variant == "peer" else REFINE_ROLLOUTS)
    print("\n".join(refine_variant(variant, budget)))
