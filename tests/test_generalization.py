"""Issue #42: the consistent fit on data the project's excitation did not make (another
spectrum, a perturbed URDF prior) predicts a fresh motion within the bench's bars of the
oracle; a Coulomb coefficient fitted to noise on a joint without friction made it 3.7x."""

from __future__ import annotations

import numpy as np
import pytest

from harness.identify.generalization import FLAT, PRIOR, generalization
from harness.robots.arm import Arm
from harness.studies.generalization import JOINT_TARGET, MEDIAN_TARGET


@pytest.mark.slow
def test_consistent_fit_generalizes_from_another_excitation():
    result = generalization(Arm.of("ur5"), (701,))
    for fit in (PRIOR, FLAT):
        fresh = result["summary"][fit]["fresh"]
        assert fresh["worst_median"] <= MEDIAN_TARGET, (fit, fresh)
        assert fresh["worst_joint"] <= JOINT_TARGET, (fit, fresh)


def test_the_no_prior_fit_says_its_bounds_hold_the_urdfs_bodies():
    """`--prior flat` keeps each body inside its link's ellipsoid, grown to hold the URDF's
    body: where the URDF generated the data (the bench, this study) that bound holds the
    truth, and the fit's name says so (#56 item 7). On the UR5 the growth is real: its wrist
    bodies lie outside their meshes' ellipsoids."""
    from identification.ellipsoids import MARGIN, inside
    from identification.physical import pseudo_inertia

    arm = Arm.of("ur5")
    model = arm.pinocchio
    grown = [e for e in arm.ellipsoids if "grown" in e.source]
    assert len(grown) >= 3 and "the URDF's body" in grown[0].source
    for joint, ellipsoid in enumerate(arm.ellipsoids, start=1):
        body = np.array(pseudo_inertia(model.inertias[joint].toDynamicParameters()))
        assert inside(body, ellipsoid) >= MARGIN * model.inertias[joint].mass * (1 - 1e-9)
    assert "grown to hold the URDF's bodies" in FLAT


@pytest.mark.slow
def test_one_sensor_noise_on_every_joint_weighs_each_joint_by_its_noise():
    """Issue #57: with the same N m of sensor noise on every joint the consistent fit weighed
    each joint's residual by its torque std, so the wrist's noisy rows pulled the bodies the
    loaded joints see: on the Panda (seed 5701, where it was found) joint 5 at 3.0x the oracle
    on a fresh motion, 0.98x with each joint weighed by its noise (joint_weights)."""
    from harness.identify.generalization import JUDGE_SEED, outside_dataset
    from harness.identify.scoring import SAMPLES, generated_motion, perturbed_prior_fit, score_draw

    arm = Arm.of("panda")
    fit = perturbed_prior_fit(arm.library, arm.nominal, arm.ellipsoids)
    draw = score_draw(outside_dataset(arm, 5701, noise_model="sensor"), {PRIOR: fit}, arm.nominal,
                      [generated_motion(arm, SAMPLES, JUDGE_SEED)])
    ratio = np.array(draw[PRIOR]["fresh"]) / np.array(draw["oracle"]["fresh"])
    assert np.median(ratio) <= MEDIAN_TARGET and ratio.max() <= JOINT_TARGET, np.round(ratio, 2).tolist()


def test_joint_weights_follow_the_noise_not_the_torque():
    """Joints of torques 100 times apart with the same noise weigh alike; with noise in
    proportion to their torque, as their torque std (the ridge weights keep their scale)."""
    from identification.physical import joint_weights

    rng = np.random.default_rng(3)
    atoms = rng.normal(size=(2000, 2, 4)) * np.array([[100.0], [1.0]])[None]
    clean = atoms @ np.ones(4)
    same = joint_weights(atoms, clean + 0.5 * rng.normal(size=clean.shape))
    assert same[0] / same[1] == pytest.approx(1.0, rel=0.1)
    tau = clean + 0.05 * clean.std(0) * rng.normal(size=clean.shape)
    np.testing.assert_allclose(joint_weights(atoms, tau), tau.std(0), rtol=0.05)
