"""mujoco.sysid as the study's peer (harness.studies.sysid_peer): its pseudo-inertia parameters
written around the toolbox's defect give Pinocchio's rigid-body torque; its windows line up
with a log MuJoCo made (the truth's residual is nil, a perturbed model's is not); the budget
stops its optimizer and keeps the best point; the bias's sign in the scoring is the motor's;
the study's quick form runs."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from harness.cli import main
from harness.identify.rollout_fit import Budget, BudgetedResidual, Windows, model_sequences
from harness.identify.rollout_model import (
    peer_parameters,
    peer_spec,
    toolbox,
    write_pseudo_inertia,
)
from harness.robots.arm import Arm
from harness.studies.sysid_peer.scoring import score_mujoco

sysid = toolbox()


def _random_pseudo_inertia(rng) -> np.ndarray:
    """A physically consistent body: J = L L^T + a little, its mass about 1 kg."""
    low = np.tril(rng.normal(scale=0.1, size=(4, 4)))
    low[3, 3] = 1.0 + rng.uniform()
    return low @ low.T + 1e-4 * np.eye(4)


def _standard_of_pseudo(j: np.ndarray) -> np.ndarray:
    """Wensing's relation, written here independently: m = J33, h = J[:3, 3], the inertia
    about the origin tr(Sigma) 1 - Sigma; Pinocchio's order m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz."""
    sigma = j[:3, :3]
    inertia = np.trace(sigma) * np.eye(3) - sigma
    return np.r_[j[3, 3], j[:3, 3], inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2],
                 inertia[1, 2], inertia[2, 2]]


def test_pseudo_inertia_writer_gives_pinocchio_torque():
    from mujoco.sysid._src.model_modifier import theta_from_pseudoinertia

    arm, rng = Arm.of("panda"), np.random.default_rng(4)
    start = arm.nominal.atom_parameters()
    spec = peer_spec(arm, start)
    model = spec.compile()
    params = peer_parameters(spec, model)
    standard = []
    for j in range(arm.dof):
        body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.jnt_bodyid[j])
        pseudo = _random_pseudo_inertia(rng)
        params[f"{body}_inertia"].value = theta_from_pseudoinertia(pseudo)
        write_pseudo_inertia(body)(spec, params[f"{body}_inertia"])
        standard.append(_standard_of_pseudo(pseudo))
    written = spec.compile()
    lo, hi = written.jnt_range.T
    q = lo + (hi - lo) * rng.uniform(0.2, 0.8, size=(5, arm.dof))
    qd, qdd = rng.normal(size=(2, 5, arm.dof))
    expected = np.einsum("nij,j->ni", arm.nominal.regressor(q, qd, qdd), np.concatenate(standard))
    data = mujoco.MjData(written)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(written, data)
        passive = written.dof_damping * qd[k]  # the spec's damping; armature 0, no friction
        # atol: the file's 6-digit joint frames against Pinocchio's URDF (1.6e-8 N m seen)
        np.testing.assert_allclose(data.qfrc_inverse - passive, expected[k], atol=1e-6)


def test_toolbox_pseudo_inertia_writer_still_refused():
    """The defect worked around: MuJoCo 4.0.1 refuses the toolbox's own writer (when this
    fails, the toolbox's writer may be used again)."""
    arm = Arm.of("panda")
    spec = peer_spec(arm, arm.nominal.atom_parameters())
    param = sysid.body_inertia_param(spec, spec.compile(), "panda_link3",
                                     sysid.InertiaType.Pseudo)
    param.apply_modifier(spec)
    with pytest.raises(ValueError, match="mass and inertia"):
        spec.compile()


def _made_log(arm: Arm, truth: np.ndarray, bias: np.ndarray, n: int = 101):
    """A log plain MuJoCo makes with the peer's model at truth (its motors' bias set)."""
    model = peer_spec(arm, truth).compile()
    model.actuator_biasprm[:, 0] = bias
    return _stepped_log(model, n, bias)


