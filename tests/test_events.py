"""External torques in a log (identification.closeloop.events), cross-checked: the observer's
momentum and beta against Pinocchio's mass matrix, gravity and Coriolis matrix; its response
to a step of external torque against the closed form of a first-order lag; pushes simulated in
MuJoCo (xfrc_applied) found at their onset and none invented; the shipped real Panda log
(an excitation, nothing pushed) without an event; the command's events and its bad input."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from harness.cli import main
from harness.data.generate import generate
from harness.data.pushes import Push
from harness.robots.arm import Arm
from harness.robots.bodies import last_body
from identification.closeloop.events.detect import find_events
from identification.closeloop.events.observer import GAIN, momentum_terms, observer
from tests.helpers import lynxmotion_motion

LYNX = Arm.of("lynxmotion")


def test_momentum_and_beta_are_pinocchios():
    m = lynxmotion_motion(50, seed=3)
    model, data = LYNX.pinocchio, LYNX.pinocchio.createData()
    p, beta = momentum_terms(LYNX.nominal, m.q, m.qd)
    for k in range(0, 50, 7):
        q, qd = m.q[k], m.qd[k]
        mass = pin.crba(model, data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        coriolis = pin.computeCoriolisMatrix(model, data, q, qd)
        gravity = pin.computeGeneralizedGravity(model, data, q)
        assert p[k] == pytest.approx(mass @ qd, abs=1e-10)
        assert beta[k] == pytest.approx(gravity - coriolis.T @ qd, abs=1e-6)


def test_a_step_of_external_torque_is_followed_as_a_first_order_lag():
    m = lynxmotion_motion(2000, seed=1, duration=10.0)
    t0, step = 4.0, np.array([0.0, 0.05, -0.02])  # N m on joints 2 and 3
    pushed = m.t >= t0
    # the motor holds the motion against the world: tau = inverse dynamics - tau_ext
    tau = LYNX.nominal.torque(m.q, m.qd, m.qdd) - pushed[:, None] * step
    r = observer(LYNX.nominal, m.t, m.q, m.qd, tau)
    scale = np.abs(LYNX.nominal.torque(m.q, m.qd, m.qdd)).max()
    # the exact model: nothing before the push but the trapezoid's error, second order in dt
    assert np.abs(r[~pushed]).max() < 1e-3 * scale
    fine = lynxmotion_motion(8000, seed=1, duration=10.0)
    r_fine = observer(LYNX.nominal, fine.t, fine.q, fine.qd,
                      LYNX.nominal.torque(fine.q, fine.qd, fine.qdd))
    assert np.abs(r_fine[fine.t < t0]).max() < np.abs(r[~pushed]).max() / 10
    after = m.t > t0 + 0.02
    lag = 1.0 - np.exp(-GAIN * (m.t[after] - t0))
    assert r[after] == pytest.approx(lag[:, None] * step, abs=0.06 * np.abs(step).max())
    assert r[-1] == pytest.approx(step, abs=1e-4)


@pytest.fixture(scope="module")
def ur5_pushed():
    arm = Arm.of("ur5")
    pushes = (Push("forearm_link", 4.0, 0.5, (60.0, 0.0, 0.0)),
              Push("wrist_2_link", 12.0, 0.3, (0.0, 40.0, 10.0)))
    data = generate(arm, 4000, 0.05, 808, "measured", 0.0, pushes=pushes)
    return arm, pushes, data


def test_simulated_pushes_are_found_at_their_onset(ur5_pushed):
    arm, pushes, d = ur5_pushed
    found = find_events(arm.nominal, d.t, d.q, d.qd, d.qdd, d.tau, last_body(arm))
    assert len(found.events) == len(pushes)
    for event, push in zip(found.events, pushes, strict=True):
        assert abs(event.start - push.start) <= 0.03
        assert abs(event.end - (push.start + push.duration)) <= 0.1
        true_peak = np.abs(d.truth["tau_external"]).max(axis=0)
        assert np.max(np.abs(event.peak)) > 0.5 * true_peak.max()
    assert not np.any(found.kept & (np.abs(d.truth["tau_external"]).max(axis=1) > 0))


def test_no_event_is_invented_where_nothing_pushes():
    arm = Arm.of("ur5")
    d = generate(arm, 4000, 0.05, 809, "measured", 0.0)
    found = find_events(arm.nominal, d.t, d.q, d.qd, d.qdd, d.tau, last_body(arm))
    assert found.events == () and found.kept.all()


@pytest.mark.slow
def test_the_real_panda_excitation_has_no_event():
    from data import DATA
    from harness.data.ingest import ingest

    arm = Arm.of("panda")
    a = ingest(DATA / "panda_gaz2019" / "panda_gaz2019.csv.gz", arm, 200.0, None).arrays
    found = find_events(arm.nominal, a["t"], a["q"], a["qd"], a["qdd"], a["tau"], last_body(arm))
    assert found.events == ()


def test_closeloop_reports_a_push_on_the_plant(tmp_path, capsys):
    out = tmp_path / "loop"
    assert main(["closeloop", "--plant", "lynxmotion", "--samples", "2000", "--seed", "5",
                 "--push", "link3:4:0.5:0,0,-3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "external torque: 1 event (4.0-4.5 s" in text
    report = json.loads((out / "closeloop.json").read_text())
    (event,) = report["events"]
    assert abs(event["start"] - 4.0) <= 0.03 and 2 in event["joints"]
    assert report["event_detection"]["observer_gain"] == GAIN
    assert report["effects"] == []


@pytest.mark.parametrize("push", ["link2:4:0.5", "link2:-1:0.5:0,0,1", "link2:4:0:0,0,1",
                                  "nolink:4:0.5:0,0,1", "link2:4:0.5:0,nan,1"])
def test_a_bad_push_is_one_line_and_exit_2(tmp_path, capsys, push):
    out = tmp_path / "loop"
    assert main(["closeloop", "--plant", "lynxmotion", "--push", push, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--push" in err[0]
    assert not out.exists()
