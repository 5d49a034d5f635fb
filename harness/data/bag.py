"""A ROS 2 recording (rosbag2, MCAP or SQLite 3 storage) of `sensor_msgs/JointState` as a log.

The log a ROS 2 robot's owner has is `ros2 bag record /joint_states`: a folder holding
metadata.yaml and the storage files. The `rosbags` library reads it without ROS. Each message
of the JointState topic is one sample: its header stamp (the recording's receive time when the
stamp is zero), `position` (rad), `velocity` (rad/s, where every message has one per joint)
and `effort` (N m, or the drive's current with --current-gains / --gains-unknown), the joints
taken by name, in the robot file's order; other joints in the message (a gripper, a head) are
left. Samples repeating the stamp before them are dropped (a driver republishing a state);
then the log is checked as a CSV log is (harness.data.csvlog.validated) and ingested the
same way (harness.data.ingest).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.data.csvlog import Log, validated
from harness.errors import UserError

JOINT_STATE = "sensor_msgs/msg/JointState"
SUFFIXES = (".mcap", ".db3")  # a rosbag2 storage file: its folder is the recording


def is_bag(path: str | Path) -> bool:
    """Whether path names a rosbag2 recording: a folder, or one of its storage files."""
    path = Path(path)
    return path.is_dir() or path.suffix in SUFFIXES


def _recording(path: Path) -> Path:
    folder = path.parent if path.is_file() else path
    if not path.exists():
        raise UserError(f"bag not found: {path}")
    if not (folder / "metadata.yaml").is_file():
        raise UserError(f"{path}: not a rosbag2 recording (a folder holding metadata.yaml and "
                        "its .mcap or .db3 files, as `ros2 bag record` writes it)")
    return folder


def read_bag(path: str | Path, joints: list[str], topic: str | None = None) -> tuple[Log, dict]:
    """The validated log of the JointState topic (the only one, or `topic`) of the rosbag2
    recording at path, the joints taken by their names `joints` (the robot file's, in order),
    and what was read (format, topic, messages, samples dropped)."""
    from rosbags.highlevel import AnyReader, AnyReaderError
    from rosbags.typesys import Stores, get_typestore

    path = Path(path)
    folder = _recording(path)
    try:
        with AnyReader([folder], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            states = [c for c in reader.connections if c.msgtype == JOINT_STATE]
            found = sorted({c.topic for c in states})
            if topic is not None:
                states = [c for c in states if c.topic == topic]
            if not states:
                every = ", ".join(f"{c.topic} ({c.msgtype})" for c in reader.connections)
                raise UserError(f"{path}: no {JOINT_STATE} topic" + (f" {topic}" if topic else "")
                                + f" (its topics: {every or 'none'})")
            if len({c.topic for c in states}) > 1:
                raise UserError(f"{path}: {len(found)} JointState topics ({', '.join(found)}): "
                                "name one with --topic")
            rows = [_sample(reader.deserialize(raw, c.msgtype), stamp, joints)
                    for c, stamp, raw in reader.messages(connections=states)]
            storage = sorted({f.suffix for f in folder.iterdir() if f.suffix in SUFFIXES})
    except (AnyReaderError, KeyError, ValueError) as exc:
        raise UserError(f"{path}: cannot read the recording ({exc})") from None
    whole = [r for r in rows if r is not None]
    if not whole:
        raise UserError(f"{path}: no message of {states[0].topic} names every joint of the "
                        f"robot ({', '.join(joints)})")
    with_velocity = all(r[2] is not None for r in whole)
    if any(r[3] is None for r in whole):
        raise UserError(f"{path}: the JointState messages of {states[0].topic} carry no effort "
                        "for every joint: the torque (or current) is needed")
    t = np.array([r[0] for r in whole])
    order = np.argsort(t, kind="stable")
    keep = order[np.concatenate([[True], np.diff(t[order]) > 0])]  # a repeated stamp: dropped
    dof = len(joints)
    names = ["t", *(f"q{j + 1}" for j in range(dof)),
             *((f"qd{j + 1}" for j in range(dof)) if with_velocity else ()),
             *(f"tau{j + 1}" for j in range(dof))]
    values = np.array([[whole[i][0], *whole[i][1], *(whole[i][2] if with_velocity else ()),
                        *whole[i][3]] for i in keep], dtype=float).reshape(len(keep), len(names))
    log = validated(path, names, values, dof, where=lambda row: f"message {int(keep[row]) + 1}")
    read = {"format": f"rosbag2 ({', '.join(s.lstrip('.') for s in storage) or 'unknown'})",
            "topic": states[0].topic, "messages": len(rows),
            "messages_without_every_joint": len(rows) - len(whole),
            "repeated_stamps_dropped": len(whole) - len(keep),
            "velocity": "logged" if with_velocity else "estimated",
            "joints": list(joints)}
    return log, read


def _sample(msg, stamp_ns: int, joints: list[str]):
    """(t s, q, qd or None, effort or None) of one JointState message in the joints' order;
    None when it lacks one of the joints."""
    index = {name: i for i, name in enumerate(msg.name)}
    if any(j not in index for j in joints):
        return None
    at = [index[j] for j in joints]

    def pick(values):
        values = np.asarray(values, dtype=float)
        return values[at] if len(values) == len(msg.name) else None

    q = pick(msg.position)
    if q is None:
        return None
    t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
    return t if t > 0 else 1e-9 * stamp_ns, q, pick(msg.velocity), pick(msg.effort)
