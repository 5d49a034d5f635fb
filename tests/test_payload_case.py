"""The bench's payload case (issue #54): on the paper's arm, the load its plant carries is
named by the measured loop within the check's 5 % and the aim's 1 cm, read against the
plant's own last body (never seen by the loop)."""

from __future__ import annotations

import pytest

from harness.closeloop.payload_case import COM_AIM, MASS_CHECK, payload_case
from harness.robots.arm import Arm


def test_the_payload_case_names_the_load(tmp_path):
    out = payload_case(Arm.of("lynxmotion"), tmp_path)
    arm = Arm.of("lynxmotion")
    mass = sum(arm.pinocchio.inertias[j].mass for j in range(1, arm.dof + 1))
    assert out["true_mass"] == pytest.approx(2.7 * mass / 18.0, rel=1e-6)  # the scaled load
    assert out["named"] and out["mass_error"] <= MASS_CHECK and out["com_error_m"] <= COM_AIM
    assert all(a < b for a, b in zip(out["error_after"], out["error_before"], strict=True))
    assert not out["other_effects"]
