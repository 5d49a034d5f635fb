"""Logs of motor currents (`ingest --current-gains`, header i1..in): torque = gain x current."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main

GAINS = (8.5, 12.0, 3.25)


def _log(path, header: str, effort: np.ndarray, n=400):
    t = np.arange(n) * 1e-3
    q = np.sin(t[:, None] + np.arange(3))
    lines = [header] + [",".join(f"{v:.12g}" for v in (ti, *qi, *ei))
                        for ti, qi, ei in zip(t, q, effort, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _torque(n=400):
    t = np.arange(n) * 1e-3
    return np.cos(t[:, None] + np.arange(3))


@pytest.mark.parametrize("effort", ["i", "tau"])
def test_currents_times_gains_are_the_torque(tmp_path, capsys, effort):
    tau = _torque()
    header = "t,q1,q2,q3," + ",".join(f"{effort}{j}" for j in (1, 2, 3))
    path = _log(tmp_path / "log.csv", header, tau / np.array(GAINS))
    out = tmp_path / "log.npz"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out),
                 "--current-gains", ",".join(map(str, GAINS))]) == 0
    data = np.load(out)
    assert np.allclose(data["tau"], tau, atol=1e-9)
    meta = json.loads(str(data["meta"]))
    assert meta["effort"]["current_gains"] == list(GAINS)
    assert "current" in meta["effort"]["logged"]


@pytest.mark.parametrize("header, gains, message", [
    ("t,q1,q2,q3,i1,i2,i3", None, "--current-gains"),
    ("t,q1,q2,q3,i1,i2,i3", "1,2", "needs 3 finite non-zero gains"),
    ("t,q1,q2,q3,i1,i2,i3", "1,a,2", "must be numbers"),
    ("t,q1,q2,q3,i1,i2,tau3", "1,2,3", "both tau and i"),
])
def test_current_problems_are_one_line(tmp_path, capsys, header, gains, message):
    path = _log(tmp_path / "log.csv", header, _torque())
    out = tmp_path / "log.npz"
    args = ["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out)]
    assert main(args + (["--current-gains", gains] if gains else [])) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not out.exists()


def test_a_torque_log_records_its_effort(tmp_path):
    path = _log(tmp_path / "log.csv", "t,q1,q2,q3,tau1,tau2,tau3", _torque())
    out = tmp_path / "log.npz"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out)]) == 0
    data = np.load(out)
    assert np.allclose(data["tau"], _torque(), atol=1e-9)
    assert json.loads(str(data["meta"]))["effort"] == {"logged": "torque (N m)"}


@pytest.mark.parametrize("effort", ["i", "tau"])
def test_currents_with_unknown_gains_stay_currents(tmp_path, effort):
    """--gains-unknown: the effort is kept as `current` (A) and the dataset has no torque, so
    no command takes it for torque (identify --loaded --load-mass identifies the gains)."""
    header = "t,q1,q2,q3," + ",".join(f"{effort}{j}" for j in (1, 2, 3))
    path = _log(tmp_path / "log.csv", header, _torque())
    out = tmp_path / "log.npz"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out),
                 "--gains-unknown"]) == 0
    data = np.load(out)
    assert "tau" not in data.files and np.allclose(data["current"], _torque(), atol=1e-9)
    effort_meta = json.loads(str(data["meta"]))["effort"]
    assert effort_meta["current_gains"] is None and "gains unknown" in effort_meta["current"]


def test_a_current_dataset_is_never_torque(tmp_path, capsys):
    path = _log(tmp_path / "log.csv", "t,q1,q2,q3,i1,i2,i3", _torque())
    data, out = tmp_path / "log.npz", tmp_path / "MODEL.json"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(data),
                 "--gains-unknown"]) == 0
    capsys.readouterr()
    assert main(["identify", "--data", str(data), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--current-gains" in err[0] and "--loaded" in err[0]
    assert not out.exists()
    args = ["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(tmp_path / "x.npz"),
            "--gains-unknown", "--current-gains", "1,2,3"]
    assert main(args) == 2 and "not both" in capsys.readouterr().err
