"""Property-based tests of every loader (hypothesis): whatever a user hands the CLI - an
empty, truncated or corrupted file, wrong types, NaN/inf, missing or renamed keys, wrong
shapes, absurd magnitudes - the answer is a result (exit 0, complete file) or one clear line
and exit 2 with no output file; never a traceback.

Each property starts from a real, valid input (a generated dataset, identified models, a
plan, the robot's MJCF and URDF, a CSV log) and mutates it. `TORQUEBENCH_HYPOTHESIS=full` (make test,
CI) runs 250 cases per property (1500 in all), the default 30.
"""

from __future__ import annotations

import io
import json
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from harness.cli import main
from harness.data.dataset import load_arrays
from harness.data.generate import generate
from harness.errors import UserError
from harness.io import write_npz
from harness.robots.arm import Arm
from models import MODELS
from tests.result_files import incomplete_files

KEYS = ("t", "q", "qd", "qdd", "tau", "tau_clean")
SAMPLES = 300  # identify needs > 200 training samples: some mutants get that far


@pytest.fixture(scope="module")
def valid(tmp_path_factory):
    """A valid dataset, two identified models of it (prior and kinematic), a short plan."""
    root = tmp_path_factory.mktemp("valid")
    data = generate(Arm.of("lynxmotion"), SAMPLES, 0.05, seed=3)
    arrays = {k: v for k, v in data.arrays().items() if k in (*KEYS, "meta")}
    write_npz(root / "data.npz", **arrays)
    models = []
    for library in ("prior", "kinematic"):
        out = root / f"model_{library}.json"
        assert main(["identify", "--data", str(root / "data.npz"), "--library", library,
                     "--holdout", "0.1", "--out", str(out)]) == 0
        models.append(json.loads(out.read_text()))
    t = np.linspace(0.0, 0.05, 11)
    pose = np.array([np.pi / 2, np.pi / 5, -np.pi / 4])
    plan = {"t": t.tolist(), "q": np.tile(pose, (11, 1)).tolist(),
            "qd": np.zeros((11, 3)).tolist(), "qdd": np.zeros((11, 3)).tolist(),
            "obstacle": np.tile([0.5, 0.5, 0.5], (11, 1)).tolist(), "threshold": 0.08,
            "energy": 0.0, "min_clearance": 0.3}
    return {"root": root, "arrays": Named("dataset arrays", arrays), "data": root / "data.npz",
            "models": [Named(f"MODEL.json {k}", m) for k, m in enumerate(models)],
            "plan": Named("PLAN.json", plan)}


class Named(dict):
    """A dict that prints as its name (hypothesis prints the strategies' arguments)."""

    def __init__(self, name: str, value: dict) -> None:
        super().__init__(value)
        self.name = name

    def __repr__(self) -> str:
        return self.name


def check_cli(argv: list[str], out: Path, capfd) -> int:
    """Run the CLI in-process: exit 0 with a complete out, or exit 2, one line, no out. capfd:
    what C++ parsers print on the process's stderr counts too."""
    code = main(argv)
    err = capfd.readouterr().err.strip()
    assert code in (0, 2), (code, err)
    bad, temporaries = incomplete_files(out.parent)
    assert not bad and not temporaries, (bad, temporaries)
    if code == 2:
        assert len(err.splitlines()) == 1 and ": error: " in err, err
        assert not out.exists()
    else:
        assert out.exists()
    return code


# ---- mutations -------------------------------------------------------------------------

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10**12, 10**12) | st.text(max_size=8)
    | st.floats(allow_nan=True, allow_infinity=True),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                 max_size=3),
    max_leaves=12)
absurd = st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e12, 1e9])


def _paths(tree, prefix=()):
    """Every (path to a value) of a JSON tree."""
    yield prefix
    if isinstance(tree, dict):
        for k, v in tree.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(tree, list):
        for k, v in enumerate(tree[:3]):
            yield from _paths(v, (*prefix, k))


def _set(tree, path, value, delete=False):
    if not path:
        return value
    parent = tree
    for k in path[:-1]:
        parent = parent[k]
    if delete and isinstance(parent, dict):
        del parent[path[-1]]
    elif delete:
        parent.pop(path[-1])
    else:
        parent[path[-1]] = value
    return tree