def _stepped_log(model, n: int = 101, bias=0.0):
    """A log plain MuJoCo makes of model from the middle of its ranges: motors driven by a
    torque (less bias) linear between 100 Hz samples (the toolbox's interpolation), q and qd
    recorded."""
    data, dt = mujoco.MjData(model), 0.01
    lo, hi = model.jnt_range.T
    data.qpos[:] = (lo + hi) / 2
    t = np.arange(n) * dt
    tau = 0.3 * np.sin(2 * np.pi * np.outer(t, [0.7, 1.1, 1.7])) - bias
    sub = int(round(dt / model.opt.timestep))
    q, qd = np.empty((n, model.nv)), np.empty((n, model.nv))
    for i in range(n):
        q[i], qd[i] = data.qpos, data.qvel
        for s in range(sub):
            w = s / sub
            data.ctrl[:] = tau[i] if i == n - 1 else (1 - w) * tau[i] + w * tau[i + 1]
            mujoco.mj_step(model, data)
    return t, q, qd, tau


def test_windows_line_up_with_a_log_mujoco_made():
    arm = Arm.of("lynxmotion")
    truth = arm.nominal.atom_parameters().copy()
    truth[30:] = [2e-4, 1e-4, 5e-5, 0.01, 0.005, 0.004, 0.02, 0.01, 0.005]
    bias = np.array([0.03, -0.02, 0.01])
    t, q, qd, tau = _made_log(arm, truth, bias)
    spec = peer_spec(arm, truth)
    model = spec.compile()
    params = peer_parameters(spec, model)
    x = params.as_vector()
    for name in params.keys():  # back to the truth, off-bound moves undone
        if name.endswith(("armature", "damping", "frictionloss")):
            params[name].value = params[name].nominal.copy()
    for j, name in enumerate(("joint1", "joint2", "joint3")):
        params[f"{name}_bias"].value = np.array([bias[j]])
    x = params.as_vector()
    residual = sysid.build_residual_fn(
        models_sequences=[model_sequences(spec, model, t, q, qd, tau, [Windows(0, len(t), 50)])],
        n_threads=1)

    def cost(v):
        r = np.concatenate(residual(v, params)[0])
        return 0.5 * float(r @ r)
    off = x.copy()
    off[np.array([k.endswith("bias") for k in _names(params)])] = 0.0  # the sensor offset lost
    assert cost(x) < 1e-6 * cost(off)


def _names(params) -> list[str]:
    return [name for name, p in params.items() for _ in range(p.size)]


def test_budget_stops_and_keeps_the_best_point():
    calls = []

    def residual_fn(x, params):
        calls.append(x)
        return [np.atleast_1d(np.ravel(x) - 1.0)], None, None
    budget = BudgetedResidual(residual_fn, seconds=3600, clock=lambda: 0.0)
    budget(np.array([3.0]), None)
    budget(np.array([[2.0]]), None)  # a point as one column, as mujoco.minimize passes it
    budget(np.array([[0.0, 5.0]]), None)  # a Jacobian's columns: not points
    assert budget.best[0] == pytest.approx(0.5) and budget.best[1].tolist() == [2.0]
    assert budget.evaluations == 4
    budget.seconds = -1.0
    with pytest.raises(Budget):
        budget(np.array([1.0]), None)
    counted = BudgetedResidual(residual_fn, seconds=3600, rollouts=3, clock=lambda: 0.0)
    counted(np.array([1.0]), None)
    counted(np.array([[0.0, 5.0]]), None)  # 3 rollouts: at the limit
    with pytest.raises(Budget):
        counted(np.array([1.0]), None)


def test_scoring_applies_the_motor_bias():
    """A log made with a motor bias rolls out exactly with its bias added to the logged
    torque (the sign the scoring uses), not without it."""
    arm = Arm.of("lynxmotion")
    truth = arm.nominal.atom_parameters()
    bias = np.array([0.05, -0.04, 0.03])
    t, q, qd, tau = _made_log(arm, truth, bias, n=201)
    model = peer_spec(arm, truth).compile()
    model.actuator_biasprm[:, 0] = bias
    arrays = {"t": t, "q": q, "qd": qd, "qdd": np.gradient(qd, t, axis=0), "tau": tau}
    right = score_mujoco("m", model, bias, arrays, 0.5, truth, None)
    wrong = score_mujoco("m", model, np.zeros(3), arrays, 0.5, truth, None)
    q_right, q_wrong = (np.asarray(s.rollout[0]["q_rms"]) for s in (right, wrong))
    assert np.all(q_right < 1e-3 * q_wrong)


