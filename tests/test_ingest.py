"""`torquebench ingest`: a measured log with irregular stamps into the dataset contract.

The derivative estimate is checked against a simulated log whose derivatives are known in
closed form (a Fourier series), and the window the data chose against the best window of a
sweep on the same data; the torque is Pinocchio's at the exact states, so the states the
ingestion hands over are checked through the torque too. Bad logs: one line, exit 2, no file.
"""

from __future__ import annotations

import gzip
import json

import numpy as np
import pytest

from data import DATA
from harness.cli import main
from harness.data.derivatives import savgol_window_derivatives
from harness.data.ingest import POLYORDER, ingest, resample, uniform_grid
from harness.robots.arm import Arm

FREQS = np.array([0.1, 0.2, 0.3, 0.5, 0.8])  # Hz, the harmonics of the simulated excitation
DOF = 3


def _motion(t: np.ndarray):
    """q, qd, qdd (n, 3) of a Fourier series, exact."""
    rng = np.random.default_rng(0)
    a = rng.normal(scale=0.3, size=(len(FREQS), DOF))
    w = 2 * np.pi * FREQS[:, None, None]
    phase = w * t[None, :, None]
    q = np.sum(a[:, None] * np.sin(phase), 0) + np.array([0.0, 1.2, -1.2])
    qd = np.sum(a[:, None] * w * np.cos(phase), 0)
    qdd = -np.sum(a[:, None] * w**2 * np.sin(phase), 0)
    return q, qd, qdd


@pytest.fixture(scope="module")
def log():
    """A 12 s log at ~1 kHz with jittered stamps and dropped samples, noisy q, qd and tau."""
    rng = np.random.default_rng(1)
    steps = rng.uniform(0.0007, 0.0013, 14000)
    steps[rng.choice(len(steps), 300, replace=False)] *= rng.uniform(2, 8, 300)  # dropped
    t = np.concatenate([[0.0], np.cumsum(steps)])
    t = t[t <= 12.0]
    q, qd, qdd = _motion(t)
    tau = Arm.of("lynxmotion").nominal.torque(q, qd, qdd)
    noisy = {"q": q + rng.normal(scale=2e-5, size=q.shape),
             "qd": qd + rng.normal(scale=2e-3, size=q.shape),
             "tau": tau + rng.normal(scale=0.002, size=q.shape)}
    return t, noisy, {"q": q, "qd": qd, "qdd": qdd, "tau": tau}


def _csv(path, t, columns: dict, header=None):
    names = ["t"] + [f"{g}{j + 1}" for g, x in columns.items() for j in range(x.shape[1])]
    values = np.column_stack([t, *columns.values()])
    lines = [",".join(header or names)] + [",".join(f"{v:.10g}" for v in row) for row in values]
    path.write_text("\n".join(lines) + "\n")
    return path


def _rel(a, b):
    return np.linalg.norm(a - b, axis=0) / np.linalg.norm(b, axis=0)


@pytest.mark.parametrize("logged", [("q", "qd", "tau"), ("q", "tau")])
def test_estimated_derivatives_match_the_closed_form(tmp_path, log, logged):
    t, noisy, exact = log
    path = _csv(tmp_path / "log.csv", t, {g: noisy[g] for g in logged})
    data = ingest(path, Arm.of("lynxmotion"))
    d = data.meta["derivatives"]
    assert d["source"] == logged[-2] and d["estimated"] == [g for g in ("qd", "qdd") if g not in logged]
    grid = data.arrays["t"]
    assert np.allclose(np.diff(grid), data.meta["raw_step_s"]["median"])
    q, qd, qdd = _motion(grid)
    inner = slice(d["window_samples"], -d["window_samples"])  # the edges fit one-sided
    assert np.all(_rel(data.arrays["qdd"][inner], qdd[inner]) < 0.01)
    assert np.all(_rel(data.arrays["qd"][inner], qd[inner]) < 0.005)  # logged: its noise
    # the torque of the handed-over states: Pinocchio's at them vs at the exact states
    model = Arm.of("lynxmotion").nominal
    tau = model.torque(data.arrays["q"], data.arrays["qd"], data.arrays["qdd"])
    assert np.all(_rel(tau[inner], model.torque(q, qd, qdd)[inner]) < 0.01)


def test_the_window_chosen_from_the_data_is_near_the_best_of_a_sweep(tmp_path, log):
    """The chosen window's acceleration error is within 1.5x the smallest of a sweep of
    windows (each scored against the exact acceleration, which the choice never sees)."""
    t, noisy, _ = log
    data = ingest(_csv(tmp_path / "log.csv", t, {g: noisy[g] for g in ("q", "qd", "tau")}),
                  Arm.of("lynxmotion"))
    grid, rate = uniform_grid(t)
    qd = resample(t, noisy["qd"], grid)
    exact = _motion(grid)[2]
    inner = slice(2000, -2000)

    def error(window):
        est = savgol_window_derivatives(qd, rate, window, POLYORDER, (1,))[0]
        return float(np.max(_rel(est[inner], exact[inner])))

    best = min(error(w) for w in range(31, 1200, 40))
    chosen = data.meta["derivatives"]["window_samples"]
    assert error(chosen) <= 1.5 * best, (chosen, error(chosen), best)


