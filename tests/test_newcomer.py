"""Small things a newcomer met (issue #58): the test run prints no CasADi notice, the slow
marker says what the Makefile does, replay names the robot (and the plant's dynamics),
`torquebench robots` lists where the robots are."""

from __future__ import annotations

import json
import re
import tomllib
import warnings
from pathlib import Path
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from harness.cli import main
from harness.commands.replay import _plant_words, summary
from harness.errors import UserError
from harness.robots.arm import Arm
from harness.robots.registry import ROBOTS, erd_robots_dir
from tests.test_replay import quintic_plan

ROOT = Path(__file__).resolve().parent.parent


def test_casadis_numpy_notice_is_not_printed_by_the_tests():
    """CasADi 3.8's 20-line FutureWarning on np.allclose(DM, ...) (pytest filterwarnings)."""
    with warnings.catch_warnings(record=True) as caught:
        assert np.allclose(ca.DM([1.0, 2.0]), [[1.0], [2.0]])
    assert not [w for w in caught if "casadi" in str(w.message)]


def test_the_slow_marker_says_what_make_test_does():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    slow = next(m for m in config["markers"] if m.startswith("slow:"))
    makefile = (ROOT / "Makefile").read_text()
    test_rule = re.search(r"^test:.*?(?=^\S)", makefile, re.M | re.S).group(0)
    assert '-m "not slow"' in test_rule and "make test-slow" in slow
    assert "run in make test" not in slow and "make test leaves them out" in slow


def test_replay_names_the_robot_and_the_plants_dynamics(tmp_path, capsys):
    """`replay --plant model.json` said 'replayed plan.json on model.json'."""
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(quintic_plan()))
    urdf = ROOT / "models" / "lynxmotion" / "lynxmotion.urdf"
    capsys.readouterr()
    assert main(["replay", "--plan", str(plan), "--plant", str(urdf),
                 "--out", str(tmp_path / "r.json")]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"replayed {plan} on lynxmotion with the dynamics of {urdf}: energy ")
    result = SimpleNamespace(energy_error=0.01, energy=1.0, energy_planned=0.99,
                             min_clearance=0.05, tracking_rms=1e-3)
    assert summary("p.json", "ur5", result, _plant_words("model.json")).startswith(
        "replayed p.json on ur5 with the dynamics model.json identified: energy 1.0000 J")


def test_robots_lists_the_registered_and_example_robot_datas_urdfs(capsys):
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    for name in ROBOTS:
        assert f"  {name}" in out
    ur3 = erd_robots_dir() / "ur_description" / "urdf" / "ur3_robot.urdf"
    assert f"  {ur3}: 6 joints\n" in out and str(erd_robots_dir()) in out
    assert main(["robots", "--registered"]) == 0
    assert str(ur3) not in capsys.readouterr().out


def test_robots_lists_only_what_loads_as_usable_and_the_others_with_the_reason(capsys):
    """finger_edu was listed as usable while MuJoCo refused it; TIAGo Pro's whole robot is
    refused by every command (a prismatic torso below its arms)."""
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    usable, refused = out.split("not usable as they are")
    rows = dict(line.strip().split(": ", 1) for line in refused.splitlines()[1:] if line.strip())
    tiago = erd_robots_dir() / "tiago_pro_description" / "robots" / "tiago_pro.urdf"
    assert "prismatic arm joint 'torso_lift_joint'" in rows[str(tiago)]
    assert f"  {tiago}" not in usable
    # the joint counts of usable files, read apart from the harness: the URDF's moving joints
    # (the UR3's six revolute, the SO-100's six: its jaw is revolute)
    import xml.etree.ElementTree as ET

    for path in (erd_robots_dir() / "ur_description" / "urdf" / "ur3_robot.urdf",
                 erd_robots_dir() / "so_arm_description" / "urdf" / "so100.urdf"):
        moving = [j for j in ET.parse(path).getroot().iter("joint")
                  if j.get("type") in ("revolute", "continuous")]
        assert f"  {path}: {len(moving)} joints\n" in usable
    for path in rows:  # every file refused is refused by the commands too (chain, engines)
        with pytest.raises(UserError):
            Arm.of(path).dof and Arm.of(path).mujoco  # noqa: B018


