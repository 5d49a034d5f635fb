"""`identify --data U.npz[,U2.npz] --loaded L.npz[,L2.npz] --load-mass KG`: the drive gains
of logs of motor currents, identified with the dynamics (identification.drive_gains, Gautier &
Briot 2014).

Every run is a dataset of currents with unknown gains (`ingest --gains-unknown`: key
`current`, A, no `tau`), of one robot (resolve_arm checks every record). The gains are
identified from all the runs, reported per joint with a 95 % interval that holds on a coloured
residual (a delete-one-block jackknife, identification.intervals) and then used: every
unloaded run's current becomes torque (gain x current) and `identify` fits those runs as
usual (the loaded runs carry a load the model does not: they fix the gains' scale and are not
training data). The load's body is `--load-body`, else the body near the chain's end whose
fits predict the held-out blocks' currents best: no rule on a joint's name.
"""

from __future__ import annotations

import numpy as np

from harness.data.dataset import STATE_KEYS, load_arrays
from harness.data.ingest import CURRENT_KEY
from harness.data.runs import Runs
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.bodies import candidate_bodies, last_body
from harness.robots.resolve import resolve_arm
from identification.drive_gains import GAIN_BLOCKS, identify_drive_gains
from identification.errors import IdentificationError
from identification.intervals import rule

UNITS = "N m/A"
METHOD = ("Gautier & Briot (2014): one linear model of both runs (Pinocchio's joint-torque "
          "regressor, base columns; armature; viscous, Coulomb and offset per run and joint; "
          "the load's first moments and inertia with its mass known; gain x current), solved "
          "by instrumental variables (the currents the previous pass predicts) after two "
          "weighted least-squares passes, each joint's rows weighted by 1 / its residual std")


def _current_run(path: str, option: str) -> tuple[dict[str, np.ndarray], dict]:
    """The arrays (q, qd, qdd, current) and meta of a dataset of currents; UserError, one line,
    for a dataset of torque."""
    arrays, meta = load_arrays(path, STATE_KEYS, optional=(CURRENT_KEY, "tau"))
    if CURRENT_KEY not in arrays:
        raise UserError(f"{option} {path} holds torque (N m), not motor currents: "
                        "--loaded/--load-mass identify the drive gains of logs of currents "
                        "(ingest --gains-unknown); fit torque without them")
    return arrays, meta


def _check_mass(mass) -> float:
    if mass is None or not np.isfinite(mass) or mass <= 0:
        raise UserError(f"--load-mass must be the load's mass in kg, > 0, got {mass}")
    return float(mass)


def _runs(files: list[str], option: str) -> list[tuple[dict[str, np.ndarray], dict]]:
    return [_current_run(f, option) for f in files]


def gain_runs(data: list[str], loaded: str | list[str] | None, mass: float | None,
              robot: str | None, body: str | None = None) -> tuple[Runs, Arm, dict]:
    """The unloaded runs as torque with the gains identified from them and the loaded runs,
    the arm, and the gains' report (MODEL.json's drive_gains); the load on the link `body`, else
    on the body near the chain's end whose fit predicts the held-out blocks' currents best
    (harness.robots.bodies.candidate_bodies: no rule on a joint's name). UserError, one
    line, on bad input, before anything is written."""
    if loaded is None or mass is None:
        raise UserError("--loaded L.npz and --load-mass KG go together: the loaded run and its "
                        "load's mass")
    mass = _check_mass(mass)
    loaded = [loaded] if isinstance(loaded, str) else list(loaded)
    plain, heavy = _runs(data, "--data"), _runs(loaded, "--loaded")
    every = list(zip([*data, *loaded], [*plain, *heavy], strict=True))  # (file, (arrays, meta))
    dof = plain[0][0]["q"].shape[1]
    for f, (a, _) in every:
        if a["q"].shape[1] != dof:
            raise UserError(f"{f} has {a['q'].shape[1]} joints, --data {data[0]} {dof}")
    arm = resolve_arm(robot, data=[(f, m) for f, (_, m) in every])
    if arm.dof != dof:
        raise UserError(f"{data[0]} has {dof} joints, robot {arm.label} {arm.dof}")
    runs = [[(arm.nominal.regressor(a["q"], a["qd"], a["qdd"]), a["qd"], a["qdd"], a[CURRENT_KEY])
             for a, _ in group] for group in (plain, heavy)]
    carrier, fit, choice = choose_carrier(arm, runs, mass, body)
    report = {"units": UNITS, "gains": fit.gains.tolist(),
              "interval_95": fit.interval.tolist(), "interval_rule": rule(GAIN_BLOCKS),
              "standard_error": fit.gain_std.tolist(),
              "standard_error_rule": "white residuals (understates a coloured residual's spread)",
              "unloaded": data[0] if len(data) == 1 else list(data),
              "loaded": loaded[0] if len(loaded) == 1 else loaded, "load_mass_kg": mass,
              "load": {"mass_kg": mass, "first_moment_kg_m": fit.load[1:4].tolist(),
                       "inertia_kg_m2": fit.load[4:].tolist(),
                       "body": carrier.name, "body_choice": choice,
                       "frame": "the body's joint's, inertia about its origin (Ixx, Ixy, Iyy, "
                                "Ixz, Iyz, Izz); only the identifiable part (base columns), "
                                "zeros elsewhere"},
              "residual_std_Nm": fit.sigma.tolist(), "method": METHOD,
              "used": "the unloaded runs' torque is gain x current; the loaded runs are not "
                      "training data"}
    return as_torque(list(data), plain, fit.gains), arm, report


