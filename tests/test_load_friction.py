"""Dry friction that grows with the load (issue #54): `load_friction` in the measured loop.

A log of the Lynxmotion carrying a load on its last body, with friction mu |L_j| sat(qd_j /
eps) on joints 2 and 3 (L the loaded rigid body's torque): the loop names the load and the
friction within a few per cent, the model it writes reads back the same torque, and its
CasADi form is its numeric one. Without the candidate the same data name an effect they do
not have (a viscous term, 2.6 % on the mass: on the UR5's wrist 79 %, docs/closeloop.md).
The 6-joint case (the UR5 with its wrist's friction) is the bench's payload case and the
study payload's, smoke-tested in tests/test_studies.py.
"""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from harness.robots.closed_model import closeloop_model, model_payload
from identification.closeloop.candidates.effects import EffectTerm
from identification.closeloop.candidates.load_friction import EFFECT
from identification.closeloop.candidates.payload import BodyTorque, describe, standard
from identification.closeloop.selection.runs import RUNS_EFFECTS, close_loop_runs
from tests.helpers import lynxmotion_motion

LYNX = Arm.of("lynxmotion")
LOAD = standard(0.15, [0.05, -0.01, 0.03], [2e-4, 0.0, 3e-4, 0.0, 0.0, 2e-4])
MU, EPS = (0.0, 0.08, 0.06), 0.01  # per joint, N m per N m; rad/s


def _runs(seeds=(3, 4)):
    body = last_body(LYNX)
    runs = []
    for seed in seeds:
        m = lynxmotion_motion(1500, seed=seed)
        rigid = LYNX.nominal.torque(m.q, m.qd, m.qdd) + BodyTorque(body, LOAD).torque(
            m.q, m.qd, m.qdd)
        tau = rigid + np.array(MU) * np.abs(rigid) * np.clip(m.qd / EPS, -1.0, 1.0)
        noise = 0.002 * np.random.default_rng(seed).normal(size=tau.shape)
        runs.append((m.q, m.qd, m.qdd, tau + noise + np.array([0.01, -0.02, 0.005])))
    return runs


@pytest.fixture(scope="module")
def loop():
    return close_loop_runs(LYNX.nominal, _runs(), body=last_body(LYNX))


def test_the_load_and_its_friction_are_named(loop):
    named = {(t.effect, t.joint): t for t in loop.terms}
    mass, com, _ = describe(named[("payload", 3)].params)
    assert mass == pytest.approx(0.15, rel=0.03)
    assert np.linalg.norm(com - [0.05, -0.01, 0.03]) < 0.01
    for joint in (2, 3):
        assert named[(EFFECT, joint)].coefficient == pytest.approx(MU[joint - 1], rel=0.1)
    assert (EFFECT, 1) not in named


def test_without_the_candidate_other_effects_take_its_place():
    """What the candidate is for: the same data, the friction left out of the dictionary."""
    effects = tuple(e for e in RUNS_EFFECTS if e != EFFECT)
    terms = close_loop_runs(LYNX.nominal, _runs(), effects=effects, body=last_body(LYNX)).terms
    assert {t.effect for t in terms} - {"payload"}


def test_model_json_reads_back_the_torque_of_the_loop(loop, tmp_path):
    m = lynxmotion_motion(200, seed=9)
    written = json.loads(json.dumps(model_payload(LYNX, "pinocchio", None, loop.terms,
                                                  loop.run_offsets)))
    assert any(e["effect"] == EFFECT and "eps" in e for e in written["effects"])
    back = closeloop_model(written, LYNX, Path(tmp_path) / "model.json")
    np.testing.assert_allclose(back.torque(m.q, m.qd, m.qdd), loop.model.torque(m.q, m.qd, m.qdd),
                               atol=1e-9)


def test_the_casadi_form_is_the_numeric_one(loop):
    m = lynxmotion_motion(50, seed=11)
    q, qd, qdd = (ca.SX.sym(s, LYNX.dof) for s in ("q", "qd", "qdd"))
    f = ca.Function("tau", [q, qd, qdd], [loop.model.symbolic_torque(q, qd, qdd)])
    symbolic = np.array([np.ravel(f(*(x[k] for x in (m.q, m.qd, m.qdd)))) for k in range(50)])
    np.testing.assert_allclose(symbolic, loop.model.torque(m.q, m.qd, m.qdd), atol=1e-9)


def test_a_load_friction_term_needs_the_load():
    m = lynxmotion_motion(10, seed=1)
    from identification.closeloop.candidates.effects import effect_torque

    with pytest.raises(ValueError, match="load torque"):
        effect_torque((EffectTerm(EFFECT, 2, 0.1),), m.q, m.qd, m.qdd)


def test_a_payload_that_trades_with_the_load_friction_is_read_as_a_range(loop):
    """Where the load friction's columns explain the payload's (variance inflation >= 10),
    the two trade on the data and the payload is reported as its interval's range, not a
    point (issue #67: one real load read 2.38 and 2.17 kg on two runs); on the loop's
    well-excited Lynxmotion runs it is told apart."""
    from identification.closeloop.candidates.load_friction import told_apart

    rng = np.random.default_rng(0)
    payload = rng.normal(size=(500, 3))
    alike = payload[:, :, None] + 0.2 * rng.normal(size=(500, 3, 1))  # R^2 about 0.96
    unlike = rng.normal(size=(500, 3, 1))
    keep = lambda x: (x.reshape(x.shape[0] * x.shape[1], -1))  # noqa: E731 (nothing projected)
    traded = told_apart({}, 2.3, 0.1, payload, alike, keep)
    assert not traded["told_apart"] and traded["variance_inflation"] > 10
    assert traded["mass_range_kg"] == pytest.approx([2.2, 2.4])
    apart = told_apart({}, 2.3, 0.1, payload, unlike, keep)
    assert apart["told_apart"] and apart["variance_inflation"] < 1.1
    assert "mass_range_kg" not in apart
    assert told_apart({"x": 1}, 2.3, 0.1, payload, unlike[:, :, :0], keep) == {"x": 1}
    entry = next(n for n in loop.named if n.term.effect == "payload").to_json()
    assert entry["told_apart"] and "mass_range_kg" not in entry