def test_the_replay_table_says_what_separates_its_two_clearances():
    """The table showed 80.0 mm centre to link beside 48.0 mm surface distance and never said
    that the difference is the link capsule's radius plus the obstacle's."""
    from harness.bench.replay import _markdown, surface_note
    from harness.replay.reference import plan_reference
    from harness.replay.simulate import replay
    from harness.robots.arm import Arm
    from harness.robots.scene import replay_scene

    arm = Arm.of("lynxmotion")
    model = replay_scene(arm)
    note = surface_note(model, arm.geometry)
    assert "(radius 12 mm)" in note and "(radius 20 mm)" in note and ", 32 mm." in note
    _, trace = replay(model, plan_reference(quintic_plan()), arm.nominal, geometry=arm.geometry)
    np.testing.assert_allclose(trace.clearance - trace.surface, 0.032, atol=1e-9)  # the run's
    assert note in _markdown("lynxmotion", {}, {}, {}, note)


def _link(name: str) -> str:
    return (f'<link name="{name}"><inertial><mass value="1"/><origin xyz="0 0 0.1"/><inertia '
            'ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>')


def _joint(name: str, parent: str, child: str, xyz: str) -> str:
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child '
            f'link="{child}"/><origin xyz="{xyz}"/><axis xyz="0 1 0"/><limit lower="-1" '
            'upper="1" effort="10" velocity="1"/></joint>')


def test_a_robot_that_is_not_a_serial_chain_is_refused_naming_its_joints(tmp_path):
    """The refusal said 'joint 3 does not follow joint 2'; the URDF's names tell more."""
    from harness.errors import UserError
    from harness.robots.arm import Arm

    urdf = tmp_path / "forked.urdf"
    urdf.write_text('<?xml version="1.0"?><robot name="forked"><link name="base"/>'
                    + "".join(_link(n) for n in "abc")
                    + _joint("shoulder", "base", "a", "0 0 0") + _joint("elbow", "a", "b", "0 0 0.2")
                    + _joint("thumb", "a", "c", "0 0.1 0.2") + "</robot>")
    with pytest.raises(UserError, match="joint 'thumb' does not follow joint 'elbow' "
                                        r"\(it hangs on joint 'shoulder'\): not a serial chain"):
        Arm.of(str(urdf)).chain  # noqa: B018 - reading it checks the chain


def test_model_json_labels_its_numbers(tmp_path):
    """MODEL.json's coefficients had no units, its standard parameters were a bare list and
    its friction's 'shape: []' was unexplained; a loader reads the labelled file back."""
    from harness.robots.arm import Arm
    from identification.feature_model import IdentifiedModel, JointModel
    from identification.model import load_model, model_to_dict

    feature = IdentifiedModel(2, (JointModel(("qd1^2*sin(q2)", "qdd1", "qd2", "cos(q1)", "q2"),
                                             (1.0,) * 5), JointModel((), ())), "paper", "coupled")
    assert model_to_dict(feature)["joints"][0]["coefficient_units"] == [
        "N m s^2/rad^2", "N m s^2/rad", "N m s/rad", "N m", "N m/rad"]
    data, out = tmp_path / "d.npz", tmp_path / "m.json"
    assert main(["generate", "--robot", "lynxmotion", "--samples", "1200", "--seed", "2",
                 "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--prior", "nominal", "--out", str(out)]) == 0
    payload = json.loads(out.read_text())
    for joint in payload["joints"]:
        assert len(joint["coefficient_units"]) == len(joint["terms"])
        units = dict(zip(joint["terms"], joint["coefficient_units"], strict=True))
        assert all(u == payload["base_parameters"][t]["unit"] for t, u in units.items())
    assert "per unit of its term" in payload["units"]
    assert all("shape" in law["description"] for law in payload["friction"])
    physical = payload["metrics"]["physical"]
    names, units = physical["standard_parameter_names"], physical["standard_parameter_units"]
    assert len(names) == len(units) == len(physical["standard_parameters"]) == 30
    assert names[:5] == ["m1", "mcx1", "mcy1", "mcz1", "Ixx1"] and units[:5] == [
        "kg", "kg m", "kg m", "kg m", "kg m^2"]
    assert "not at the centre of mass" in physical["standard_parameters_frame"]
    assert payload["bodies"][0]["inertia_at_com"]["about"].startswith("the centre of mass")
    arm = Arm.of("lynxmotion")
    assert load_model(out, lambda: arm.library).dof == 3


