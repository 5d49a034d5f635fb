"""`torquebench sweep` on a small grid: rows, resume after a torn write, the figures' data.

The grid is the issue's: lynxmotion and double_pendulum, noise 0 and 5 %, two seeds, two
methods (coupled sparse and the oracle), at 400 samples; one local Ray instance serves the
module (the sweep keeps a Ray the process already runs). Cross-checks: noise-free data are
identified exactly (both libraries span the rigid-body torque), a cell recomputed serially in
this process gives the row Ray wrote bit for bit, a resumed sweep recomputes exactly the torn
and missing cells and reproduces their values, and the plotted medians and quartiles equal
numpy's over the csv rows."""

from __future__ import annotations

import csv
import io
import itertools

import numpy as np
import pytest
from matplotlib.image import imread

from harness.cli import main
from harness.errors import UserError
from harness.sweep.cell import CellFailure, CellResult, run_cell
from harness.sweep.figures import write_figures
from harness.sweep.grid import Cell, parse_grid
from harness.sweep.progress import Progress
from harness.sweep.store import ResultsStore, read
from harness.sweep.summary import bands

ROBOTS, NOISE, SEEDS, METHODS, SAMPLES = ("lynxmotion", "double_pendulum"), (0.0, 0.05), 2, \
    ("coupled", "oracle"), 300
ARGS = ["--robots", ",".join(ROBOTS), "--noise", "0,0.05", "--seeds", str(SEEDS), "--methods",
        ",".join(METHODS), "--samples", str(SAMPLES)]
DOF = {"lynxmotion": 3, "double_pendulum": 2}


@pytest.fixture(scope="module")
def ray_local():
    from harness.sweep.run import ray_session

    with ray_session() as ray:  # the sweep's own local start-up, kept for the module
        yield ray


def _rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _key(row: dict) -> tuple:
    return (row["robot"], float(row["noise"]), int(row["seed"]), row["method"], int(row["samples"]))


