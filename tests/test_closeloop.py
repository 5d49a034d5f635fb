"""Closing the loop on measured MuJoCo data (issue #6 acceptance)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from harness.cli import main
from harness.closeloop.acceptance import absorbed_joints, checks, coefficient_errors, meets_noise_bar
from harness.closeloop.plant import run_closeloop
from harness.closeloop.plants import DECLARED_MJCF, Variant, write_variant
from harness.robots.arm import Arm
from identification.closeloop.candidates.effects import Effect
from identification.closeloop.closed.extended import ExtendedModel
from identification.closeloop.selection.bic import refit
from identification.closeloop.selection.plant import projected_dictionary
from identification.closeloop.selection.residual import noise_sigma
from identification.metrics import rel_error

COUPLED = DECLARED_MJCF.parent / "lynxmotion_coupled.xml"

# Default run: the hardest joint effect (dry friction on the light joint 3: a wide linear
# zone) and the coupled one; every effect on every joint is in the slow tests.
SINGLE = [
    Variant((("coulomb", 3, 0.05),), name="coulomb3"),
    Variant(payload=0.1, name="payload"),
]

EVERY_JOINT = [Variant(((e, j, v),), name=f"{e}{j}") for e, v in
               (("viscous", 0.02), ("coulomb", 0.05), ("armature", 0.01), ("spring", 0.2))
               for j in (1, 2, 3)]


def _loop(plant, **options):
    """The loop on the plant file, a variant of the Lynxmotion."""
    return run_closeloop(Arm.of(plant), Arm.of("lynxmotion"), **options)


def _assert_accepted(loop):
    ok = checks(loop)
    assert all(ok.values()), (ok, coefficient_errors(loop), loop.to_json()["effects"])


@pytest.mark.parametrize("variant", SINGLE, ids=lambda v: v.name)
def test_single_effect_named_on_its_joint(tmp_path, variant):
    loop = _loop(write_variant(variant, tmp_path))
    assert not loop.result.unexplained
    assert [(t.effect, t.joint) for t in loop.result.terms] == [
        (t.effect, t.joint) for t in loop.truth]
    _assert_accepted(loop)


def test_control_plant_names_nothing():
    loop = _loop(DECLARED_MJCF)
    assert loop.result.terms == ()
    assert loop.result.unexplained is False


def test_effect_outside_dictionary_is_unexplained():
    loop = _loop(COUPLED)
    assert loop.outside_dictionary
    assert loop.result.unexplained is True
    assert loop.result.terms == ()


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2, 3])
def test_tendon_names_no_stand_ins_and_is_never_worse(seed):
    """The tendon q2 + q3 is outside the dictionary: BIC's stand-ins (springs, offsets,
    armatures, a payload) are screened out as candidates with a reason, and no joint's
    held-out error gets worse (seed 2 joint 1 went 0.0014 -> 0.119, seed 3 joint 3
    0.64 -> 1.05 when they were named)."""
    loop = _loop(COUPLED, seed=seed, compare=True)
    for run in (loop, *loop.others):
        r = run.result
        assert r.unexplained is True, run.declared
        assert r.terms == (), (run.declared, r.terms)
        assert np.all(r.error_after <= r.error_before), (run.declared, r.error_before,
                                                         r.error_after)
        assert all(c.reason for c in r.candidates)
    assert loop.result.candidates  # pinocchio: BIC did propose stand-ins
    report = loop.to_json()
    assert report["candidates"] and {"effect", "joint", "reason"} <= report["candidates"][0].keys()


def test_tendon_with_an_effect_in_the_dictionary_names_that_effect(tmp_path):
    """Viscous friction on joint 1 beside the tendon: named, at the plant's value, and the
    tendon's structure still reported as unexplained."""
    v = Variant((("viscous", 1, 0.02),), coupling=0.3, name="viscous1_tendon")
    loop = _loop(write_variant(v, tmp_path), samples=3000)
    r = loop.result
    assert [(t.effect, t.joint) for t in r.terms] == [("viscous", 1)]
    assert r.terms[0].coefficient == pytest.approx(0.02, rel=0.1)
    assert r.unexplained is True
    assert r.error_after[0] * 5 <= r.error_before[0]
    assert np.all(r.error_after <= r.error_before)


def _clean_error(loop, terms):
    r, d = loop.result, loop.data
    held = slice(r.split, None)
    model = ExtendedModel(r.model.declared, terms, r.model._payload)
    return rel_error(model.torque(d.q[held], d.qd[held], d.qdd[held]), d.tau_clean[held])


