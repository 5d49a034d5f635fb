"""Physical or nothing (identification.closeloop.verdicts.ranges): an effect whose coefficient leaves its
physical range is never named, on any path of the loop, however much it lowers the error.

Each range is tried on the Lynxmotion (motors of 10 N m, 10 rad/s; 1.0 kg): a log whose
torque carries an effect just beyond its range must not name it, and the same effect inside
its range is named (so a range too tight fails too). The ranges themselves are the closed
forms of the module's docstring, on the arm's own limits."""

from __future__ import annotations

import numpy as np
import pytest

from harness.closeloop.one_log import rigid_library
from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from harness.robots.scales import robot_scales
from identification.closeloop.candidates.effects import EffectTerm, effect_torque
from identification.closeloop.candidates.payload import BodyTorque, standard
from identification.closeloop.selection.one_log import close_loop_measured
from identification.closeloop.selection.plant import close_loop
from identification.closeloop.selection.runs import close_loop_runs
from identification.closeloop.verdicts.ranges import ACCEL_TIME, LOAD_FRICTION_MAX, Scales
from tests.helpers import lynxmotion_motion

LYNX = Arm.of("lynxmotion")


def _motions(seeds=(11, 12), n=1500):
    return [lynxmotion_motion(n, seed=s) for s in seeds]


def _scales(motions) -> Scales:
    return robot_scales(LYNX, [(m.q, m.qd, m.qdd, LYNX.nominal.torque(m.q, m.qd, m.qdd))
                               for m in motions])


def test_the_ranges_are_the_closed_forms_on_the_arms_limits():
    motions = _motions()
    s = _scales(motions)
    tau, v = 10.0, 10.0  # the Lynxmotion's motors
    span = np.ptp(np.concatenate([m.q for m in motions])[:, 2])  # joint 3's, as the data cover it
    assert s.bounds(EffectTerm("viscous", 2, 0.0)) == pytest.approx((0.0, tau / v))
    assert s.bounds(EffectTerm("armature", 1, 0.0)) == pytest.approx((0.0, tau * ACCEL_TIME / v))
    assert s.bounds(EffectTerm("spring", 3, 0.0)) == pytest.approx((0.0, 2 * tau / span))
    assert s.bounds(EffectTerm("coulomb", 3, 0.0)) == pytest.approx((0.0, tau))
    assert s.bounds(EffectTerm("payload", 3, 0.0)) == pytest.approx((0.0, 1.0))
    assert not s.holds(EffectTerm("payload", 3, 0.0))  # a payload has a mass
    assert not s.holds(EffectTerm("load_friction", 2, LOAD_FRICTION_MAX))
    assert s.holds(EffectTerm("load_friction", 2, 0.0))


def _logs(term: EffectTerm, motions, body=None, params=None):
    """(q, qd, qdd, tau) per motion: the nominal torque, the term's and a load's, and noise."""
    runs = []
    for i, m in enumerate(motions):
        rigid = LYNX.nominal.torque(m.q, m.qd, m.qdd)
        if params is not None:
            rigid = rigid + BodyTorque(body, params).torque(m.q, m.qd, m.qdd)
        tau = rigid + effect_torque((term,), m.q, m.qd, m.qdd, load=rigid)
        noise = 0.002 * np.random.default_rng(i).normal(size=tau.shape)
        runs.append((m.q, m.qd, m.qdd, tau + noise))
    return runs


# (effect beyond its range, the same inside it): Lynxmotion's bounds are viscous 1, armature
# 0.5, spring 2 x 10 / the data's span (about 8 N m/rad), Coulomb 10 N m, load friction 0.5, a
# payload's mass 1 kg
CASES = {"viscous": (EffectTerm("viscous", 2, 1.5), EffectTerm("viscous", 2, 0.05)),
         "negative viscous": (EffectTerm("viscous", 2, -0.05), EffectTerm("viscous", 2, 0.05)),
         "armature": (EffectTerm("armature", 1, 0.8), EffectTerm("armature", 1, 0.01)),
         "spring": (EffectTerm("spring", 3, 12.0), EffectTerm("spring", 3, 0.05)),
         "coulomb": (EffectTerm("coulomb", 2, 12.0, lead=0.0, eps=0.01),
                     EffectTerm("coulomb", 2, 0.05, lead=0.0, eps=0.01)),
         "load_friction": (EffectTerm("load_friction", 2, 0.7, lead=0.0, eps=0.01),
                           EffectTerm("load_friction", 2, 0.1, lead=0.0, eps=0.01))}


def _named(loop) -> set[tuple[str, int]]:
    return {(t.effect, t.joint) for t in loop.terms}


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_runs_loop_names_an_effect_only_in_its_range(case):
    motions = _motions()
    beyond, inside = CASES[case]
    scales = _scales(motions)
    for term, expect in ((beyond, False), (inside, True)):
        loop = close_loop_runs(LYNX.nominal, _logs(term, motions), scales=scales)
        assert ((term.effect, term.joint) in _named(loop)) is expect, (case, term, loop.terms)
        assert all(scales.holds(t) for t in loop.terms)
        assert all(n.physical for n in loop.named)


def test_a_payload_heavier_than_the_arm_is_not_named():
    motions, body = _motions(), last_body(LYNX)
    scales = _scales(motions)
    for mass, expect in ((1.5, False), (0.2, True)):
        params = standard(mass, [0.02, 0.0, 0.01], [1e-4, 0.0, 1e-4, 0.0, 0.0, 1e-4])
        runs = _logs(EffectTerm("viscous", 1, 0.0), motions, body, params)
        loop = close_loop_runs(LYNX.nominal, runs, body=body, scales=scales)
        named = [t for t in loop.terms if t.effect == "payload"]
        assert bool(named) is expect, (mass, loop.terms)
        assert all(scales.holds(t) for t in loop.terms)


LOOPS = {  # the plant's loop (a fixed declared model) and the one-log loop (its own fit)
    "plant": (13, lambda q, qd, qdd, tau, scales: close_loop(
        LYNX.nominal, q, qd, qdd, tau, tau, scales=scales)),
    "measured": (14, lambda q, qd, qdd, tau, scales: close_loop_measured(
        rigid_library(LYNX), q, qd, qdd, tau, scales=scales)),
}


@pytest.mark.parametrize("path", sorted(LOOPS))
def test_the_other_loops_name_an_effect_only_in_its_range(path):
    seed, loop_of = LOOPS[path]
    (m,) = _motions((seed,), 3000)
    scales = _scales([m])
    for term, expect in ((CASES["viscous"][0], False), (CASES["viscous"][1], True)):
        (q, qd, qdd, tau), = _logs(term, [m])
        loop = loop_of(q, qd, qdd, tau, scales)
        assert (("viscous", 2) in _named(loop)) is expect, (path, term, loop.terms)
        assert all(scales.holds(t) for t in loop.terms)