def test_excite_and_generate_print_one_condition_number(tmp_path, capsys):
    """`excite` printed 32 for the default excitation while `generate` along it printed
    'normalized condition 44.2, excitation condition 3.71': two definitions, named apart."""
    from harness.data.generate import condition_number
    from harness.robots.arm import Arm

    def figure(line: str) -> float:
        return float(re.search(r"excitation condition number ([0-9.e+-]+)", line).group(1))

    traj = tmp_path / "traj.csv"
    assert main(["excite", "--robot", "lynxmotion", "--duration", "5", "--rate", "200",
                 "--iterations", "2", "--harmonics", "5", "--seed", "1", "--out", str(traj)]) == 0
    excite = capsys.readouterr().out
    designed = figure(excite)
    default = float(re.search(r"generate's default excitation's ([0-9.e+-]+)", excite).group(1))
    assert main(["generate", "--robot", "lynxmotion", "--excitation", str(traj),
                 "--out", str(tmp_path / "along.npz")]) == 0
    assert figure(capsys.readouterr().out) == designed
    assert main(["generate", "--robot", "lynxmotion", "--samples", "1000", "--seed", "1",
                 "--out", str(tmp_path / "default.npz")]) == 0
    assert figure(capsys.readouterr().out) == default
    data = np.load(tmp_path / "default.npz")
    meta = json.loads(str(data["meta"]))
    q, qd, qdd = (np.asarray(data[k]) for k in ("q", "qd", "qdd"))
    assert meta["condition_number"] == pytest.approx(condition_number(Arm.of("lynxmotion"), q, qd, qdd))
    assert "excitation_condition" in meta  # the older figure kept


def test_closeloop_says_when_its_leftover_is_the_sensor_noise(tmp_path, capsys):
    """On a clean simulated robot closeloop names nothing (right) and left the user to guess
    whether 0.035 after is good: it is what the data's declared noise alone gives."""
    from identification.closeloop.closed.noise_level import declared_sigma, noise_line

    data = tmp_path / "d.npz"
    assert main(["generate", "--robot", "lynxmotion", "--samples", "1500", "--seed", "4",
                 "--out", str(data)]) == 0
    capsys.readouterr()
    assert main(["closeloop", "--data", str(data), "--out", str(tmp_path / "cl")]) == 0
    out = capsys.readouterr().out
    assert "nothing named: the model is the declared one" in out
    assert "unexplained joints: none" in out
    line = next(x for x in out.splitlines() if "the leftover is at the sensor noise's level" in x)
    after = re.search(r"after \[([^]]*)\]", out).group(1)
    assert f"error after [{after}] against [" in line
    assert "that the data's declared noise (0.05 of each joint's torque std) alone gives" in line
    # the floor: the declared noise's std over the scored torque's RMS, per joint
    tau = np.load(data)["tau_clean"]
    sigma, level = declared_sigma([{"noise": 0.05}], [tau])
    np.testing.assert_allclose(sigma, 0.05 * tau.std(axis=0))
    assert level == 0.05
    assert declared_sigma([{}], [tau]) is None
    assert noise_line([0.2, 0.05], [0.05, 0.05], "x") is None  # joint 1 well above: not said


