"""The real-data section's rollout figures (reported, not targets): the nominal URDF as MuJoCo
holds it and the identified model's exported MJCF, each started from the log's state at the
start of every window of its held-out part and driven by its torque (harness.replay.rollout),
as `predict --rollout 0.1,0.5 --rollout-holdout 0.25` measures them: the identified model's
sensor offset for a new run is taken off the logged torque, the nominal model has none."""

from __future__ import annotations

import numpy as np

from harness.replay.rollout import held_model, roll_out
from harness.robots.arm import Arm
from identification.closeloop.closed.offsets import held_out_offset
from identification.model import model_payload

WINDOWS = (0.1, 0.5)  # s
COMMAND = ("torquebench predict --model {model} --data panda.npz --rollout 0.1,0.5 "
           "--rollout-holdout 0.25 --out pred.npz")


def rollout_figures(arm: Arm, identification, arrays: dict, holdout: float) -> dict:
    """Per model ('nominal', 'identified'): its words, the command that gives its figures and
    per window length the figures (WindowFidelity.to_json)."""
    payload = model_payload(identification, arm.record,
                            {"kind": "last_fraction", "fraction": holdout}, "tau")
    new_run = np.asarray(identification.sensor_offsets()["new_run"], float)
    offset = held_out_offset(identification.model, new_run)
    out = {}
    for name, model, spec, off in (("nominal", None, "pinocchio", 0.0),
                                   ("identified", payload, "model.json", offset)):
        held, words = held_model(model, arm)
        done = roll_out(held, arrays["t"], arrays["q"], arrays["qd"], arrays["tau"] - off,
                        WINDOWS, holdout)
        out[name] = {"model": words, "command": COMMAND.format(model=spec),
                     "from_sample": done.start,
                     "windows": [f.to_json() for f in done.figures]}
    return out


def rollout_markdown(figures: dict) -> list[str]:
    """The figures as a table, with what they are."""
    any_model = next(iter(figures.values()))
    dof = len(next(w["q_rms"] for w in any_model["windows"] if w["q_rms"] is not None))
    out = ["Rollout in MuJoCo on the held-out part (reported, not a target): from the log's q, qd "
           "at the start of each window, driven by its torque (less the identified model's "
           "sensor offset), MuJoCo's own mj_step; RMS position error per joint (rad) over the "
           "windows that did not diverge (non-finite, or a joint over pi rad off). The "
           "identified model is its exported MJCF (`export --format mjcf`), which leaves out "
           "the friction laws MuJoCo has no joint term for (a sigmoid). Commands: "
           f"`{COMMAND.format(model='pinocchio')}` and the same with `--model model.json`.", "",
           "| model | window | windows | diverged | " + " | ".join(
               f"joint {j + 1}" for j in range(dof)) + " |", "|---|---|---|---|" + "---|" * dof]
    for name, model in figures.items():
        for w in model["windows"]:
            errors = (["-"] * dof if w["q_rms"] is None else [f"{v:.3g}" for v in w["q_rms"]])
            out.append(f"| {name} | {w['seconds']:g} s | {w['windows']} | "
                       f"{100 * w['diverged_fraction']:.0f} % | " + " | ".join(errors) + " |")
    return out
