"""`ingest --bag`: a ROS 2 recording of sensor_msgs/JointState (rosbag2, MCAP and SQLite 3,
written here by the `rosbags` library itself) gives the dataset the same log gives as CSV: the
joints taken by name whatever their order in the message, a joint the robot lacks left, a
repeated stamp dropped; bad recordings are one line and exit 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from harness.data.generate import generate
from harness.robots.arm import Arm

ARM = Arm.of("lynxmotion")


def _run(samples: int = 400):
    return generate(ARM, samples, 0.02, 7, "inverse")


def _write_bag(path, run, storage: str = "mcap", topics=("/joint_states",), drop=None,
               repeat: int | None = None) -> None:
    """run's samples as JointState messages on each topic: the arm's joints in reverse order
    after a gripper joint the robot lacks (drop: a joint left out of every message; repeat: a
    sample whose message is sent twice)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    joints = list(ARM.pinocchio.names[1:])
    order = [j for j in reversed(range(len(joints))) if joints[j] != drop]
    names = ["gripper_joint", *(joints[j] for j in order)]
    plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[storage]
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = [writer.add_connection(t, JointState.__msgtype__, typestore=store) for t in topics]
        for k, t in enumerate(run.t):
            sec = int(np.floor(t + 100.0))
            stamp = Time(sec=sec, nanosec=int(round((t + 100.0 - sec) * 1e9)))
            msg = JointState(header=Header(stamp=stamp, frame_id=""), name=names,
                             position=np.array([0.01, *run.q[k, order]]),
                             velocity=np.array([0.0, *run.qd[k, order]]),
                             effort=np.array([0.0, *run.tau[k, order]]))
            data = store.serialize_cdr(msg, JointState.__msgtype__)
            for conn in conns:
                for _ in range(2 if k == repeat else 1):
                    writer.write(conn, int((t + 100.0) * 1e9), data)


def _csv(path, run) -> None:
    dof = ARM.dof
    header = ["t", *(f"q{j + 1}" for j in range(dof)), *(f"qd{j + 1}" for j in range(dof)),
              *(f"tau{j + 1}" for j in range(dof))]
    # the stamps as the bag holds them: seconds and nanoseconds of t + 100 s
    sec = np.floor(run.t + 100.0)
    t = sec + np.round((run.t + 100.0 - sec) * 1e9) * 1e-9
    np.savetxt(path, np.column_stack([t, run.q, run.qd, run.tau]), delimiter=",",
               header=",".join(header), comments="", fmt="%.17g")


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_gives_the_dataset_its_csv_gives(tmp_path, capsys, storage):
    run = _run()
    _write_bag(tmp_path / "bag", run, storage, repeat=10)
    _csv(tmp_path / "log.csv", run)
    for source, out in ((["--bag", str(tmp_path / "bag")], "bag.npz"),
                        (["--csv", str(tmp_path / "log.csv")], "csv.npz")):
        assert main(["ingest", *source, "--robot", "lynxmotion", "--out",
                     str(tmp_path / out)]) == 0
    with np.load(tmp_path / "bag.npz") as bag, np.load(tmp_path / "csv.npz") as csv:
        for key in ("t", "q", "qd", "qdd", "tau"):
            np.testing.assert_allclose(bag[key], csv[key], rtol=0, atol=1e-9, err_msg=key)
        read = json.loads(str(bag["meta"]))["read"]
    assert read["format"] == f"rosbag2 ({'mcap' if storage == 'mcap' else 'db3'})"
    assert read["topic"] == "/joint_states" and read["repeated_stamps_dropped"] == 1
    assert read["messages"] == len(run.t) + 1
    # the bag's own file names the recording too
    if storage == "mcap":
        (file,) = (tmp_path / "bag").glob("*.mcap")
        assert main(["ingest", "--bag", str(file), "--robot", "lynxmotion", "--out",
                     str(tmp_path / "file.npz")]) == 0


@pytest.mark.parametrize("case, message", [
    ("two_topics", "name one with --topic"),
    ("missing_joint", "names every joint of the robot"),
    ("no_such_topic", "no sensor_msgs/msg/JointState topic /arm"),
    ("not_a_bag", "not a rosbag2 recording"),
    ("both", "exactly one of --csv"),
])
def test_a_bad_recording_is_one_line(tmp_path, capsys, case, message):
    run = _run(250)
    bag = tmp_path / "bag"
    if case == "two_topics":
        _write_bag(bag, run, topics=("/joint_states", "/other/joint_states"))
    elif case == "missing_joint":
        _write_bag(bag, run, drop=ARM.pinocchio.names[2])
    elif case == "not_a_bag":
        bag.mkdir()
    else:
        _write_bag(bag, run)
    args = ["ingest", "--bag", str(bag), "--robot", "lynxmotion", "--out",
            str(tmp_path / "d.npz")]
    args += {"no_such_topic": ["--topic", "/arm"], "both": ["--csv", "x.csv"]}.get(case, [])
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "d.npz").exists()
