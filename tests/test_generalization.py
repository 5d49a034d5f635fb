"""Issue #42: the consistent fit on data the project's excitation did not make (another
spectrum, a perturbed URDF prior) predicts a fresh motion within the bench's bars of the
oracle; a Coulomb coefficient fitted to noise on a joint without friction made it 3.7x."""

from __future__ import annotations

from harness.identify.generalization import FLAT, PRIOR, generalization
from harness.robots.arm import Arm
from harness.studies.generalization import JOINT_TARGET, MEDIAN_TARGET


def test_consistent_fit_generalizes_from_another_excitation():
    result = generalization(Arm.of("ur5"), (701,))
    for fit in (PRIOR, FLAT):
        fresh = result["summary"][fit]["fresh"]
        assert fresh["worst_median"] <= MEDIAN_TARGET, (fit, fresh)
        assert fresh["worst_joint"] <= JOINT_TARGET, (fit, fresh)