def test_the_paper_librarys_miss_is_measured():
    """The paper library's rows read 103.87x and 749.99x the oracle with no word on why: on
    the Lynxmotion it lacks joint 1's qd1*qd2*sin(2*q2), so no coefficients reach below a
    floor there; joints 2 and 3 it spans exactly."""
    from harness.data.generate import generate
    from harness.identify.fits import library_named
    from harness.identify.library_gap import library_gap, markdown
    from harness.identify.scoring import HOLDOUT, sines_motion
    from harness.robots.arm import Arm
    from identification.identify import identify

    arm = Arm.of("lynxmotion")
    clean = generate(arm, 2000, 0.0, 1, "inverse")
    prior, paper = library_named("prior", arm), library_named("paper", arm)
    exact = identify(clean.q, clean.qd, clean.qdd, clean.tau, prior, HOLDOUT, clean.tau_clean)
    judge = sines_motion(arm, 2000, 5)
    gap = library_gap(paper, exact.model, prior, [judge], clean, 1500)
    assert [(m["joint"], m["term"]) for m in gap["missing"]] == [(1, "qd1*qd2*sin(2*q2)")]
    # the floor is plain least squares of the clean torque on the paper's columns
    X = paper.evaluate(judge.q, judge.qd, judge.qdd)
    tau = judge.tau_clean
    best = [np.linalg.norm(X @ np.linalg.lstsq(X, tau[:, j], rcond=None)[0] - tau[:, j])
            / np.linalg.norm(tau[:, j]) for j in range(3)]
    np.testing.assert_allclose(gap["floor"]["sines"], best, rtol=1e-6, atol=1e-9)
    assert best[0] > 1e-3 and max(best[1:]) < 1e-9
    # fitted without noise on the draw, the stand-in for the missing term does not carry over
    part = slice(0, 1500)
    c = np.linalg.lstsq(paper.evaluate(clean.q[part], clean.qd[part], clean.qdd[part]),
                        clean.tau_clean[part], rcond=None)[0]
    carried = np.linalg.norm(X @ c - tau, axis=0) / np.linalg.norm(tau, axis=0)
    np.testing.assert_allclose(gap["noise_free_fit"]["sines"], carried, rtol=1e-9)
    assert carried[0] > 3 * best[0]
    note = markdown(gap, {"sines": np.full(3, best[0] / 100)}, 0.05)
    assert "lack joint 1: `qd1*qd2*sin(2*q2)`" in note and "100x the oracle's" in note
    assert f"errs far more on the judges: on `sines`, joint 1: {100 * carried[0]:.2f} %" in note
    assert "Joints 2, 3 it spans exactly" in note


def _fake_trace(k: int, dof: int = 3, n: int = 50):
    t = np.linspace(0.0, 1.0, n)
    q = np.sin(np.outer(t, np.arange(1, dof + 1)))
    return SimpleNamespace(t=t, q=q + 1e-4 * k, q_ref=q)


def test_the_tracking_figure_has_a_panel_per_joint_and_its_legend_beside_the_data():
    """replay_tracking.png crowded 18 series (6 plans x 3 joints) on one axis under its
    legend."""
    from harness.replay.figures import tracking_axes
    from harness.report.figures import plt

    fig = tracking_axes({f"plan{k}": _fake_trace(k) for k in range(6)})
    fig.canvas.draw()
    assert len(fig.axes) == 3 and all(len(ax.lines) == 6 for ax in fig.axes)
    assert all(ax.get_legend() is None for ax in fig.axes) and len(fig.legends) == 1
    legend = fig.legends[0].get_window_extent()
    assert not any(legend.overlaps(ax.get_window_extent()) for ax in fig.axes)
    assert all("(mrad)" in ax.get_ylabel() for ax in fig.axes)
    plt.close(fig)


def test_figures_write_units_in_parentheses():
    """Figures wrote '[s]' in some places, '(s)' in others: parentheses everywhere."""
    bracket = re.compile(r"""(label|title)[^\n]*["'][^"'\n]*\[(s|m|W|mrad|rad|N m|J|mm|-|\{unit\})\]""")
    offenders = []
    for path in [*ROOT.glob("harness/**/*.py"), *ROOT.glob("planning/**/*.py")]:
        text = path.read_text()
        if "plt" in text or "ax.set" in text:
            offenders += [f"{path.relative_to(ROOT)}:{m.group(0)}" for m in bracket.finditer(text)]
    assert not offenders