def test_cli_writes_the_contract_and_decimates(tmp_path, log, capsys):
    t, noisy, _ = log
    path = _csv(tmp_path / "log.csv", t, {g: noisy[g] for g in ("q", "qd", "tau")})
    gz = tmp_path / "log.csv.gz"
    gz.write_bytes(gzip.compress(path.read_bytes()))
    out = tmp_path / "d.npz"
    assert main(["ingest", "--csv", str(gz), "--robot", "lynxmotion", "--out", str(out),
                 "--rate", "100"]) == 0
    assert "window" in capsys.readouterr().out
    with np.load(out) as d:
        assert set(d.files) == {"t", "q", "qd", "qdd", "tau", "meta"}  # no tau_clean
        meta = json.loads(str(d["meta"]))
        assert d["q"].shape == (meta["samples"], DOF) and d["t"].shape == (meta["samples"],)
        assert np.allclose(np.diff(d["t"]), 0.01, rtol=0.01)
        full = ingest(path, Arm.of("lynxmotion"))
        np.testing.assert_allclose(d["qdd"], full.arrays["qdd"][::meta["resampling"]["decimation"]])
    assert meta["plant"] == meta["robot"] == "lynxmotion" and meta["derivatives"]["window_samples"] > 1
    assert meta["robot_hash"] == Arm.of("lynxmotion").record["hash"]


def test_the_shipped_panda_log_reads(tmp_path):
    data = ingest(DATA / "panda_gaz2019" / "panda_gaz2019.csv.gz", Arm.of("panda"), rate=100)
    assert data.meta["raw_samples"] == 20544 and data.meta["logged"] == ["q", "qd", "tau"]
    assert data.arrays["q"].shape == (2100, 7) and np.all(np.isfinite(data.arrays["qdd"]))
    assert (DATA / "panda_gaz2019" / "LICENSE").read_text().startswith("                    GNU")


def _lines(n=300, dof=DOF):
    t = np.arange(n) * 1e-3
    return ["t," + ",".join(f"q{j}" for j in range(1, dof + 1)) + ","
            + ",".join(f"tau{j}" for j in range(1, dof + 1))] + [
        ",".join(f"{v:.6g}" for v in [ti, *np.sin(ti + np.arange(dof)), *np.cos(ti + np.arange(dof))])
        for ti in t]


def _edit(lines, row=None, value=None, header=None):
    lines = list(lines)
    if header is not None:
        lines[0] = header
    if row is not None:
        lines[row] = value
    return lines