def test_study_quick(tmp_path):
    out = tmp_path / "s"
    assert main(["study", "sysid_peer", "--quick", "--no-video", "--out", str(out)]) == 0
    section = json.loads((out / "report.json").read_text())["sections"]["sysid_peer"]
    panda = section["results"]["panda"]
    assert [m["name"] for m in panda["models"]] == [
        "nominal", "identify (exported MJCF)", "mujoco.sysid", "identify --refine rollout"]
    for fit in (panda["peer"], panda["refined"]):
        assert fit["cost"] <= fit["cost_start"] and fit["parameters_fitted"] == 14 * 7
        assert fit["evaluations"] <= 110


def test_budget_refuses_a_call_that_would_end_past_it():
    now = [0.0]

    def slow(x, params):  # each column takes 1 s of the budget's clock
        now[0] += np.shape(np.atleast_2d(x))[1] if np.ndim(x) == 2 else 1.0
        return [np.ravel(x)], None, None
    budget = BudgetedResidual(slow, seconds=4.5, clock=lambda: now[0])
    budget(np.array([0.5]), None)  # the start: ends at 1 s
    budget(np.array([[1.0, 2.0]]), None)  # a Jacobian of 2 columns: ends at 3 s
    with pytest.raises(Budget):  # another would end at 5 s
        budget(np.array([[1.0, 2.0]]), None)
    budget(np.array([0.5]), None)  # a point: ends at 4 s
    with pytest.raises(Budget):
        budget(np.array([0.5]), None)
    first = BudgetedResidual(slow, seconds=2.5, clock=lambda: now[0])
    first(np.array([0.5]), None)  # 1 s: a Jacobian of 2 columns is expected to take 2 s more
    with pytest.raises(Budget):
        first(np.array([[1.0, 2.0]]), None)
    late = BudgetedResidual(slow, seconds=-1.0, clock=lambda: now[0])
    late(np.array([0.5]), None)  # the start is evaluated whatever the budget


def _file_log(path, n: int = 101):
    """A log plain MuJoCo makes of the MJCF at path: its motors' control (the torque the
    sensor reads) linear between 100 Hz samples, q and qd recorded."""
    return _stepped_log(mujoco.MjModel.from_xml_path(str(path)), n)


def test_refinement_starts_from_the_exported_file(tmp_path):
    """On a log plain MuJoCo made of the exported MJCF, the refinement's start (the same
    export, read back, driven by the toolbox) has a nil residual; without the sensor offset
    in its bias it does not; the refined file loads in plain MuJoCo."""
    from harness.identify.refine import refine_rollout
    from harness.robots.export import export_model

    arm = Arm.of("lynxmotion")
    truth = arm.nominal.atom_parameters().copy()
    truth[30:] = [2e-4, 1e-4, 5e-5, 0.01, 0.005, 0.004, 0.02, 0.01, 0.005]
    payload, offset = {"body_parameters": truth.tolist()}, np.array([0.03, -0.02, 0.01])
    export_model(payload, arm, "mjcf", tmp_path / "plant.xml", offset=offset)
    log = _file_log(tmp_path / "plant.xml")
    _, right = refine_rollout(payload, arm, *log, [(0, len(log[0]))], offset, 1e-9,
                              tmp_path / "refined.xml")
    _, wrong = refine_rollout(payload, arm, *log, [(0, len(log[0]))], 0 * offset, 1e-9)
    assert right["cost_start"] < 1e-6 * wrong["cost_start"]
    refined = mujoco.MjModel.from_xml_path(str(tmp_path / "refined.xml"))
    assert refined.nu == 3 and np.allclose(refined.body_mass, mujoco.MjModel.from_xml_path(
        str(tmp_path / "plant.xml")).body_mass, rtol=1e-6)


def _identify(tmp_path, *extra):
    data = tmp_path / "lx.npz"
    if not data.exists():
        assert main(["generate", "--robot", "lynxmotion", "--samples", "400", "--seed", "5",
                     "--out", str(data)]) == 0
    return main(["identify", "--data", str(data), "--out", str(tmp_path / "m.json"), *extra])


