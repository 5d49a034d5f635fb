"""Any serial arm through the CLI: generate -> identify -> predict on the UR5 and the Panda
with the library generated from their kinematics; noise-free data identified exactly, the
model's CasADi form equal to its numeric form, and a model used with another robot or data
of another robot refused with one line."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

from harness.cli import main
from harness.robots.arm import Arm
from harness.robots.torque_models import load_torque_model


@pytest.fixture(scope="module", params=["ur5", "panda"])
def noise_free(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    data, model = folder / "data.npz", folder / "MODEL.json"
    assert main(["generate", "--robot", request.param, "--samples", "1200", "--noise", "0",
                 "--out", str(data)]) == 0
    assert main(["identify", "--data", str(data), "--out", str(model)]) == 0
    return request.param, data, model


def test_noise_free_data_are_identified_exactly(noise_free):
    robot, _, model = noise_free
    payload = json.loads(model.read_text())
    assert payload["library"] == "kinematic" and payload["robot"]["name"] == robot
    assert max(payload["metrics"]["heldout_rel_rmse"]) <= 1e-6
    assert payload["atoms"] == Arm.of(robot).library.names
    for joint in payload["joints"]:  # the contract: terms and coefficients per joint
        assert len(joint["terms"]) == len(joint["coefficients"]) > 0


def test_predict_equals_the_clean_torque_and_the_symbolic_form(noise_free, tmp_path):
    robot, data, model = noise_free
    out = tmp_path / "pred.npz"
    assert main(["predict", "--model", str(model), "--data", str(data), "--out", str(out)]) == 0
    arrays = np.load(data)
    tau = np.load(out)["tau"]
    assert np.linalg.norm(tau - arrays["tau_clean"]) <= 1e-6 * np.linalg.norm(arrays["tau_clean"])
    m = load_torque_model(str(model), Arm.of(robot))
    q, qd, qdd = (ca.SX.sym(s, m.dof) for s in ("q", "qd", "qdd"))
    f = ca.Function("f", [q, qd, qdd], [m.symbolic_torque(q, qd, qdd)])
    for k in (0, 500, 1100):
        x = (arrays["q"][k], arrays["qd"][k], arrays["qdd"][k])
        assert np.allclose(np.asarray(f(*x)).ravel(), tau[k], rtol=1e-10, atol=1e-10)


def test_a_model_of_another_robot_is_one_line_and_no_file(noise_free, tmp_path, capsys):
    robot, data, model = noise_free
    other = "panda" if robot == "ur5" else "ur5"
    out = tmp_path / "pred.npz"
    assert main(["predict", "--model", str(model), "--data", str(data), "--robot", other,
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"identified for robot '{robot}'" in err[0] and not out.exists()


def test_data_of_another_robot_or_dof_are_one_line(noise_free, tmp_path, capsys):
    """Data recording their robot name it; data recording none, their joint count."""
    robot, data, _ = noise_free
    out = tmp_path / "MODEL.json"
    assert main(["identify", "--data", str(data), "--robot", "double_pendulum",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"records robot '{robot}'" in err[0] and not out.exists()
    assert "'double_pendulum'" in err[0]
    anonymous = tmp_path / "anonymous.npz"
    with np.load(data) as d:
        np.savez(anonymous, **{k: d[k] for k in ("q", "qd", "qdd", "tau")})
    assert main(["identify", "--data", str(anonymous), "--robot", "double_pendulum",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "robot double_pendulum has 2" in err[0] and not out.exists()


@pytest.mark.slow
def test_identification_section_scores_the_generated_library_against_the_oracle(tmp_path):
    """The bench's identification section on the UR5 (quick: 2 draws): noise-free data
    identified exactly, and per draw the generated library's error against the oracle's on
    both judge motions, the summary computed from those numbers."""
    from harness.bench import identification as section
    from harness.report.results import Context

    out = section.run(Context(Arm.of("ur5"), tmp_path, quick=True))
    r = out.results
    assert all(c.passed for c in out.checks) and max(r["noise_free_heldout"]) <= 1e-6
    draws = r["draws"]["0.05"]
    assert r["closed_form_gap"] <= 1e-9 and len(draws) == len(section.QUICK_LEVELS[0.05])
    for draw in draws:
        for judge in ("fresh", "sines"):
            assert len(draw["kinematic"][judge]) == len(draw["oracle"][judge]) == 6
            assert all(0 < e < 0.05 for e in draw["kinematic"][judge] + draw["oracle"][judge])
    ratios = np.array([np.array(d["kinematic"]["sines"]) / np.array(d["oracle"]["sines"])
                       for d in draws])
    summary = r["summary"]["0.05"]["kinematic"]["sines"]
    assert np.isclose(summary["worst_joint"], ratios.max())
    assert np.isclose(summary["worst_median"], np.median(ratios, axis=1).max())
    assert out.targets[0].measured == summary["worst_median"] and "ur5" in out.markdown


@pytest.mark.slow
def test_closing_the_loop_on_the_ur5_names_every_effect_within_10_percent(tmp_path):
    """A UR5 plant with viscous, Coulomb, armature, spring and a flange payload the declared
    Pinocchio model lacks: each is named on its joint with its coefficient within 10 %, nothing
    else is named, and no joint is worse after; the control plant names nothing; a tendon
    spring (outside the dictionary) is said unexplained."""
    from harness.bench import closeloop as section
    from harness.report.results import Context

    result = section.run(Context(Arm.of("ur5"), tmp_path))
    out = {"results": result.results}
    assert all(c.passed for c in result.checks)
    # the payload cases' three each included: the UR5 and the UR5 with its wrist's load friction
    assert [t.met for t in result.targets if "push" not in t.name] == [True] * 9
    assert sum("push" in t.name for t in result.targets) == 5  # the push case's, reported
    payload = out["results"]["payload"]  # a load no model declares, named by the measured loop
    assert payload["named"] and payload["mass_error"] < 0.03 and payload["com_error_m"] < 0.01
    effects = out["results"]["plants"]["effects"]
    assert {(e["effect"], e["joint"]) for e in effects["effects"]} == {
        ("viscous", 2), ("coulomb", 3), ("armature", 1), ("spring", 4), ("payload", 6)}
    assert all(effects["acceptance"].values()), effects
    for e in effects["effects"]:
        assert abs(e["named"] - e["true"]) <= 0.10 * abs(e["true"])
        # the same fit on the clean torque: little bias from the estimated states (within 2 %:
        # 1.15 % on joint 3's Coulomb term on the bench's fresh draw, seed 4548, where seed 0,
        # the one the loop was developed on, kept every term within 1 %), and the named
        # coefficient's miss is the noise's (a few of its standard errors)
        assert abs(e["refit_clean"] - e["true"]) <= 0.02 * abs(e["true"])
        assert 0 < e["stderr"] < 0.1 * abs(e["true"]) and abs(e["z"]) < 4
    control = out["results"]["plants"]["control"]
    assert control["effects"] == [] and control["spurious"] == []
    assert not control["unexplained"] and not effects["unexplained"]
    # a tendon spring q2 + q3 is outside the dictionary: said unexplained, nothing named
    coupled = out["results"]["plants"]["coupled"]
    assert coupled["outside_dictionary"] and coupled["unexplained"] and coupled["spurious"] == []
    assert all(coupled["acceptance"].values()) and all(control["acceptance"].values())
    assert (tmp_path / "plants" / "ur5_effects.xml").is_file()


def test_plant_of_another_arm_is_one_line(tmp_path, capsys):
    from harness.closeloop.arm_plants import write_arm_variant
    from harness.closeloop.plants import Variant

    plant = write_arm_variant(Arm.of("ur5"), Variant(name="control"), tmp_path)
    out = tmp_path / "cl"
    assert main(["closeloop", "--plant", str(plant), "--robot", "panda", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a variant" in err[0] and not out.exists()


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_a_plant_written_without_effects_carries_none(tmp_path, robot):
    """The plants are written by MjSpec.to_xml, which keeps 6 significant digits: masses
    rounded alike must not read as a payload (the Panda's control plant did: 6e-6 kg)."""
    from harness.closeloop.arm_plants import write_arm_variant
    from harness.closeloop.plant import effects_reference
    from harness.closeloop.plants import Variant, true_effects

    arm = Arm.of(robot)
    plant = Arm.of(write_arm_variant(arm, Variant(name="control"), tmp_path))
    assert true_effects(plant.mujoco, effects_reference(arm)) == ((), False)
    loaded = Arm.of(write_arm_variant(arm, Variant(payload=0.5, name="p"), tmp_path))
    (payload,), _ = true_effects(loaded.mujoco, effects_reference(arm))
    assert payload.effect == "payload" and payload.coefficient == pytest.approx(0.5, abs=1e-12)
