"""`identify --data U.npz --loaded L.npz --load-mass KG`: the drive gains of logs of motor
currents, identified with the dynamics (identification.drive_gains, Gautier & Briot 2014).

Both runs are datasets of currents with unknown gains (`ingest --gains-unknown`: key
`current`, A, no `tau`), of one robot (resolve_arm checks both records). The gains are
identified from both runs, reported per joint and then used: every run's current becomes
torque (gain x current) and `identify` fits the unloaded run as usual (the loaded run
carries a load the model does not: it fixes the gains' scale and is not training data).
"""

from __future__ import annotations

import numpy as np

from harness.closeloop.payload import last_body
from harness.data.dataset import STATE_KEYS, load_arrays
from harness.data.ingest import CURRENT_KEY
from harness.data.runs import Runs
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.resolve import resolve_arm
from identification.drive_gains import identify_drive_gains

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


def gain_runs(data: list[str], loaded: str | None, mass: float | None, robot: str | None,
              body: str | None = None) -> tuple[Runs, Arm, dict]:
    """The unloaded run as torque with the gains identified from it and the loaded run, the
    arm, and the gains' report (MODEL.json's drive_gains); the load on the link `body` (default:
    closeloop.payload.last_body's). UserError, one line, on bad input,
    before anything is written."""
    if loaded is None or mass is None:
        raise UserError("--loaded L.npz and --load-mass KG go together: the loaded run and its "
                        "load's mass")
    mass = _check_mass(mass)
    if len(data) != 1:
        raise UserError(f"with --loaded, --data is the one unloaded run of currents, got "
                        f"{len(data)} files")
    (u, u_meta), (v, v_meta) = _current_run(data[0], "--data"), _current_run(loaded, "--loaded")
    if u["q"].shape[1] != v["q"].shape[1]:
        raise UserError(f"--loaded {loaded} has {v['q'].shape[1]} joints, --data {data[0]} "
                        f"{u['q'].shape[1]}")
    arm = resolve_arm(robot, data=[(data[0], u_meta), (loaded, v_meta)])
    if arm.dof != u["q"].shape[1]:
        raise UserError(f"{data[0]} has {u['q'].shape[1]} joints, robot {arm.label} {arm.dof}")
    runs = [(arm.nominal.regressor(a["q"], a["qd"], a["qdd"]), a["qd"], a["qdd"], a[CURRENT_KEY])
            for a in (u, v)]
    carrier = last_body(arm, body)  # default: the last body, or the one a gripper's jaw turns on
    fit = identify_drive_gains(runs[0], runs[1], mass, body=carrier.joint)
    report = {"units": UNITS, "gains": fit.gains.tolist(), "standard_error": fit.gain_std.tolist(),
              "unloaded": data[0], "loaded": loaded, "load_mass_kg": mass,
              "load": {"mass_kg": mass, "first_moment_kg_m": fit.load[1:4].tolist(),
                       "inertia_kg_m2": fit.load[4:].tolist(),
                       "body": carrier.name,
                       "frame": "the body's joint's, inertia about its origin (Ixx, Ixy, Iyy, "
                                "Ixz, Iyz, Izz); only the identifiable part (base columns), "
                                "zeros elsewhere"},
              "residual_std_Nm": fit.sigma.tolist(), "method": METHOD,
              "used": "the unloaded run's torque is gain x current; the loaded run is not "
                      "training data"}
    return as_torque([data[0]], [(u, u_meta)], fit.gains), arm, report


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
    """stdout lines: the gains per joint with their standard errors."""
    gains = ", ".join(f"K{j + 1} {k:.5g} +- {s:.2g}" for j, (k, s) in
                      enumerate(zip(report["gains"], report["standard_error"], strict=True)))
    return [f"drive gains ({UNITS}), identified with the dynamics from {report['unloaded']} and "
            f"{report['loaded']} (load {report['load_mass_kg']:g} kg): {gains}"]