@pytest.mark.parametrize("extra, words", [
    (("--prior", "none", "--refine", "rollout"), "has none"),
    (("--prior", "nominal", "--refine", "rollout", "--refine-seconds", "0"), "must be positive"),
])
def test_refine_refused_in_one_line(tmp_path, capsys, extra, words):
    assert _identify(tmp_path, *extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert not (tmp_path / "m.json").exists() and not (tmp_path / "m.refined.xml").exists()


def test_a_plate_past_the_edge_by_rounding_compiles():
    """A body whose moments break A + B >= C by rounding (3e-16 kg m^2, as the Panda's link 3
    came out of one of the optimizer's steps) is written at the edge, not refused."""
    from harness.identify.rollout_model import write_inertia

    arm = Arm.of("panda")
    spec = peer_spec(arm, arm.nominal.atom_parameters())
    plate = np.zeros(10)  # m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz about the body's origin
    plate[0], plate[4], plate[6], plate[9] = 1.0, 0.067306, 0.30264923, 0.36995523 + 3.3e-16
    write_inertia(spec.body("panda_link3"), plate)
    model = spec.compile()
    a, b, c = np.sort(model.body_inertia[model.body("panda_link3").id])
    assert a + b >= c and c == pytest.approx(0.36995523, rel=1e-12)


def test_refine_writes_the_refined_mjcf_and_its_record(tmp_path, capsys):
    assert _identify(tmp_path, "--prior", "nominal", "--refine", "rollout",
                     "--refine-seconds", "1") == 0
    record = json.loads((tmp_path / "m.json").read_text())["refined"]
    assert record["mjcf"] == str(tmp_path / "m.refined.xml") and record["windows"] > 0
    assert record["cost"] <= record["cost_start"]
    refined = mujoco.MjModel.from_xml_path(record["mjcf"])  # plain MuJoCo reads it
    assert refined.nu == 3 and "refined by rollouts" in capsys.readouterr().out


def test_no_model_row_is_the_constant_velocity_closed_form():
    """Under a constant acceleration a, continuing each window at its first velocity misses
    q by a t^2 / 2 and qd by a t: the RMS over a window's samples in closed form."""
    from harness.studies.sysid_peer.scoring import WINDOWS, constant_velocity

    dt, a, v = 0.01, np.array([2.0, -0.5]), np.array([0.3, 1.0])
    t = np.arange(401) * dt
    arrays = {"t": t, "q": 0.5 * np.outer(t ** 2, a) + np.outer(t, v),
              "qd": np.outer(t, a) + v}
    for w in constant_velocity(arrays, 0.5):
        s = dt * np.arange(1, int(round(w["seconds"] / dt)) + 1)
        assert w["seconds"] in WINDOWS and w["diverged"] == 0
        np.testing.assert_allclose(w["q_rms"], np.abs(a) / 2 * np.sqrt(np.mean(s ** 4)),
                                   rtol=1e-9)
        np.testing.assert_allclose(w["qd_rms"], np.abs(a) * np.sqrt(np.mean(s ** 2)),
                                   rtol=1e-9)


def _stepped_rms(model, t, q, qd, tau, seconds: float) -> np.ndarray:
    """Per joint q RMS of plain MuJoCo stepping model with its own motors on (control: the
    logged torque, linear between samples) from the log's state at the start of each window
    tiling the log, over every sample of the windows."""
    step = t[1] - t[0]
    sub, samples = int(round(step / model.opt.timestep)), int(round(seconds / step))
    assert abs(sub * model.opt.timestep - step) < 1e-12
    data, errors = mujoco.MjData(model), []
    for k in range(0, len(t) - samples, samples):
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = q[k], qd[k]
        for i in range(k, k + samples):
            for s in range(sub):
                data.ctrl[:] = (1 - s / sub) * tau[i] + s / sub * tau[i + 1]
                mujoco.mj_step(model, data)
            errors.append(data.qpos - q[i + 1])
    return np.sqrt(np.mean(np.square(errors), axis=0))


def test_predict_rolls_out_the_refined_mjcf_as_plain_mujoco_steps_it(tmp_path):
    """MODEL.json of `identify --refine rollout` (moved with its MJCF to another folder):
    `predict --rollout` gives the figures of plain MuJoCo stepping the refined file, its own
    motors driven by the logged torque (their bias the refined sensor offset)."""
    assert _identify(tmp_path, "--prior", "nominal", "--refine", "rollout",
                     "--refine-seconds", "1") == 0
    moved = tmp_path / "moved"
    moved.mkdir()
    for name in ("m.json", "m.refined.xml"):
        (tmp_path / name).rename(moved / name)
    assert main(["predict", "--model", str(moved / "m.json"), "--data", str(tmp_path / "lx.npz"),
                 "--rollout", "0.1,0.25", "--out", str(tmp_path / "p.npz")]) == 0
    windows = json.loads((tmp_path / "p.rollout.json").read_text())["windows"]
    log = np.load(tmp_path / "lx.npz")
    model = mujoco.MjModel.from_xml_path(str(moved / "m.refined.xml"))
    assert np.any(model.actuator_biasprm[:, 0] != 0)
    for w in windows:
        expected = _stepped_rms(model, np.ravel(log["t"]), log["q"], log["qd"], log["tau"],
                                w["seconds"])
        np.testing.assert_allclose(w["q_rms"], expected, rtol=1e-6)


def test_predict_refuses_a_refined_mjcf_gone_in_one_line(tmp_path, capsys):
    assert _identify(tmp_path, "--prior", "nominal", "--refine", "rollout",
                     "--refine-seconds", "1") == 0
    (tmp_path / "m.refined.xml").unlink()
    capsys.readouterr()
    assert main(["predict", "--model", str(tmp_path / "m.json"), "--data",
                 str(tmp_path / "lx.npz"), "--rollout", "0.1", "--out",
                 str(tmp_path / "p.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "refined MJCF" in err[0] and "not found" in err[0]
    assert not (tmp_path / "p.npz").exists() and not (tmp_path / "p.rollout.json").exists()


def test_draws_judge_the_worst_draw_joint_by_joint():
    """Two plants: the refinement above the peer on no joint of the first and on joints 2 and
    3 of the second (a rollout), its torque above on joint 1 of the first: the targets read
    the worst draw's count, 2 and 1."""
    from harness.studies.sysid_peer.draws import draw_figures, draws_targets
    from harness.studies.sysid_peer.scoring import Scored

    def scored(torque, q):
        return Scored("m", np.array(torque), [{"seconds": 0.5, "q_rms": q}], None, None, None)
    still = [{"seconds": 0.5, "q_rms": [1.0, 1.0, 1.0]}]
    peer = scored([0.1, 0.1, 0.1], [0.2, 0.2, 0.2])
    draws = [draw_figures((1, 2), peer, peer, scored([0.2, 0.1, 0.05], [0.1, 0.2, 0.1]), still),
             draw_figures((3, 4), peer, peer, scored([0.1, 0.1, 0.1], [0.1, 0.3, 0.25]), still)]
    assert [d["joints_above_peer"]["refined_rollout"] for d in draws] == [0, 2]
    measured = {t.name.split("where ")[1]: t.measured for t in draws_targets(draws)}
    assert measured["identify --refine rollout's 0.5 s rollout q RMS is above mujoco.sysid's"] == 2
    assert measured["identify --refine rollout's held-out torque error is above "
                    "mujoco.sysid's"] == 1


def test_rollouts_repeat_bit_for_bit():
    """The toolbox's residual at a point, and a finite-difference Jacobian's columns, come out
    bit for bit the same on repeated calls across threads (what differs between runs of a fit
    is the optimizer's path, not the rollouts: docs/identification.md)."""
    arm = Arm.of("lynxmotion")
    truth = arm.nominal.atom_parameters().copy()
    truth[30:] = [2e-4, 1e-4, 5e-5, 0.01, 0.005, 0.004, 0.02, 0.01, 0.005]
    t, q, qd, tau = _made_log(arm, truth, np.array([0.03, -0.02, 0.01]), n=201)
    spec = peer_spec(arm, truth)
    model = spec.compile()
    params = peer_parameters(spec, model)
    residual = sysid.build_residual_fn(
        models_sequences=[model_sequences(spec, model, t, q, qd, tau, [Windows(0, len(t), 25)])],
        n_threads=2)
    x = params.as_vector()
    columns = np.tile(x[:, None], (1, 6)) + 1e-3 * np.eye(x.size, 6)

    def flat(v):
        return np.concatenate([np.ravel(r) for r in residual(v, params.copy())[0]])
    first, jacobian = flat(x), flat(columns)
    assert np.array_equal(flat(columns), jacobian) and np.array_equal(flat(x), first)
    assert not np.array_equal(flat(columns[:, ::-1]), jacobian)  # the columns do matter