@st.composite
def mutated_json(draw, base: dict) -> str:
    """JSON text: base with values replaced, deleted, renamed or set absurd; or its text
    truncated or garbled."""
    tree = json.loads(json.dumps(dict(base)))
    for _ in range(draw(st.integers(1, 3))):
        paths = list(_paths(tree))
        path = draw(st.sampled_from(paths))
        action = draw(st.sampled_from(["replace", "delete", "rename", "absurd", "stringify"]))
        target = tree
        for k in path[:-1] if path else ():
            target = target[k]
        if action == "replace" or not path:
            tree = _set(tree, path, draw(json_values))
        elif action == "delete":
            tree = _set(tree, path, None, delete=True)
        elif action == "rename" and isinstance(target, dict):
            target[path[-1] + draw(st.sampled_from(["_", "s", "X"]))] = target.pop(path[-1])
        elif action == "absurd":
            tree = _set(tree, path, float(draw(absurd)))
        elif action == "stringify":
            tree = _set(tree, path, str(target[path[-1]])[:20])
        if not isinstance(tree, dict | list):
            break
    text = json.dumps(tree)
    how = draw(st.sampled_from(["keep", "keep", "keep", "truncate", "garble"]))
    return text if how == "keep" else _damage(text, how, draw)


def _damage(text: str, how: str, draw) -> str:
    if how == "truncate":
        return text[:draw(st.integers(0, max(len(text) - 1, 0)))]
    k = draw(st.integers(0, max(len(text) - 1, 0)))
    return text[:k] + draw(st.text(min_size=1, max_size=4)) + text[k + 1:]


@st.composite
def damaged_bytes(draw, good: bytes) -> bytes:
    """good truncated, with bytes overwritten, or replaced by random bytes."""
    how = draw(st.sampled_from(["truncate", "flip", "random", "empty"]))
    if how == "empty":
        return b""
    if how == "random":
        return draw(st.binary(max_size=200))
    if how == "truncate":
        return good[:draw(st.integers(0, len(good) - 1))]
    data = bytearray(good)
    for _ in range(draw(st.integers(1, 8))):
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
    return bytes(data)


array_dtypes = st.sampled_from(["<f8", "<f4", "<i8", "<c16", "|b1", "<U3", "|S2"])


@st.composite
def mutated_arrays(draw, arrays: dict) -> dict:
    """The dataset's arrays with keys dropped or renamed, arrays of other dtypes and shapes,
    NaN/inf/absurd entries, or a broken meta."""
    out = dict(arrays)
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(sorted(out) or ["q"]))
        action = draw(st.sampled_from(["drop", "rename", "replace", "poke", "reshape", "meta",
                                       "rows"]))
        if key not in out:
            continue
        if action == "drop":
            del out[key]
        elif action == "rename":
            out[key.upper() + "_"] = out.pop(key)
        elif action == "replace":
            out[key] = draw(hnp.arrays(array_dtypes, hnp.array_shapes(min_dims=0, max_dims=3,
                                                                       min_side=0, max_side=4)))
        elif action == "poke" and out[key].dtype.kind == "f" and out[key].size:
            x = out[key].copy()
            x.flat[draw(st.integers(0, x.size - 1))] = draw(absurd)
            out[key] = x
        elif action == "reshape" and out[key].ndim == 2:
            out[key] = draw(st.sampled_from([out[key].T, out[key][:, :2], out[key].ravel(),
                                             out[key][None]]))
        elif action == "meta":
            out["meta"] = draw(st.sampled_from([np.array("{not json"), np.array("[1, 2]"),
                                                np.arange(3.0), np.array(["a", "b"])]))
        elif action == "rows" and out[key].ndim >= 1:
            out[key] = out[key][:draw(st.integers(0, 3))]
    return out


def _fresh(suffix: str) -> tuple[Path, Path]:
    folder = Path(tempfile.mkdtemp(prefix="torquebench-prop-"))
    return folder / f"input{suffix}", folder / "out" / f"result{suffix}"


# ---- properties ------------------------------------------------------------------------

@given(data=st.data())
def test_dataset_npz_mutated_arrays(valid, capfd, data):
    """Arrays dropped, renamed, of other dtypes or shapes, poked with NaN/inf/absurd values."""
    arrays = data.draw(mutated_arrays(valid["arrays"]))
    path, out = _fresh(".npz")
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)  # object arrays pickled: the loader must refuse them
    path.write_bytes(buffer.getvalue())
    command = data.draw(st.sampled_from(["predict", "identify"]))
    argv = (["predict", "--model", "pinocchio"] if command == "predict" else ["identify"])
    check_cli([*argv, "--data", str(path), "--out", str(out.with_suffix(
        ".npz" if command == "predict" else ".json"))], out.with_suffix(
        ".npz" if command == "predict" else ".json"), capfd)