def test_the_3d_path_names_the_links_and_draws_the_clearance_threshold(monkeypatch):
    """planning_path3d.png drew the links at mid-time with no legend entry, and no threshold."""
    import harness.bench.planning.figures as figures
    from planning.formulation.kinematics import paper_arm

    geometry, t = paper_arm(), np.linspace(0.0, 2.0, 41)
    q = np.column_stack([np.linspace(1.5, -1.5, 41), np.full(41, 0.6), np.full(41, -0.8)])
    centre = np.column_stack([np.full(41, 0.15), np.linspace(0.4, -0.35, 41), np.full(41, 0.22)])
    clearance = np.abs(t - 1.25)[:, None] + np.array([[0.08, 0.1]])  # closest at t = 1.25 s
    plan = SimpleNamespace(t=t, q=q, obstacle=centre, clearance=clearance)
    scenario = SimpleNamespace(duration=2.0, obstacle=SimpleNamespace(
        position=lambda s: np.column_stack([np.full(np.size(s), 0.15),
                                            0.4 - 0.375 * np.atleast_1d(s),
                                            np.full(np.size(s), 0.22)])))
    kept = {}
    monkeypatch.setattr(figures, "save_figure", lambda fig, path, **_: kept.setdefault("fig", fig))
    figures.path3d({"unobstructed": plan, "pinocchio": plan}, scenario, geometry, Path("x.png"),
                   threshold=0.08)
    fig = kept["fig"]
    labels = [text.get_text() for legend in fig.legends for text in legend.get_texts()]
    assert "links at mid-time (t = 1 s), each plan's colour" in labels
    sphere = next(x for x in labels if x.startswith("clearance threshold λ = 80 mm"))
    assert "closest approach to pinocchio (t = 1.25 s)" in sphere
    assert "pinocchio's links then" in labels
    wire = next(c for c in fig.axes[0].collections if c.get_label() == sphere)
    ends = np.concatenate([np.asarray(seg) for seg in wire._segments3d])
    np.testing.assert_allclose(np.linalg.norm(ends - centre[25], axis=1), 0.08, atol=1e-12)
    figures.plt.close(fig)


HEAVY = ("numpy", "scipy", "mujoco", "pinocchio", "casadi", "sklearn")


@pytest.mark.parametrize("args, code", [(["--help"], 0), (["--version"], 0), (["idnetify"], 2),
                                        ([], 2)])
def test_help_version_and_a_mistyped_command_import_no_library(args, code):
    """`torquebench --help`, `--version`, a mistyped command and none at all answer before any
    of the numerical libraries is imported (they took 2-19 s of imports to answer): a fresh
    interpreter, the modules it loaded looked at afterwards."""
    import subprocess
    import sys

    probe = ("import sys\nfrom harness.cli import main\ntry:\n    code = main(sys.argv[1:])\n"
             "except SystemExit as e:\n    code = e.code\n"
             f"print('LOADED', [m for m in {HEAVY!r} if m in sys.modules], code)")
    out = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True,
                         timeout=120, cwd=Path(__file__).parent.parent)
    loaded = [line for line in out.stdout.splitlines() if line.startswith("LOADED")]
    assert loaded == [f"LOADED [] {code}"], out.stdout + out.stderr
    if args == ["--version"]:
        from importlib.metadata import version

        assert f"torquebench {version('torquebench')}" in out.stdout


def test_every_option_of_every_command_says_what_it_does():
    """`torquebench COMMAND --help` has a text for every option (closeloop's --samples and
    --holdout, generate's --seed and --mode had none)."""
    import argparse

    from harness.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    silent = [f"{name} {a.option_strings[0]}" for name, parser in sub.choices.items()
              for a in parser._actions if a.option_strings and a.help is None]
    assert not silent