def test_noise_bar_fails_for_a_missing_or_wrong_effect():
    """The bar (error against the clean torque within 1.5x of the noise floor: the true effect
    set refitted) holds for the named effects and fails when one is missing or wrong."""
    loop = _loop(DECLARED_MJCF.parent / "lynxmotion_friction.xml", samples=3000)
    r, d = loop.result, loop.data
    truth = loop.noise_floor
    assert checks(loop)["noise_bar"]
    assert not meets_noise_bar(r.error_before, truth)  # the declared model alone
    missing = replace(loop, result=replace(r, error_after=r.error_before))
    assert checks(missing)["noise_bar"] is False
    tr = slice(0, r.split)
    residual = d.tau[tr] - r.model.declared.torque(d.q[tr], d.qd[tr], d.qdd[tr])
    dictionary = projected_dictionary(d.q[tr], d.qd[tr], d.qdd[tr], r.model._payload)
    for chosen in ([Effect("viscous", 2), Effect("viscous", 3)],  # viscous j1 missing
                   [Effect("coulomb", 1), Effect("coulomb", 2), Effect("viscous", 3)]):  # wrong
        terms = refit(residual, dictionary, noise_sigma(residual), chosen)
        error = _clean_error(loop, terms)
        assert error[0] > 1.5 * truth[0], (chosen, error / truth)
        assert not meets_noise_bar(error, truth)


def test_cli_writes_contract(tmp_path):
    out = tmp_path / "cl"
    rc = main(["closeloop", "--plant", str(DECLARED_MJCF.parent / "lynxmotion_friction.xml"),
               "--out", str(out), "--samples", "3000"])
    assert rc == 0
    report = json.loads((out / "closeloop.json").read_text())
    assert {"effects", "error_before", "error_after", "unexplained"} <= report.keys()
    named = {(e["effect"], e["joint"]): e["coefficient"] for e in report["effects"]}
    assert set(named) == {("viscous", 1), ("coulomb", 2), ("viscous", 3)}
    assert named[("coulomb", 2)] == pytest.approx(0.05, rel=0.1)
    assert report["unexplained"] is False
    assert len(report["error_before"]) == len(report["error_after"]) == 3
    for key in ("error_before_measured", "error_after_measured", "truth_error_measured"):
        assert len(report[key]) == 3
    assert report["candidates"] == [] and report["fallback_joints"] == []


TWO_JOINTS = ('<mujoco><worldbody><body><joint type="hinge"/><geom size="0.1"/><body>'
              '<joint type="hinge"/><geom size="0.1"/></body></body></worldbody></mujoco>')
TWO_NAMED = ('<mujoco><worldbody><body name="upper"><joint name="a" axis="0 1 0"/>'
             '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>'
             '<body name="lower" pos="0.3 0 0"><joint name="b" axis="0 1 0"/>'
             '<geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02"/></body></body>'
             '</worldbody></mujoco>')
FREE_BODY = '<mujoco><worldbody><body><freejoint/><geom size="0.1"/></body></worldbody></mujoco>'
OTHER_ARM = DECLARED_MJCF.read_text().replace('axis="0 -1 0" range="-3.14', 'axis="0 0 1" range="-3.14')


@pytest.mark.parametrize("text,robot,message", [
    (None, None, "plant file not found"),
    ("<mujoco><worldbody><body>", None, "invalid MJCF"),
    ("", None, "invalid MJCF"),
    (TWO_JOINTS, "lynxmotion", "has 2 joints; the declared lynxmotion model has 3"),
    (FREE_BODY, None, "needs 1-DOF joints only"),
    (OTHER_ARM, "lynxmotion", "joint 3 differs from lynxmotion's"),
], ids=["missing", "malformed", "empty", "wrong-dof", "free-joint", "other-arm"])
def test_cli_bad_plant_is_one_line_and_no_output(tmp_path, capsys, text, robot, message):
    plant = tmp_path / "plant.xml"
    if text is not None:
        plant.write_text(text)
    out = tmp_path / "o"
    rc = main(["closeloop", "--plant", str(plant), "--out", str(out),
               *(["--robot", robot] if robot else [])])
    assert rc == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and message in err[0], captured.err
    assert "Traceback" not in captured.err
    assert not (out / "closeloop.json").exists()