@given(data=st.data())
def test_dataset_npz_damaged_bytes(valid, capfd, data):
    path, out = _fresh(".npz")
    path.write_bytes(data.draw(damaged_bytes(valid["data"].read_bytes())))
    check_cli(["predict", "--model", "pinocchio", "--data", str(path), "--out", str(out)], out,
              capfd)


@given(data=st.data())
def test_model_json_mutated(valid, capfd, data):
    model = data.draw(st.sampled_from(valid["models"]))
    path, out = _fresh(".json")
    path.write_text(data.draw(mutated_json(model)))
    out = out.with_suffix(".npz")
    check_cli(["predict", "--model", str(path), "--data", str(valid["data"]), "--out", str(out)],
              out, capfd)


@given(data=st.data())
def test_plan_json_mutated(valid, capfd, data):
    path, out = _fresh(".json")
    path.write_text(data.draw(mutated_json(valid["plan"])))
    check_cli(["replay", "--plan", str(path), "--out", str(out)], out, capfd)


ROBOT_FILES = {".xml": (MODELS / "lynxmotion" / "lynxmotion.xml").read_text(),
               ".urdf": (MODELS / "lynxmotion" / "lynxmotion.urdf").read_text()}


@st.composite
def mutated_robot(draw, text: str) -> str:
    """Robot description text with an attribute set to junk or an absurd number, an element
    deleted, or the text truncated or garbled."""
    how = draw(st.sampled_from(["attribute", "attribute", "element", "truncate", "garble"]))
    if how in ("truncate", "garble"):
        return _damage(text, how, draw)
    if how == "element":
        tags = list(re.finditer(r"<(\w+)\b[^>]*/>", text))
        m = draw(st.sampled_from(tags))
        return text[:m.start()] + text[m.end():]
    attrs = list(re.finditer(r'(\w+)="([^"]*)"', text))
    m = draw(st.sampled_from(attrs))
    value = draw(st.sampled_from(["nan", "inf", "-1", "1e300", "0", "", "x y", "1 2 3 4 5"])
                 | st.text(alphabet="0123456789.-e ", max_size=12))
    return text[:m.start(2)] + value + text[m.end(2):]


@given(data=st.data())
def test_robot_file_mutated(valid, capfd, data):
    suffix = data.draw(st.sampled_from(sorted(ROBOT_FILES)))
    path, out = _fresh(suffix)
    path.write_text(data.draw(mutated_robot(ROBOT_FILES[suffix])))
    for load in (lambda p: Arm.of(p).mujoco, lambda p: Arm.of(p).pinocchio,
                 lambda p: Arm.of(p).chain):  # a fresh path each draw: Arm.of caches by path
        try:
            load(str(path))
        except UserError as exc:  # the loader's own message is one line, not only the CLI's
            assert str(exc).strip() and "\n" not in str(exc) and "\r" not in str(exc), str(exc)
    capfd.readouterr()  # what the loads above printed is not the command's output
    out = out.with_suffix(".npz")
    check_cli(["predict", "--model", "pinocchio", "--robot", str(path), "--data",
               str(valid["data"]), "--out", str(out)], out, capfd)


# ---- the cases of issue #16, one by one -------------------------------------------------

FRAME_MJCF = ('<mujoco><worldbody><frame pos="0 0 0.1"><body name="a"><joint name="j1" '
              'type="hinge" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.2 0 0" '
              'size="0.02" mass="1"/></body></frame></worldbody></mujoco>')


@pytest.mark.parametrize("case", ["empty npz", "NaN coefficient", "Infinity coefficient",
                                  "MJCF Pinocchio cannot read", "URDF with a NaN mass",
                                  "MJCF with a NaN", "corrupted .npy header"])
