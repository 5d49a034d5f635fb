"""`torquebench closeloop`: trace a plant's measured residual to missing effects, add them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.closeloop.plant import run_closeloop
from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.errors import UserError
from harness.io import write_json
from harness.robots.arm import Arm
from harness.robots.registry import ROBOTS, chain_reference
from harness.robots.resolve import resolve_arm, variant_of
from identification.closeloop.closed.noise_level import noise_line, runs_line
from identification.metrics import REFERENCES, error_figures, error_words

HELD = "held-out samples"


def register(sub) -> None:
    p = sub.add_parser("closeloop", help=SUMMARY["closeloop"])
    p.add_argument("--plant", help="MJCF of the arm (may carry undeclared effects): measured "
                   "data are simulated on it")
    add_chain_option(p)
    p.add_argument("--data", help="dataset .npz files instead, comma-separated runs of one "
                   "robot (measured logs from `ingest`): the loop on the declared model, "
                   "effects named only if they hold from one run to the next; writes "
                   "DIR/model.json (the declared model with the named effects)")
    p.add_argument("--validate", help="with --data: comma-separated held-out runs the errors "
                   "are scored on (closeloop.json 'heldout'); default: the last --holdout of "
                   "every --data run")
    p.add_argument("--out", required=True, help="output directory (closeloop.json)")
    p.add_argument("--samples", type=int, default=4000,
                   help="with --plant: measured samples simulated on it (default 4000)")
    p.add_argument("--noise", type=float, default=0.05, help="torque noise std / torque std")
    p.add_argument("--bias", type=float, default=0.0,
                   help="torque-sensor bias in noise stds (non-zero: named as an offset)")
    p.add_argument("--seed", type=int, default=0,
                   help="with --plant: the simulated measurement's seed (default 0)")
    p.add_argument("--robot", default=None,
                   help="registered robot (or URDF/MJCF path) the plant is a variant of (its "
                   "declared model; default: the registered robot of the plant's kinematics, "
                   "else the plant itself), or the data's robot (default: the one the data "
                   "record)")
    p.add_argument("--holdout", type=float, default=0.25,
                   help="the last fraction of every run scored, never fitted (without "
                   "--validate; default 0.25)")
    p.add_argument("--declared", default="pinocchio",
                   help="declared model of the contract keys: 'pinocchio', 'identified' (fitted "
                   "on the training part, refitted jointly with the effects) or MODEL.json; "
                   "'declared_models' in closeloop.json reports both built-in ones; with "
                   "--data: 'pinocchio' (the robot's nominal URDF/MJCF model), MODEL.json, or "
                   "'identified' (one log: the rigid-body identification on its first part)")
    p.add_argument("--payload-reach", type=float, default=0.4, metavar="M",
                   help="with --data: a payload's centre of mass lies within M m of the last "
                   "joint (default 0.4)")
    p.add_argument("--payload-body", metavar="LINK",
                   help="with --data: the link a payload rides on (default: chosen by the "
                        "data among the bodies the last three joints move, by held-out "
                        "validation; closeloop.json payload_body)")
    p.add_argument("--push", action="append", default=[], metavar="BODY:START:DURATION:FX,FY,FZ",
                   help="with --plant: the world pushes the plant, a force (N, world frame) on "
                   "the body's centre of mass from START s for DURATION s; repeatable. The "
                   "loop must report it as an event and leave it out")
    p.set_defaults(func=run)


def _print(run) -> None:
    r = run.result
    fmt = ", ".join
    named = fmt(f"joint {t.joint} {t.effect} {t.coefficient:.5g}" for t in r.terms) or "none"
    print(f"  declared {run.declared}: named [{named}]")
    print(f"    {error_words('clean', HELD)}: before {error_figures(r.error_before)} "
          f"after {error_figures(r.error_after)}; unexplained {str(r.unexplained).lower()}")
    print(f"    against {REFERENCES['measured']}: before {error_figures(r.error_before_measured)} "
          f"after {error_figures(r.error_after_measured)}")
    if run.truth_error_measured is not None and not r.unexplained:
        line = noise_line(r.error_after_measured, run.truth_error_measured,
                          "that the plant's own model scores on the same samples (the sensor "
                          f"noise, {run.data.meta['noise']:g} of each joint's torque std)")
        if line:
            print(line)
    if r.candidates:
        print("    not named: " + "; ".join(f"joint {c.term.joint} {c.term.effect} ({c.reason})"
                                         for c in r.candidates))
    if r.fallback:
        print(f"    joints {list(r.fallback)} fall back to the declared model")
    if run.events is not None:
        print(f"    {run.events.line()}")


def _print_measured(run) -> None:
    r, fmt = run.loop, ", ".join
    named = fmt(f"joint {t.joint} {t.effect} {t.coefficient:.4g}" for t in r.terms) or "none"
    print(f"  robot {run.robot}, declared: its rigid-body identification; named [{named}]")
    print(f"    {error_words('measured', HELD)}: before {error_figures(r.error_before)} "
          f"after {error_figures(r.error_after)}")
    print(f"    unexplained joints: {list(r.unexplained_joints) or 'none'}")
    print(f"    {run.events.line()}")
    if not r.unexplained_joints:
        a, held = run.arrays, slice(r.split, None)
        line = runs_line(r.error_after, [run.meta], [a.get("tau_clean", a["tau"])],
                         a["tau"][held], r.noise)
        if line:
            print(line)


def _per_run(runs) -> list[np.ndarray]:
    """Each run's torque (clean where known), as its meta's noise fraction is of."""
    tau = runs.arrays.get("tau_clean", runs.arrays["tau"])
    return np.split(tau, np.cumsum(runs.lengths)[:-1])


def parse_push(text: str, plant: Arm):
    """A --push BODY:START:DURATION:FX,FY,FZ of the plant (harness.data.pushes.Push)."""
    from harness.data.pushes import Push

    parts = text.split(":")
    try:
        if len(parts) != 4:
            raise ValueError
        start, duration = float(parts[1]), float(parts[2])
        force = tuple(float(f) for f in parts[3].split(","))
        if len(force) != 3 or not (start >= 0 and duration > 0) or not all(
                np.isfinite([start, duration, *force])):
            raise ValueError
    except ValueError:
        raise UserError(f"--push {text!r}: expected BODY:START:DURATION:FX,FY,FZ (s, s, N), "
                        "START >= 0, DURATION > 0") from None
    names = [plant.mujoco.body(i).name for i in range(1, plant.mujoco.nbody)]
    if parts[0] not in names:
        raise UserError(f"--push: the plant has no body {parts[0]!r} (its bodies: "
                        f"{', '.join(names)})")
    return Push(parts[0], start, duration, force)


def _named(named) -> str:
    """One named effect with its units and 95 % interval; a payload with its mass and centre of
    mass (per run too where the runs' disagree)."""
    t, entry = named.term, named.to_json()
    pm = f" +- {entry['interval_95']:.2g}" if np.isfinite(entry["interval_95"]) else ""
    if t.effect != "payload" or "com" not in entry:
        return f"joint {t.joint} {t.effect} {t.coefficient:.4g}{pm} {entry['unit']}"
    xyz = ", ".join(f"{c:.3f}" for c in entry["com"])
    frame = entry.get("body") or "the last link"
    text = f"payload {entry['mass']:.3g}{pm} kg, centre of mass ({xyz}) m"
    if "com_interval_95" in entry:
        text += " +- (" + ", ".join(f"{c:.3f}" for c in entry["com_interval_95"]) + ")"
    text += f" in {frame}'s frame"
    if "mass_range_kg" in entry:
        low, high = entry["mass_range_kg"]
        text += (f" (the payload and the load friction trade on these data: its mass lies in "
                 f"[{low:.3g}, {high:.3g}] kg)")
    if "per_run_mass" in entry:
        text += " (mass per run " + " / ".join(f"{m:.3g}" for m in entry["per_run_mass"]) + " kg"
        if not entry["com_agrees"]:
            text += "; the runs' centres of mass disagree: " + " / ".join(
                "(" + ", ".join(f"{c:.3f}" for c in com) + ")" for com in entry["per_run_com"])
        text += ")"
    return text


def _data_arm(args, records: list[tuple[str, dict]]) -> Arm:
    """The arm of --data: --robot, else the declared MODEL.json's robot, else the data's;
    every record checked (resolve_arm)."""
    model = None
    if args.declared not in ("pinocchio", "identified"):
        from harness.robots.torque_models import read_model

        model = read_model(args.declared).recorded
    return resolve_arm(args.robot, model=model, data=records, chain=chain_option(args))


def _plant_arms(args) -> tuple[Arm, Arm]:
    """The --plant (its own Arm) and the arm it is a variant of: --robot, else the registered
    robot of its kinematics, else the plant itself."""
    path = Path(args.plant)
    if args.plant not in ROBOTS and path.suffix and not path.is_file():  # else: unknown robot
        raise UserError(f"plant file not found: {args.plant}")
    plant = Arm.of(chain_reference(args.plant, chain_option(args)))
    return plant, (resolve_arm(args.robot, chain=chain_option(args)) if args.robot else variant_of(plant))


def _run_data(args) -> int:
    """closeloop --data: on the runs, or (--declared identified) on one log."""
    from harness.closeloop.one_log import run_measured
    from harness.closeloop.runs import read_runs, run_runs

    if args.declared == "identified" and ("," in args.data or args.validate):
        raise UserError("--declared identified takes one --data log and no --validate")
    train, held = read_runs(args.data, args.validate)
    arm = _data_arm(args, train.records + (held.records if held is not None else []))
    print(declared_line(args.declared))
    if args.declared == "identified":
        measured = run_measured(train.files[0], arm, args.holdout)
        out = Path(args.out) / "closeloop.json"
        write_json(out, measured.to_json())
        _print_measured(measured)
        print(f"wrote {out}")
        return 0
    if not args.payload_reach > 0:
        raise UserError(f"--payload-reach must be positive, got {args.payload_reach}")
    r = run_runs(train, arm, args.declared, held, args.holdout, args.payload_reach,
                 args.payload_body)
    out = Path(args.out)
    write_json(out / "model.json", r.model_json)
    write_json(out / "closeloop.json", r.to_json())
    fmt = ", ".join
    named = fmt(_named(n) for n in r.loop.named)
    print(f"  robot {r.robot}, declared {r.declared}; " + (
        f"named [{named}]" if named else "nothing named: the model is the declared one"))
    if r.loop.named:
        print("    (+- : 95 % intervals, a delete-one-block jackknife over time blocks of every run)")
    print(f"    {error_words('measured', HELD)}: before {error_figures(r.error_before)} "
          f"after {error_figures(r.error_after)}")
    print(f"    unexplained joints: {list(r.left.unexplained_joints) or 'none'}")
    print(f"    {r.events_line}")
    choice = r.loop.body_choice
    if choice.get("next") and any(n.term.effect == "payload" for n in r.loop.named):
        print(f"    the load's body, chosen by validation: {choice['chosen']} (next "
              f"{choice['next']}: {choice['margin']:+.1%} validation error power)")
    if not r.left.unexplained_joints:
        scored = held if held is not None else train
        line = runs_line(r.error_after, scored.metas, _per_run(scored),
                         np.concatenate([s.scored[3] for s in r.scored]), r.left.noise)
        if line:
            print(line)
    print(f"wrote {out / 'closeloop.json'}, {out / 'model.json'}")
    return 0


def declared_line(declared: str) -> str:
    """The output's first line: which model the residual is taken against."""
    if declared == "pinocchio":
        what = ("the robot file's nominal model (Pinocchio RNEA and the file's damping), not an "
                "identified one: --declared MODEL.json starts from a model `identify` wrote")
    elif declared == "identified":
        what = "a rigid-body identification on the log's training part"
    else:
        what = f"{declared} (a MODEL.json)"
    return f"closeloop: declared model: {what}"


def run(args) -> int:
    if not 0.0 < args.holdout < 1.0:
        raise UserError(f"--holdout must be in (0, 1), got {args.holdout}")
    if (args.plant is None) == (args.data is None):
        raise UserError("give exactly one of --plant MJCF (simulated measurement) and "
                        "--data FILE.npz (given data)")
    if args.data is not None:
        if args.push:
            raise UserError("--push applies to --plant (a simulated plant)")
        return _run_data(args)
    if args.validate:
        raise UserError("--validate applies to --data")
    plant, arm = _plant_arms(args)
    print(declared_line(args.declared))
    loop = run_closeloop(plant, arm, args.samples, args.noise, args.seed, args.bias,
                         args.holdout, args.declared, compare=True,
                         pushes=tuple(parse_push(p, plant) for p in args.push))
    out = Path(args.out) / "closeloop.json"
    write_json(out, loop.to_json())
    for run_ in (loop, *loop.others):
        _print(run_)
    print(f"wrote {out}")
    return 0
