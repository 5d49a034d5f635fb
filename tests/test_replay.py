"""Replay: interpolation, clearance and energy cross-checked against independent computations."""

from __future__ import annotations

import numpy as np
import pytest

from harness.replay.reference import plan_reference
from harness.replay.simulate import TrackingGains, replay
from harness.robots.arm import Arm
from harness.robots.registry import MODELS
from planning.formulation.clearance import segment_distance

Q0 = np.array([np.pi / 2, np.pi / 5, -np.pi / 4])
Q_END = np.array([-np.pi / 2, 2 * np.pi / 5, -np.pi / 3])
OBSTACLE_FROM, OBSTACLE_TO = np.array([0.15, 0.40, 0.22]), np.array([0.18, -0.35, 0.28])


def quintic(t: np.ndarray, duration: float = 2.0):
    """Rest-to-rest quintic from Q0 to Q_END: q, qd, qdd of shape (n, 3)."""
    s = t / duration
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    dp = (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    ddp = (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    d = Q_END - Q0
    return Q0 + p[:, None] * d, dp[:, None] * d, ddp[:, None] * d


def quintic_plan(samples: int = 200, duration: float = 2.0) -> dict:
    """The paper's scenario as a PLAN.json-shaped dict (no obstacle avoidance)."""
    t = np.linspace(0.0, duration, samples)
    q, qd, qdd = quintic(t, duration)
    s = (t / duration)[:, None]
    obstacle = OBSTACLE_FROM + s * (OBSTACLE_TO - OBSTACLE_FROM)
    return {"t": t.tolist(), "q": q.tolist(), "qd": qd.tolist(), "qdd": qdd.tolist(),
            "obstacle": obstacle.tolist(), "threshold": 0.08}


@pytest.fixture(scope="module")
def feedforward():
    return Arm.of("lynxmotion").nominal


@pytest.fixture(scope="module")
def scene_replay(feedforward):
    model = Arm.of("lynxmotion").scene
    return replay(model, plan_reference(quintic_plan()), feedforward)


def test_reference_interpolates_between_coarse_samples_exactly():
    # A single quintic is reproduced exactly by the quintic Hermite spline from 7 samples.
    ref = plan_reference(quintic_plan(samples=7))
    t = np.linspace(0.0, 2.0, 1001)
    for got, want in zip(ref.joints_at(t), quintic(t), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-10)


def test_segment_distance_matches_dense_sampling():
    rng = np.random.default_rng(0)
    a, b, p = (rng.normal(size=(50, 3)) for _ in range(3))
    s = np.linspace(0.0, 1.0, 20001)
    brute = [np.min(np.linalg.norm(a[i] + s[:, None] * (b[i] - a[i]) - p[i], axis=1))
             for i in range(50)]
    np.testing.assert_allclose(segment_distance(p, a, b), brute, atol=1e-6)


def test_replay_tracks_and_measures_the_reference_energy(scene_replay, feedforward):
    result, trace = scene_replay
    assert result.tracking_rms < 1e-3
    # Independent energy: feedforward torques on the analytic quintic, fine trapezoid.
    t = np.linspace(0.0, 2.0, 40001)
    q, qd, qdd = quintic(t)
    power = np.abs(np.sum(feedforward.torque(q, qd, qdd) * qd, axis=1))
    energy = float(np.sum((power[1:] + power[:-1]) / 2 * np.diff(t)))
    assert result.energy == pytest.approx(energy, rel=2e-3)
    assert result.energy_planned == pytest.approx(energy, rel=2e-3)


def test_surface_clearance_is_centre_distance_minus_radii(scene_replay):
    result, trace = scene_replay
    model = Arm.of("lynxmotion").scene
    capsule = model.geom("link2").size[0]
    sphere = model.geom("obstacle").size[0]
    np.testing.assert_allclose(trace.surface, trace.clearance - capsule - sphere, atol=1e-9)
    assert result.surface_clearance == pytest.approx(result.min_clearance - capsule - sphere)


def test_clearance_follows_the_moving_obstacle(scene_replay):
    _, trace = scene_replay
    # The obstacle is where the plan says at every step (mocap moved, not left at its start).
    np.testing.assert_allclose(trace.obstacle[0], OBSTACLE_FROM)
    np.testing.assert_allclose(trace.obstacle[-1], OBSTACLE_TO)
    ee_to_obstacle = np.linalg.norm(trace.end_effector - trace.obstacle, axis=1)
    assert np.all(trace.clearance[:, 1] <= ee_to_obstacle + 1e-12)


def test_damped_plant_without_obstacle_body_still_replays(tmp_path, feedforward):
    # Effects the feedforward lacks (viscous damping, friction) are left to the PD.
    xml = (MODELS / "lynxmotion" / "lynxmotion.xml").read_text()
    xml = xml.replace('damping="0" armature="0" frictionloss="0"',
                      'damping="0.05" armature="0" frictionloss="0.02"')
    plant = tmp_path / "damped.xml"
    plant.write_text(xml)
    model = Arm.of(plant).mujoco
    result, _ = replay(model, plan_reference(quintic_plan()), feedforward, TrackingGains())
    assert result.tracking_rms < 1e-3
    assert result.surface_clearance is None
    assert result.energy > 1.02 * result.energy_reference  # the plant spends more than planned


def test_repeated_boundary_sample_counts_once_and_conflicts_are_rejected():
    from harness.errors import UserError

    plan = quintic_plan(samples=11)
    k = 5
    doubled = {key: (v[: k + 1] + v[k:] if isinstance(v, list) else v) for key, v in plan.items()}
    ref = plan_reference(doubled)
    assert len(ref.t) == 11
    doubled["q"][k + 1] = [0.0, 0.0, 0.0]
    with pytest.raises(UserError, match="two different states"):
        plan_reference(doubled)