def test_issue_cases_exit_2_one_line(valid, capfd, tmp_path, case):
    out = tmp_path / "out" / "result.npz"
    if case == "empty npz":
        (tmp_path / "empty.npz").write_bytes(b"")
        argv = ["identify", "--data", str(tmp_path / "empty.npz")]
        out = out.with_suffix(".json")
    elif case == "corrupted .npy header":  # found by hypothesis: numpy's header tokenizer fails
        data = valid["data"].read_bytes().replace(b"'fortran_order': False, 'shape': (300, 3)",
                                                  b"'fortran_order'[ False, 'shape': (300, 3)", 1)
        assert data != valid["data"].read_bytes()
        (tmp_path / "header.npz").write_bytes(data)
        argv = ["predict", "--model", "pinocchio", "--data", str(tmp_path / "header.npz")]
    elif case.endswith("coefficient"):
        text = json.dumps(dict(valid["models"][0]))
        value = "NaN" if case.startswith("NaN") else "Infinity"
        text = re.sub(r'("coefficients": \[)[-0-9.e]+', rf"\g<1>{value}", text, count=1)
        (tmp_path / "model.json").write_text(text)
        argv = ["predict", "--model", str(tmp_path / "model.json"), "--data", str(valid["data"])]
    elif case == "MJCF with a NaN":  # found by hypothesis: MuJoCo warns, then builds a model
        mjcf = re.sub(r'(<key name="home" qpos=")[^"]*', r"\g<1>nan", ROBOT_FILES[".xml"])
        assert 'qpos="nan"' in mjcf
        (tmp_path / "nan.xml").write_text(mjcf)
        argv = ["generate", "--plant", str(tmp_path / "nan.xml"), "--samples", "50"]
    elif case.startswith("MJCF"):
        (tmp_path / "frame.xml").write_text(FRAME_MJCF)
        argv = ["generate", "--plant", str(tmp_path / "frame.xml"), "--samples", "50"]
    else:
        urdf = ROBOT_FILES[".urdf"].replace('<mass value="0.3"', '<mass value="nan"')
        assert "nan" in urdf
        (tmp_path / "nan.urdf").write_text(urdf)
        argv = ["predict", "--model", "pinocchio", "--robot", str(tmp_path / "nan.urdf"),
                "--data", str(valid["data"])]
    assert check_cli([*argv, "--out", str(out)], out, capfd) == 2


@st.composite
def mutated_csv(draw, text: str) -> str:
    """CSV log text with a cell set to junk, NaN, inf or an absurd number, a header name
    renamed, a row dropped or repeated, or the text truncated or garbled."""
    lines = text.splitlines()
    how = draw(st.sampled_from(["cell", "cell", "header", "row", "truncate", "garble"]))
    if how in ("truncate", "garble"):
        return _damage(text, how, draw)
    if how == "header":
        names = lines[0].split(",")
        k = draw(st.integers(0, len(names) - 1))
        names[k] = draw(st.sampled_from(["", "q9", "tau", "x", names[k].upper(), names[k] + "_"]))
        lines[0] = ",".join(names)
    elif how == "row":
        k = draw(st.integers(1, len(lines) - 1))
        lines = lines[:k] + lines[k + 1:] if draw(st.booleans()) else lines[:k] + [lines[k]] + lines[k:]
    else:
        k = draw(st.integers(1, len(lines) - 1))
        cells = lines[k].split(",")
        j = draw(st.integers(0, len(cells) - 1))
        cells[j] = draw(st.sampled_from(["nan", "inf", "-inf", "1e300", "", "x", "1,2", "-1e9"])
                        | st.text(alphabet="0123456789.-e ", max_size=8))
        lines[k] = ",".join(cells)
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def csv_log(valid) -> Named:
    """The valid dataset as a measured CSV log: t, q1..q3, tau1..tau3."""
    a = valid["arrays"]
    header = ["t", "q1", "q2", "q3", "tau1", "tau2", "tau3"]
    rows = np.column_stack([a["t"], a["q"], a["tau"]])
    return Named("CSV log", {"text": "\n".join([",".join(header), *(",".join(f"{x:.17g}" for x in r)
                                                                     for r in rows)]) + "\n"})


@given(data=st.data())
def test_csv_log_mutated(csv_log, capfd, data):
    path, out = _fresh(".csv")
    path.write_text(data.draw(mutated_csv(csv_log["text"])))
    out = out.with_suffix(".npz")
    argv = ["ingest", "--csv", str(path), "--robot", "lynxmotion", "--out", str(out)]
    if check_cli(argv, out, capfd) == 0:  # what ingest wrote passes the dataset loader
        load_arrays(out, ("q", "qd", "qdd", "tau"))
