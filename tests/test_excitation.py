"""`torquebench excite` and `generate --excitation`: the designed excitation's file, its limits,
rest at both ends, consistent derivatives, collision-free, better conditioned than generate's
own; data along it match Pinocchio's RNEA; bad input is one line and exit 2."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pinocchio as pin
import pytest

from harness.cli import main
from harness.data.excitation_file import header, read_trajectory, write_trajectory
from harness.data.excite import capsule_clearance, design_for
from harness.data.generate import default_excitation, generate
from harness.robots.arm import Arm
from harness.robots.registry import erd_robots_dir
from identification.excitation.criteria import log_information
from identification.excitation.fourier import design_excitation
from identification.excitation.regressor import AtomRegressor

DURATION, RATE, ACCEL = 4.0, 50.0, 10.0  # short and coarse: the file stays fast
ITERATIONS = 30


@pytest.fixture(scope="module")
def ur5_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("excite") / "ur5.csv"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(["excite", "--robot", "ur5", "--duration", str(DURATION), "--rate", str(RATE),
                     "--accel-limit", str(ACCEL), "--iterations", str(ITERATIONS),
                     "--out", str(out)])
    assert code == 0
    return out, printed.getvalue()


def test_csv_contract(ur5_file):
    out, printed = ur5_file
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(header(6))
    assert lines[0].startswith("t,q1,") and lines[0].endswith(",qdd6")
    traj = read_trajectory(out, 6)
    assert len(traj.t) == int(DURATION * RATE) + 1
    assert np.allclose(np.diff(traj.t), 1 / RATE) and traj.t[0] == 0 and traj.t[-1] == DURATION
    assert "condition number" in printed and "default excitation" in printed


def test_limits_rest_and_derivatives(ur5_file):
    traj = read_trajectory(ur5_file[0], 6)
    arm = Arm.of("ur5")
    lo, hi = arm.position_limits
    pad = 0.05 * (hi - lo)
    assert np.all(traj.q >= lo + pad) and np.all(traj.q <= hi - pad)
    assert np.all(np.abs(traj.qd) <= arm.speed_bounds)
    assert np.all(np.abs(traj.qdd) <= ACCEL)
    for x in (traj.qd, traj.qdd):  # at rest at both ends
        assert np.max(np.abs(x[[0, -1]])) < 1e-9
    assert np.allclose(traj.q[0], traj.q[-1])
    for x, dx in ((traj.q, traj.qd), (traj.qd, traj.qdd)):
        fd = np.gradient(x, traj.t, axis=0)[1:-1]
        assert np.max(np.abs(fd - dx[1:-1])) < 0.02 * np.max(np.abs(dx)) + 1e-9
    assert np.all(capsule_clearance(arm)(traj.q) > 0)


def test_designed_more_informative_than_default_ur5(ur5_file):
    """The default criterion (D-optimal) at the file's samples: a larger log det of the
    regressor's Gram than generate's default excitation over the same duration."""
    traj = read_trajectory(ur5_file[0], 6)
    arm = Arm.of("ur5")
    regressor = AtomRegressor(arm.library)
    default, _ = default_excitation(arm, int(DURATION * 200), 0)
    grid = np.linspace(0, DURATION, 200, endpoint=False)
    designed, ours = (log_information(regressor, *e.evaluate(grid)) for e in (traj, default))
    assert designed < ours


def test_condition_design_better_conditioned_than_default_ur5():
    designed = design_for(Arm.of("ur5"), DURATION, RATE, ACCEL, seed=0, iterations=ITERATIONS,
                          criterion="condition")
    assert designed.condition < designed.default_condition


@pytest.mark.slow
def test_designed_better_conditioned_than_default_panda():
    designed = design_for(Arm.of("panda"), DURATION, RATE, ACCEL, seed=0, iterations=ITERATIONS,
                          criterion="condition")
    assert designed.condition < designed.default_condition


def test_generate_along_the_file_matches_rnea(ur5_file, tmp_path):
    traj = read_trajectory(ur5_file[0], 6)
    data = generate(Arm.of("ur5"), len(traj.t), 0.0, 1, "inverse", excitation=traj)
    assert np.array_equal(data.q, traj.q) and np.array_equal(data.qdd, traj.qdd)
    assert data.meta["rate"] == pytest.approx(RATE)
    tau = Arm.of("ur5").nominal.torque(data.q, data.qd, data.qdd)
    assert np.max(np.abs(tau - data.tau_clean)) <= 1e-9 * np.max(np.abs(data.tau_clean))
    out = tmp_path / "d.npz"
    assert main(["generate", "--robot", "ur5", "--excitation", str(ur5_file[0]), "--samples", "100",
                 "--out", str(out)]) == 0 and out.is_file()



def test_measured_along_the_file_tracks_it(ur5_file, tmp_path):
    """--mode measured along the file: the simulated arm follows the file's motion (within
    its tracking error), on the file's clock, and the sensed torque is Pinocchio's RNEA at
    the states the simulator had."""
    traj = read_trajectory(ur5_file[0], 6)
    data = generate(Arm.of("ur5"), len(traj.t), 0.0, 1, "measured", excitation=traj)
    assert np.array_equal(data.t, traj.t) and data.meta["rate"] == pytest.approx(RATE)
    assert np.max(np.abs(data.truth["q"] - traj.q)) < 5e-3
    tau = Arm.of("ur5").nominal.torque(
        data.truth["q"], data.truth["qd"], data.truth["qdd"])
    assert np.max(np.abs(tau - data.tau_clean)) <= 1e-6 * np.max(np.abs(data.tau_clean))
    out = tmp_path / "m.npz"
    assert main(["generate", "--robot", "ur5", "--excitation", str(ur5_file[0]), "--mode",
                 "measured", "--out", str(out)]) == 0 and out.is_file()

def test_default_excitation_holds_the_velocity_limits():
    arm = Arm.of("ur5")
    exc, _ = default_excitation(arm, 400, 0)
    _, qd, _ = exc.evaluate(np.arange(4000) / 200.0)
    assert np.all(np.abs(qd) <= arm.speed_bounds)
    lynx = Arm.of("lynxmotion")  # within its limits: the excitation it always had
    lo, hi = lynx.position_limits
    same, _ = design_excitation(lo, hi, 3, lambda exc: float(np.sum(exc.sin_coef)), candidates=4)
    held, _ = design_excitation(lo, hi, 3, lambda exc: float(np.sum(exc.sin_coef)), candidates=4,
                                velocity=lynx.speed_bounds)
    assert np.array_equal(same.sin_coef, held.sin_coef) and np.array_equal(same.centre, held.centre)


def _fails(capsys, args, out) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error" in err
    assert not out.exists()


def test_a_hanging_arm_is_told_of_the_floor_and_swings_below_it_without(capsys, tmp_path):
    """A humanoid's arm (its base the shoulder, hanging at q = 0): the default floor z = 0
    cuts its home pose, which excite says in one note; its joint origins (Pinocchio's
    kinematics) stay above that floor, and with --floor none the excitation swings below."""
    robot = str(erd_robots_dir() / "talos_data/robots/talos_left_arm.urdf")
    model = Arm.of(robot).pinocchio
    data = model.createData()
    lowest, notes = {}, {}
    for floor in ("0", "none"):
        out = tmp_path / f"{floor}.csv"
        assert main(["excite", "--robot", robot, "--duration", str(DURATION), "--rate", str(RATE),
                     "--iterations", "3", "--floor", floor, "--out", str(out)]) == 0
        notes[floor] = [x for x in capsys.readouterr().err.splitlines()
                        if x.startswith("note:") and "floor" in x]
        heights = []
        for q in read_trajectory(out, model.nq).q:
            pin.forwardKinematics(model, data, q)
            heights += [data.oMi[j].translation[2] for j in range(2, model.njoints)]
        lowest[floor] = min(heights)
    assert len(notes["0"]) == 1 and "--floor none" in notes["0"][0] and not notes["none"]
    assert lowest["0"] > 0 > lowest["none"], lowest

@pytest.mark.parametrize("change", [
    {"--robot": "nosuchrobot"}, {"--duration": "0"}, {"--rate": "-1"}, {"--accel-limit": "0"},
    {"--duration": "nan"}, {"--floor": "nan"}])
def test_excite_bad_input(capsys, tmp_path, change):
    out = tmp_path / "x.csv"
    options = {"--robot": "ur5", "--duration": "4", "--rate": "50", "--accel-limit": "10", **change}
    _fails(capsys, ["excite", *[x for kv in options.items() for x in kv], "--out", str(out)], out)


def test_excite_unwritable_path(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / "x.csv"
    _fails(capsys, ["excite", "--robot", "ur5", "--duration", "4", "--rate", "50", "--out", str(out)],
           out)


def test_generate_excitation_bad_input(capsys, tmp_path, ur5_file):
    out = tmp_path / "d.npz"
    _fails(capsys, ["generate", "--robot", "panda", "--excitation", str(ur5_file[0]), "--out",
                    str(out)], out)  # 6 joints for a 7-joint robot
    late = tmp_path / "late.csv"
    traj = read_trajectory(ur5_file[0], 6)
    write_trajectory(late, type(traj)(traj.t + 1.0, traj.q, traj.qd, traj.qdd))
    _fails(capsys, ["generate", "--robot", "ur5", "--excitation", str(late), "--mode",
                    "measured", "--out", str(out)], out)  # measured mode starts at t = 0
    bad = tmp_path / "bad.csv"
    bad.write_text("time,a,b\n0,1,2\n")
    _fails(capsys, ["generate", "--robot", "ur5", "--excitation", str(bad), "--out", str(out)], out)
    traj = read_trajectory(ur5_file[0], 6)
    write_trajectory(bad, traj)
    _fails(capsys, ["generate", "--robot", "ur5", "--excitation", str(bad), "--samples", "100000",
                    "--out", str(out)], out)


def test_the_information_gradient_matches_finite_differences():
    """log_information's gradient (through the regressor's vector-Jacobian product) against
    central differences of its value, at random UR5 states."""
    regressor = AtomRegressor(Arm.of("ur5").library)
    rng = np.random.default_rng(8)
    q, qd, qdd = (rng.normal(size=(40, 6)) for _ in range(3))
    _, grads = log_information(regressor, q, qd, qdd, gradient=True)
    step = 1e-6
    for which, grad in enumerate(grads):
        for i, j in ((0, 0), (7, 3), (39, 5)):
            states = [q.copy(), qd.copy(), qdd.copy()]
            states[which][i, j] += step
            up = log_information(regressor, *states)
            states[which][i, j] -= 2 * step
            down = log_information(regressor, *states)
            assert grad[i, j] == pytest.approx((up - down) / (2 * step), rel=1e-4, abs=1e-7)


def test_an_information_design_holds_more_information_than_a_condition_design():
    """excite --criterion information: the log det of its Gram beats the condition design's,
    both within the limits and at rest at both ends."""
    regressor = AtomRegressor(Arm.of("lynxmotion").library)
    grid = np.linspace(0.0, 6.0, 120, endpoint=False)
    designs = {c: design_for(Arm.of("lynxmotion"), 6.0, 50.0, seed=0, iterations=20, criterion=c)
               for c in ("condition", "information")}
    info = {c: log_information(regressor, *d.design.excitation.evaluate(grid)) for c, d in designs.items()}
    assert info["information"] < info["condition"]
    for d in designs.values():
        assert d.limits.violation(d.trajectory.q, d.trajectory.qd, d.trajectory.qdd) <= 1e-9
        assert np.abs(d.trajectory.qd[[0, -1]]).max() < 1e-9
        assert not d.design.stuck and d.design.status is not None and d.design.message


def test_a_design_stuck_at_its_random_start_is_reported(capsys, tmp_path, monkeypatch):
    """SLSQP failing at once (its linesearch: no step from the start): the design is its
    random start, ExcitationDesign says so with SLSQP's status and message, and excite says
    so on stderr (#56 item 10: it was reported like any other design)."""
    from scipy.optimize import OptimizeResult

    from identification.excitation import descent

    def failed(fun, x0, **kwargs):
        return OptimizeResult(x=np.array(x0), nit=1, status=8, success=False,
                              message="Positive directional derivative for linesearch")

    monkeypatch.setattr(descent, "minimize", failed)
    stuck = design_for(Arm.of("lynxmotion"), 6.0, 50.0, seed=0, iterations=20).design
    assert stuck.stuck and stuck.status == 8 and "linesearch" in stuck.message
    assert stuck.condition == stuck.start_condition
    capsys.readouterr()
    assert main(["excite", "--robot", "lynxmotion", "--duration", "6", "--rate", "50",
                 "--iterations", "20", "--out", str(tmp_path / "t.csv")]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "random start" in line]
    assert len(notes) == 1 and "linesearch" in notes[0]


def test_a_design_stopped_at_its_iteration_limit_is_a_miss_not_an_optimum(capsys, tmp_path,
                                                                         monkeypatch):
    """SLSQP stopped by its iteration limit (exit status 9, 2 iterations here) is not a
    converged design: ExcitationDesign says so, excite says so on stderr, and the bench's
    excitation targets report the convergence target missed and the condition as not an
    optimum's (issue #68 item 5: the bench's design stopped at status 9 was reported as a
    design)."""

    from harness.identify import excitation

    short = design_for(Arm.of("lynxmotion"), 6.0, 50.0, seed=0, iterations=2)
    assert short.design.status == 9 and not short.design.converged
    assert "not converged" in short.design.convergence()
    assert main(["excite", "--robot", "lynxmotion", "--duration", "6", "--rate", "50",
                 "--iterations", "2", "--out", str(tmp_path / "t.csv")]) == 0
    assert "not converged" in capsys.readouterr().err
    monkeypatch.setattr(excitation, "design_for", lambda *a, **k: short)
    monkeypatch.setattr(excitation, "sines_motion", lambda *a: None)
    monkeypatch.setattr(excitation, "along_design", lambda *a: {
        "seed": a[-1], "errors": [0.01], "default_errors": [0.02], "median_ratio": 0.5,
        "same_sensor_errors": [0.01], "same_sensor_median_ratio": 0.5})
    targets, results = excitation.excitation_comparison(Arm.of("lynxmotion"), None, "prior",
                                                        None, True)
    converged = [t for t in targets if t.name == excitation.CONVERGED]
    assert len(converged) == 1 and converged[0].met is False
    assert targets[0].note == "not a converged optimum" and results["converged"] is False


def test_the_designed_excitation_is_scored_on_draws_no_setting_was_chosen_on():
    """The bench scores the design on fresh draws and a fresh judge motion: none of them is a
    seed its settings (top frequency, criterion) or the identification's were chosen on, nor
    one the bench's other identification figures use (#56 item 1)."""
    from harness.bench.identification import FRESH_SEED, LEVELS, NEXT_RUNS
    from harness.identify.excitation import FRESH_DRAWS, FRESH_JUDGE, QUICK_FRESH_DRAWS
    from harness.identify.excitation_criteria import JUDGE, SEEDS

    chosen_on = set(SEEDS) | {JUDGE} | set(range(1, 11)) | set(range(601, 623))
    used = chosen_on | {FRESH_SEED} | set(NEXT_RUNS) | {s for seeds in LEVELS.values() for s in seeds}
    fresh = set(FRESH_DRAWS) | {FRESH_JUDGE}
    assert set(QUICK_FRESH_DRAWS) <= set(FRESH_DRAWS) and len(FRESH_DRAWS) >= 10
    assert not fresh & used, sorted(fresh & used)



def _development_seeds() -> set[int]:
    """Seeds the excitation's or the identification's settings were chosen on, or that the
    bench's other identification figures draw."""
    from harness.bench.identification import FRESH_SEED, LEVELS, NEXT_RUNS
    from harness.identify.excitation_criteria import JUDGE, SEEDS

    return (set(SEEDS) | {JUDGE, FRESH_SEED} | set(NEXT_RUNS) | set(range(1, 11))
            | set(range(601, 623)) | {s for seeds in LEVELS.values() for s in seeds})


@pytest.mark.parametrize("quick", [True, False])
def test_the_excitation_target_scores_the_draws_and_judge_its_report_names(monkeypatch, quick):
    """The bench's excitation comparison (harness.identify.excitation), its design and each
    draw's scoring recorded instead of run: the draws scored and the judge motion they are
    scored on are the ones its targets and figures name, and none is a development seed."""
    import re
    from types import SimpleNamespace

    from harness.identify import excitation

    judges, scored = {}, []

    def sines(arm, samples, seed):
        judges[seed] = SimpleNamespace(name="sines", seed=seed)
        return judges[seed]

    def along(arm, designed, fit, name, baseline, judge, seed):
        scored.append((seed, judge))
        return {"seed": seed, "errors": [0.01], "default_errors": [0.02], "median_ratio": 0.5,
                "same_sensor_errors": [0.01], "same_sensor_median_ratio": 0.5}

    design = SimpleNamespace(iterations=1, status=0, message="", stuck=False, converged=True,
                             convergence=lambda: "converged")
    monkeypatch.setattr(excitation, "design_for", lambda *a, **k: SimpleNamespace(
        trajectory=None, condition=1.0, default_condition=2.0, design=design))
    monkeypatch.setattr(excitation, "sines_motion", sines)
    monkeypatch.setattr(excitation, "along_design", along)
    targets, results = excitation.excitation_comparison(Arm.of("lynxmotion"), None, "prior",
                                                        None, quick)
    seeds = [seed for seed, _ in scored]
    assert seeds and len(set(seeds)) == len(seeds)
    assert [d["seed"] for d in results["draws"]] == seeds
    judge = results["judge_seed"]
    assert all(motion is judges[judge] for _, motion in scored)
    named = [t for t in targets if "fresh draws" in t.name]
    assert len(named) == 2
    for target in named:
        listed = re.search(r"seeds ([\d, ]+), judge motion seed (\d+)", target.name)
        assert [int(s) for s in listed.group(1).split(", ")] == seeds
        assert int(listed.group(2)) == judge
    assert not (set(seeds) | {judge}) & _development_seeds()

def test_a_long_design_says_how_far_it_is_and_the_same_design_comes_out(tmp_path, capsys,
                                                                       monkeypatch):
    """The design's progress reaches its caller at every optimizer iteration, up to the
    iterations the design reports, without changing the design; `excite` turns it into a line
    on stderr at most every Progress.EVERY_S seconds (a UR10 at 20 s designed ten minutes in
    silence)."""
    from harness.commands import excite

    seen = []
    arm = Arm.of("lynxmotion")
    with_progress = design_for(arm, 6.0, 50.0, seed=0, iterations=20,
                               progress=lambda i, n: seen.append((i, n)))
    without = design_for(arm, 6.0, 50.0, seed=0, iterations=20)
    np.testing.assert_array_equal(with_progress.trajectory.q, without.trajectory.q)
    counts = [i for i, _ in seen]
    assert counts == sorted(counts) and counts[0] == 1 and {n for _, n in seen} == {20}
    assert max(counts) == with_progress.design.iterations >= 2
    monkeypatch.setattr(excite.Progress, "EVERY_S", 0.0)
    capsys.readouterr()
    assert main(["excite", "--robot", "lynxmotion", "--duration", "6", "--rate", "50",
                 "--iterations", "5", "--out", str(tmp_path / "t.csv")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines()
             if line.startswith("excite: designing")]
    assert lines and "of at most 5" in lines[-1]
