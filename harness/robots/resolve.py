"""Which robot a command works on: the one inference rule, and the refusal of a model or data
of another robot.

`resolve_arm`: the robot the user gave (--robot), else the robot a model records
(MODEL.json's `robot`), else the robot the data record (a dataset's or a PLAN.json's
`robot`/`plant`), else the default robot; then every record is checked against the arm's
kinematics, and a model or data of another robot is refused in one line. Nothing else reads
a record's robot. `variant_of`: the registered robot a plant file (a variant: another payload,
friction) is a variant of, by its kinematics.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS, chain_reference, split_reference
from harness.robots.subchain import HOLD_MARK


def recorded_robot(record) -> str | None:
    """The robot a record names: a MODEL.json's robot {"name"}, a dataset's or a PLAN.json's
    'robot' (else 'plant'); None when it names none."""
    if not isinstance(record, dict):
        return None
    robot = record.get("robot") or record.get("plant")
    if isinstance(robot, dict):  # a model's record: the robot's file where it has one
        chain, hold = robot.get("chain"), robot.get("hold")
        robot = robot.get("file") or robot.get("name")
        if isinstance(hold, dict) and isinstance(chain, str):
            chain += HOLD_MARK + ",".join(f"{j}={v!r}" for j, v in hold.items())
        if isinstance(robot, str) and isinstance(chain, str):
            robot = chain_reference(split_reference(robot)[0], chain)
    return robot if robot not in (None, "") else None


def resolve_arm(given: str | None = None, *, model: tuple[str, dict] | None = None,
                data: Iterable[tuple[str, dict]] = (), default: str | None = DEFAULT_ROBOT,
                chain: str | None = None) -> Arm:
    """The arm a command works on, by the one rule (module docstring), every record checked.

    given: --robot; model: (its file, MODEL.json's robot record {"name", "hash"}); data: (file,
    record) of each dataset or plan; chain: --chain BASE:TIP, the arm between two links of the
    robot (given or recorded). UserError, one line, when the records name a robot that
    cannot be found without --robot, or a robot whose kinematics differ from the arm's."""
    data = [(f, r) for f, r in data if isinstance(r, dict)]
    named = [recorded_robot(r) for _, r in data]
    chosen = given or (recorded_robot({"robot": model[1]}) if model else None) or next(
        (n for n in named if n), None) or default
    if chosen is None:
        raise UserError("no robot given and none recorded: pass --robot")
    if chain is not None and isinstance(chosen, str):
        given = chosen = chain_reference(split_reference(chosen)[0], chain)
    if not isinstance(chosen, str) or "\0" in chosen or not (
            _resolvable(chosen) or chosen == given):
        raise UserError(f"the records name robot {str(chosen)[:60]!r}, neither a registered "
                        "robot nor an existing URDF/MJCF file: pass --robot")
    arm = Arm.of(chosen)
    if model is not None and isinstance(model[1], dict) and model[1].get("hash") is not None \
            and model[1]["hash"] != arm.record["hash"]:
        raise UserError(f"model {model[0]} was identified for robot "
                        f"'{str(model[1].get('name')):.60}' (kinematics "
                        f"{str(model[1]['hash']):.20}), not '{arm.label}' ({arm.record['hash']})")
    for (file, record), name in zip(data, named, strict=True):
        _check_data(arm, file, record, name, given is not None)
    return arm


def _check_data(arm: Arm, file: str, record: dict, name: str | None, given: bool) -> None:
    """UserError when file's record names a robot whose kinematics are not the arm's: the
    named robot's kinematics compared (a file it names that is found), else the hash the
    record keeps (robot_hash); a named robot found nowhere needs --robot."""
    other = name is not None and name != arm.reference
    if other and _resolvable(name):
        differs = arm.first_difference(Arm.of(name)) is not None
    elif other and not given and record.get("robot_hash") is None:
        raise UserError(f"{file} records robot {name[:60]!r}, neither a registered robot "
                        "nor an existing URDF/MJCF file: pass --robot")
    else:
        differs = record.get("robot_hash") not in (None, arm.record["hash"])
    if differs:
        raise UserError(f"{file} records robot '{str(name):.60}' (kinematics "
                        f"{str(record.get('robot_hash') or Arm.of(name).record['hash']):.20}), "
                        f"not '{arm.label}' ({arm.record['hash']})")
    _check_dof(arm, file, record)


def _resolvable(name: str) -> bool:
    robot = split_reference(name)[0] if "\0" not in name else name
    return robot in ROBOTS or ("\0" not in robot and Path(robot).is_file())


def _check_dof(arm: Arm, file: str, record: dict) -> None:
    if isinstance(record.get("dof"), int) and record["dof"] != arm.dof:
        raise UserError(f"{file} has {record['dof']} joints, robot {arm.label} has {arm.dof}")


def variant_of(plant: Arm) -> Arm:
    """The registered robot plant is a variant of: the one with its kinematics (the default
    robot first), else the plant itself (its own file is then its declared model)."""
    if plant.registered:
        return plant
    plant.record  # noqa: B018 - one clear error for a file that is no open serial chain
    for name in (DEFAULT_ROBOT, *sorted(set(ROBOTS) - {DEFAULT_ROBOT})):
        try:
            arm = Arm.of(name)
            if arm.first_difference(plant) is None:
                return arm
        except UserError:  # a registered robot whose files are not installed
            continue
    return plant