def test_cli_plant_of_another_arm_closes_the_loop_on_that_arm(tmp_path, capsys):
    """A UR5 plant without --robot: the loop runs on the UR5 it is a variant of (its six
    joints, its nominal model), not on the default Lynxmotion; with --robot another arm's
    plant is refused in one line."""
    from harness.closeloop.arm_plants import write_arm_variant

    plant = write_arm_variant(Arm.of("ur5"), Variant((("viscous", 2, 0.8),), name="viscous2"),
                              tmp_path)
    for robot in ("lynxmotion", "panda"):
        assert main(["closeloop", "--plant", str(plant), "--robot", robot,
                     "--out", str(tmp_path / robot)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "not a variant of this robot" in err[0], err
    out = tmp_path / "cl"
    assert main(["closeloop", "--plant", str(plant), "--out", str(out), "--samples", "2000"]) == 0
    report = json.loads((out / "closeloop.json").read_text())
    assert len(report["error_before"]) == 6 and set(report["declared_models"]) == {"pinocchio"}
    assert {(e["effect"], e["joint"]) for e in report["plant_effects"]} == {("viscous", 2)}
    assert ("viscous", 2) in {(e["effect"], e["joint"]) for e in report["effects"]}


def test_cli_plant_of_no_registered_arm_is_its_own_arm(tmp_path, capsys):
    """A 2-joint MJCF of no registered robot's kinematics, without --robot: the loop runs on
    the plant itself (its own file the declared model: nothing to name), not on the
    Lynxmotion, whose 3 joints it does not have."""
    plant = tmp_path / "two.xml"
    plant.write_text(TWO_NAMED)
    out = tmp_path / "cl"
    assert main(["closeloop", "--plant", str(plant), "--out", str(out), "--samples", "1000"]) == 0
    report = json.loads((out / "closeloop.json").read_text())
    assert len(report["error_before"]) == 2 and report["plant_effects"] == []


@pytest.mark.slow
def test_identified_declared_model_refits_jointly():
    """Declared = the sparse model identified on the same training data: the friction plant's
    effects are named at the plant's values (not split with the model's own terms), and the
    Pinocchio numbers are reported beside them."""
    loop = _loop(DECLARED_MJCF.parent / "lynxmotion_friction.xml", samples=3000,
                         declared="identified", compare=True)
    _assert_accepted(loop)
    report = loop.to_json()
    assert set(report["declared_models"]) == {"pinocchio", "identified"}
    assert report["declared_models"]["identified"]["error_after"] == report["error_after"]
    pin = loop.others[0]
    assert pin.declared == "pinocchio"
    _assert_accepted(pin)


@pytest.mark.slow
@pytest.mark.parametrize("variant", EVERY_JOINT, ids=lambda v: v.name)
def test_every_effect_on_every_joint(tmp_path, variant):
    _assert_accepted(_loop(write_variant(variant, tmp_path)))


@pytest.mark.slow
def test_identified_model_carries_what_its_terms_span():
    """Payload and armature lie in the identified model's span: absorbed, not named; the
    spring it cannot span is named on joint 3."""
    loop = _loop(DECLARED_MJCF.parent / "lynxmotion_payload.xml", declared="identified")
    assert set(loop.absorbed) == {"payload", "armature@3"}
    assert [(t.effect, t.joint) for t in loop.result.terms] == [("spring", 3)]
    assert absorbed_joints(loop) == [0, 1]  # reported and checked, not dropped
    assert "absorbed_not_worse" in checks(loop)
    _assert_accepted(loop)


@pytest.mark.slow
def test_combination_of_five_effects(tmp_path):
    v = Variant((("viscous", 1, 0.01), ("coulomb", 2, 0.05), ("armature", 3, 0.005),
                 ("spring", 3, 0.1)), payload=0.05, name="combo")
    _assert_accepted(_loop(write_variant(v, tmp_path)))


COMBOS = [
    Variant((("coulomb", 3, 0.05), ("viscous", 3, 0.02)), name="coulomb3_viscous3"),
    Variant((("coulomb", 1, 0.05), ("coulomb", 2, 0.05), ("coulomb", 3, 0.05)), name="coulomb123"),
]


@pytest.mark.slow
@pytest.mark.parametrize("declared", ["pinocchio", "identified"])
@pytest.mark.parametrize("variant", COMBOS, ids=lambda v: v.name)
def test_friction_combinations_both_declared_models(tmp_path, request, variant, declared):
    """Dry friction's linear zone looks viscous on joint 3; a sparse model fitted on friction
    data may drop rigid-body terms (re-identified without the named effects)."""
    if (variant.name, declared) == ("coulomb3_viscous3", "identified"):
        # Measured when the noise bar moved to the clean torque (issue #16): both effects are
        # named within 3 %, but joint 2 falls back to the identified model fitted on the
        # friction data (its shared atoms biased by joint 3's friction): 0.51 % against a
        # 0.20 % noise floor (2.6x > 1.5x). Against the measured torque the old bar read 1.004.
        request.applymarker(pytest.mark.xfail(strict=True, reason="joint 2 at 2.6x the noise "
                                              "floor after falling back to the biased model"))
    _assert_accepted(_loop(write_variant(variant, tmp_path), declared=declared))