@pytest.fixture(scope="module")
def swept(ray_local, tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    assert main(["sweep", *ARGS, "--out", str(out)]) == 0
    return out


@pytest.mark.slow
def test_one_row_per_cell_with_its_errors(swept):
    rows = _rows(swept / "results.csv")
    want = set(itertools.product(ROBOTS, NOISE, range(SEEDS), METHODS, [SAMPLES]))
    assert len(rows) == len(want) and {_key(r) for r in rows} == want
    for r in rows:
        dof = DOF[r["robot"]]
        assert int(r["dof"]) == dof
        # a 2-joint robot's row leaves joint 3 empty; a 3-joint robot's holds a number
        if dof == 2:
            assert r.get("error_j3", "") == ""
        else:
            assert np.isfinite(float(r["error_j3"]))
        errors = [float(r[f"error_j{j + 1}"]) for j in range(dof)]
        assert float(r["median"]) == np.median(errors)
        assert 0 < float(r["seconds"]) <= float(r["cell_seconds"])
        if float(r["noise"]) == 0:  # the libraries span the truth: noise-free data are exact
            assert max(errors) < 1e-6
        else:  # noisy data are never fitted exactly (the coupled model may extrapolate badly
            # from 300 samples: a Coulomb atom of a joint whose velocity keeps its sign there)
            assert max(errors) > 1e-4 and np.all(np.isfinite(errors))
            assert r["method"] != "oracle" or max(errors) < 0.2
    row = next(r for r in rows if _key(r) == ("lynxmotion", 0.05, 1, "coupled", SAMPLES))
    again = run_cell(Cell("lynxmotion", 0.05, 1, "coupled", SAMPLES))  # serially, here
    assert isinstance(again, CellResult)
    assert [float(row[f"error_j{j + 1}"]) for j in range(3)] == list(again.errors)
    assert (swept / "summary.md").read_text().count("| lynxmotion | coupled |") == 2


@pytest.mark.slow
def test_rerun_reuses_and_a_torn_sweep_resumes(swept, capsys):
    path = swept / "results.csv"
    before = path.read_bytes()
    assert main(["sweep", *ARGS, "--out", str(swept)]) == 0
    assert path.read_bytes() == before and "0 cells computed" in capsys.readouterr().out
    lines = before.decode().splitlines(keepends=True)
    # a sweep killed while writing: the last cell missing, the one before torn mid-line
    path.write_text("".join(lines[:-2]) + lines[-2][: len(lines[-2]) // 2])
    assert main(["sweep", *ARGS, "--out", str(swept)]) == 0
    printed = capsys.readouterr()
    assert "2 cells computed" in printed.out and "1 torn last line" in printed.err
    after = path.read_text().splitlines(keepends=True)
    assert after[: len(lines) - 2] == lines[:-2]  # the finished cells untouched
    old = {_key(r): r for r in csv.DictReader(lines)}
    for r in csv.DictReader([after[0], *after[len(lines) - 2:]]):
        assert all(r[f"error_j{j + 1}"] == old[_key(r)][f"error_j{j + 1}"] for j in range(DOF[r["robot"]]))
    assert len(after) == len(lines)


@pytest.mark.slow
def test_figures_plot_the_median_and_quartiles_of_the_rows(swept, tmp_path):
    grid = parse_grid(",".join(ROBOTS), "0,0.05", SEEDS, ",".join(METHODS), str(SAMPLES))
    results = list(read(swept / "results.csv")[0].values())
    drawn = write_figures(bands(results), results, grid, tmp_path)
    rows = _rows(swept / "results.csv")
    for robot, method in itertools.product(ROBOTS, METHODS):
        x, med, lo, hi = drawn["error_vs_noise.png"][robot][method]
        assert list(x) == [0.0, 5.0]
        for k, noise in enumerate(NOISE):
            errs = [float(r["median"]) * 100 for r in rows
                    if _key(r)[:2] == (robot, noise) and r["method"] == method]
            assert len(errs) == SEEDS
            assert np.allclose([med[k], lo[k], hi[k]], np.percentile(errs, [50, 25, 75]), rtol=1e-12)
        assert len(drawn["time_per_method.png"][robot][method]) == len(NOISE) * SEEDS
    for name in drawn:
        image = imread(tmp_path / name)
        assert image.shape[0] > 100 and image.shape[1] > 300 and image.std() > 0
    assert {f.name for f in swept.glob("*.png")} == set(drawn)


@pytest.mark.parametrize("change, message", [
    (["--methods", "coupled,lasso"], "--methods: 'lasso' is not a method"),
    (["--robots", "lynxmotion,nosuchbot"], "unknown robot 'nosuchbot'"),
    (["--noise", "0,-0.1"], "--noise: '-0.1' is not a finite noise fraction"),
    (["--samples", "20"], "--samples 20 is too few for robot lynxmotion"),
    (["--samples", "249"], "--samples 249 is too few for the sparse methods"),
    (["--seeds", "0"], "--seeds must be a number of seeds >= 1"),
])
def test_bad_input_is_one_line_and_no_output(tmp_path, capsys, change, message):
    args = dict(zip(ARGS[::2], ARGS[1::2], strict=True))
    args.update(dict(zip(change[::2], change[1::2], strict=True)))
    out = tmp_path / "out"
    assert main(["sweep", *itertools.chain(*args.items()), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1 and not out.exists()


def _result(robot: str, seed: int, dof: int) -> CellResult:
    errors = tuple(0.001 * (seed + 1) * (j + 1) for j in range(dof))
    return CellResult(Cell(robot, 0.05, seed, "oracle", 400), errors, 0.5, 1.0, 0.9)


def test_store_drops_a_torn_line_and_widens_for_more_joints(tmp_path):
    path = tmp_path / "results.csv"
    store = ResultsStore(path, 2)
    for seed in range(3):
        store.append(_result("double_pendulum", seed, 2))
    path.write_bytes(path.read_bytes()[:-7])  # the last row torn
    store = ResultsStore(path, 3)  # a 3-joint robot joins: one more error column
    assert store.dropped == 1 and len(store.rows) == 2
    store.append(_result("lynxmotion", 0, 3))
    rows, joints, dropped = read(path)
    assert joints == 3 and dropped == 0 and len(rows) == 3
    assert rows[_result("double_pendulum", 1, 2).cell.key] == _result("double_pendulum", 1, 2)
    assert rows[_result("lynxmotion", 0, 3).cell.key].errors == (0.001, 0.002, 0.003)
    # a complete line damaged in the middle of the file is not a torn write: an error, the
    # file left as it is (it was dropped silently before)
    text = path.read_text().splitlines(keepends=True)
    damaged = "".join([text[0], text[1].replace(",", ";", 2), *text[2:]])
    path.write_text(damaged)
    with pytest.raises(UserError, match="line 2 is unreadable"):
        ResultsStore(path, 3)
    assert path.read_text() == damaged
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not a sweep's results file"):
        ResultsStore(tmp_path / "other.csv", 2)


def test_a_cell_a_user_can_fix_comes_back_as_a_failure(tmp_path):
    missing = tmp_path / "arm.urdf"
    failure = run_cell(Cell(str(missing), 0.05, 0, "oracle", 300))
    assert isinstance(failure, CellFailure) and str(missing) in failure.message


def test_progress_counts_cells_and_reused_ones():
    stream = io.StringIO()
    progress = Progress(total=5, done=2, stream=stream, every=0.0)
    progress.update()
    progress.update(2)
    lines = stream.getvalue().splitlines()
    assert [line.split(" | ")[0] for line in lines] == ["sweep: 3/5 cells, 2 reused",
                                                        "sweep: 5/5 cells, 2 reused"]
    assert lines[-1].endswith("~0:00 left") and "elapsed" in lines[0]


@pytest.mark.slow  # Ray's local start-up: about 20 s of the fast suite's CPU
def test_a_small_window_of_tasks_runs_every_cell_once(ray_local):
    from harness.sweep.run import ray_cells

    cells = [Cell("double_pendulum", 0.05, s, "oracle", 300) for s in range(5)]
    results = list(ray_cells(ray_local, cells, window=2))
    assert sorted(r.cell for r in results) == cells
    assert all(r.errors == run_cell(r.cell).errors for r in results[:1])