def _finite(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None  # a fold failed: no finite held-out error


def choose_carrier(arm: Arm, runs: list, mass: float, body: str | None = None):
    """(the body the load rides on (LastBody), the gains' fit with the load there, how it was
    chosen): the link `body` when named, else among the bodies near the chain's end the one
    whose fits predict the held-out blocks' currents best; runs: [unloaded runs, loaded runs],
    each run (Y, qd, qdd, current). IdentificationError when no body identifies the gains."""
    carriers = (last_body(arm, body),) if body else candidate_bodies(arm)
    fits, errors = {}, []  # by the carrier's index
    for i, carrier in enumerate(carriers):
        try:
            fits[i] = identify_drive_gains(*runs, mass, body=carrier.joint)
        except IdentificationError as e:
            if body:
                raise
            errors.append(f"{carrier.name}: {e}")
    if not fits:
        raise IdentificationError("the drive gains are not identified with the load on any "
                                  "body near the chain's end: " + "; ".join(errors))
    order = sorted(fits, key=lambda i: fits[i].heldout)
    carrier, fit = carriers[order[0]], fits[order[0]]
    best = max(fit.heldout, 1e-300)
    choice = {"rule": "--load-body" if body else
              "the gains fitted with the load on each body near the chain's end; the body whose "
              "fits predict the held-out blocks' currents best (delete-one-block, the currents "
              "in units of each joint's std); heldout_ratio: each body's held-out error power "
              "over the chosen one's",
              "candidates": [{"body": carriers[i].name, "heldout_ratio": _finite(
                  fits[i].heldout / best)} for i in fits],
              "not_identified": errors}
    if len(order) > 1:
        choice["next"] = carriers[order[1]].name
        choice["margin"] = _finite(fits[order[1]].heldout / best - 1.0)
    return carrier, fit, choice


def as_torque(files: list[str], loaded: list[tuple[dict, dict]], gains: np.ndarray) -> Runs:
    """Runs of torque from runs of currents: gain x current, the gains recorded in meta."""
    arrays = {k: np.concatenate([a[k] for a, _ in loaded]) for k in STATE_KEYS}
    arrays["tau"] = np.concatenate([a[CURRENT_KEY] * gains for a, _ in loaded])
    effort = {"current_gains": np.asarray(gains).tolist(), "gains_identified": True,
              "torque": "identified gain x current (N m/A x A)"}
    metas = tuple({**m, "effort": {**m.get("effort", {}), **effort}} for _, m in loaded)
    return Runs(arrays, metas, tuple(files), tuple(len(a["q"]) for a, _ in loaded))


def current_or_torque(files: list[str], gains: np.ndarray) -> Runs:
    """--validate runs next to identified gains: a run of currents becomes gain x current, a
    run of torque is taken as it is."""
    out = []
    for f in files:
        arrays, meta = load_arrays(f, STATE_KEYS, optional=(CURRENT_KEY, "tau"))
        if CURRENT_KEY in arrays:
            arrays["tau"] = arrays.pop(CURRENT_KEY) * gains
        elif "tau" not in arrays:
            raise UserError(f"{f}: missing keys tau (or current)")
        out.append((arrays, meta))
    return Runs({k: np.concatenate([a[k] for a, _ in out]) for k in (*STATE_KEYS, "tau")},
                tuple(m for _, m in out), tuple(files), tuple(len(a["q"]) for a, _ in out))


def describe(report: dict) -> list[str]:
    """stdout lines: the gains per joint with their 95 % intervals, and the load's body."""
    gains = ", ".join(f"K{j + 1} {k:.5g} +- {h:.2g}" for j, (k, h) in
                      enumerate(zip(report["gains"], report["interval_95"], strict=True)))
    files = lambda x: x if isinstance(x, str) else ",".join(x)  # noqa: E731
    load = report["load"]
    choice = load.get("body_choice", {})
    beat = (f"; {choice['next']} leaves {1 + choice['margin']:.3g}x its held-out error"
            if choice.get("margin") is not None else "")
    why = "--load-body" if choice.get("rule") == "--load-body" else f"chosen by the data{beat}"
    return [f"drive gains ({UNITS}, +- 95 % interval), identified with the dynamics from "
            f"{files(report['unloaded'])} and {files(report['loaded'])} (load "
            f"{report['load_mass_kg']:g} kg on {load['body']}, {why}): {gains}"]