BAD = {
    "missing column": (_edit(_lines(), header="t,q1,q2,q3,tau1,tau2,tau9"), "tau9"),
    "missing group": ([",".join(["t", "q1", "q2", "q3"])] + [r.rsplit(",", 3)[0] for r in _lines()[1:]],
                      "missing columns tau1..tau3"),
    "unknown column": (_edit(_lines(), header="t,q1,q2,q3,tau1,tau2,torque3"), "unknown column 'torque3'"),
    "no time": (_edit(_lines(), header="time,q1,q2,q3,tau1,tau2,tau3"), "unknown column 'time'"),
    "duplicate": (_edit(_lines(), header="t,q1,q2,q2,tau1,tau2,tau3"), "appears twice"),
    "dof mismatch": (_lines(dof=4), "robot has 3 joints"),
    "NaN": (_edit(_lines(), 40, "0.039,nan,1,1,1,1,1"), "'q1' is NaN or infinite at line 41"),
    "not a number": (_edit(_lines(), 40, "0.039,abc,1,1,1,1,1"),
                     "line 41, column 'q1': 'abc' is not a number"),
    "ragged row": (_edit(_lines(), 40, "0.039,1,1,1,1,1"), "line 41 has 6 values, the header names 7"),
    "non-monotonic time": (_edit(_lines(), 40, "0.037,1,1,1,1,1,1"), "strictly increase: line 41"),
    "gap": (_edit(_lines(), 40, "5.0,1,1,1,1,1,1")[:41] + [f"{5 + k * 1e-3:.6g},1,1,1,1,1,1"
                                                              for k in range(1, 300)], "gap"),
    "too short": (_lines(50), "50 samples, at least 200"),
    "header only": (_lines(0), "0 samples"),
    "empty": ([""], "empty file"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_log_is_one_line_and_exit_2(tmp_path, capsys, case):
    lines, message = BAD[case]
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(lines) + "\n")
    out = tmp_path / "d.npz"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not out.exists() and not list(tmp_path.glob(".d.npz*"))


def test_a_missing_file_and_an_unknown_robot_are_one_line(tmp_path, capsys):
    assert main(["ingest", "--csv", str(tmp_path / "none.csv"), "--robot", "lynxmotion",
                 "--out", str(tmp_path / "d.npz")]) == 2
    path = tmp_path / "ok.csv"
    path.write_text("\n".join(_lines()) + "\n")
    assert main(["ingest", "--csv", str(path), "--robot", "nosuch", "--out",
                 str(tmp_path / "d.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "not found" in err[0] and "unknown robot" in err[1]
    assert not (tmp_path / "d.npz").exists()


def test_the_reference_figures_are_read_from_the_shipped_readme():
    from harness.bench.real_data.section import readme_reference

    ls, nominal = readme_reference("least squares"), readme_reference("nominal")
    assert len(ls) == len(nominal) == 7 and ls[0] == 0.22 and nominal[6] == 0.99


@pytest.mark.parametrize("window, ok", [(51, True), (50, False), (3, False)])
def test_a_given_window_replaces_the_chosen_one(tmp_path, capsys, window, ok):
    path = tmp_path / "ok.csv"
    path.write_text("\n".join(_lines()) + "\n")
    out = tmp_path / "d.npz"
    code = main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out),
                 "--window", str(window)])
    assert code == (0 if ok else 2) and out.exists() == ok
    if ok:
        with np.load(out) as d:
            meta = json.loads(str(d["meta"]))["derivatives"]
        assert meta["window_samples"] == 51 and meta["rule"] == "given"
    else:
        assert "--window must be odd" in capsys.readouterr().err


def test_an_ingested_log_identifies_and_scores_against_the_measured_torque(tmp_path, log):
    """ingest -> identify: the torque carries a sensor offset; the held-out error against the
    measured torque (no tau_clean) counts the model's fitted offsets, and is recomputed here."""
    t, noisy, _ = log
    offset = np.array([0.05, -0.03, 0.02])
    path = _csv(tmp_path / "log.csv", t, {"q": noisy["q"], "qd": noisy["qd"],
                                          "tau": noisy["tau"] + offset})
    data, model = tmp_path / "d.npz", tmp_path / "MODEL.json"
    assert main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--rate", "100",
                 "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0
    payload = json.loads(model.read_text())
    offsets = np.array([j["offset"] for j in payload["joints"]])
    np.testing.assert_allclose(offsets, offset, atol=0.01)
    from identification.model import load_model

    with np.load(data) as d:
        held = slice(int(round(0.75 * len(d["q"]))), None)
        pred = load_model(model).torque(d["q"][held], d["qd"][held], d["qdd"][held]) + offsets
        expected = np.linalg.norm(pred - d["tau"][held], axis=0) / np.linalg.norm(d["tau"][held], axis=0)
    np.testing.assert_allclose(payload["metrics"]["heldout_rel_rmse"], expected, rtol=1e-9)
    assert max(expected) < 0.02


def _mutations(text: str, rng: np.random.Generator):
    """Damaged versions of a valid log: a character deleted, replaced or inserted, a cell
    replaced by text, NaN or inf, two lines swapped, the file cut short, a line duplicated."""
    lines = text.splitlines()
    for _ in range(60):
        kind = rng.integers(7)
        out = list(lines)
        i = int(rng.integers(len(out)))
        if kind == 0:
            k = int(rng.integers(len(text)))
            yield text[:k] + text[k + 1:]
        elif kind == 1:
            k = int(rng.integers(len(text)))
            yield text[:k] + rng.choice(list(",.-e9x \t\"")) + text[k:]
        elif kind == 2:
            cells = out[i].split(",")
            cells[int(rng.integers(len(cells)))] = str(rng.choice(["nan", "inf", "-inf", "", "1e999",
                                                                   "abc", "1,2", "--1"]))
            out[i] = ",".join(cells)
            yield "\n".join(out)
        elif kind == 3:
            j = int(rng.integers(len(out)))
            out[i], out[j] = out[j], out[i]
            yield "\n".join(out)
        elif kind == 4:
            yield text[:int(rng.integers(len(text)))]
        elif kind == 5:
            yield "\n".join(out[:i] + [out[i]] + out[i:])
        else:
            yield "\n".join(out[:i] + out[i + 1:])


def test_damaged_logs_are_ingested_or_refused_in_one_line(tmp_path, capsys):
    """Whatever the damage, ingest either writes a finite dataset or exits 2 with one line
    (never a traceback, never a partial file)."""
    rng = np.random.default_rng(7)
    text = "\n".join(_lines(260)) + "\n"
    outcomes = {0: 0, 2: 0}
    for k, damaged in enumerate(_mutations(text, rng)):
        path, out = tmp_path / f"log{k}.csv", tmp_path / f"d{k}.npz"
        path.write_text(damaged)
        code = main(["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out)])
        err = capsys.readouterr().err.strip()
        assert code in outcomes, (code, damaged[:200])
        outcomes[code] += 1
        if code == 2:
            assert len(err.splitlines()) == 1 and not out.exists(), err
        else:
            with np.load(out) as d:
                assert all(np.all(np.isfinite(d[key])) for key in ("t", "q", "qd", "qdd", "tau"))
    assert outcomes[0] and outcomes[2]  # both kinds of damage occurred
