"""Link capsules fitted to the robots' meshes (harness.robots.capsules, issue #43 item 5):
each holds its body's mesh and is not much fatter; the planner's CasADi distance to a
capsule is MuJoCo's mj_geomDistance to the scene's capsule; `plan` on the UR5 keeps the
surfaces clear in replay; a robot without meshes keeps its centre lines."""

from __future__ import annotations

import json

import casadi as ca
import mujoco
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial import ConvexHull

from harness.cli import main
from harness.commands.replay import plan_capsules
from harness.errors import UserError
from harness.replay.clearance import ClearanceProbe
from harness.robots.arm import Arm
from harness.robots.capsules import fit_capsule, link_capsules
from harness.robots.registry import erd_robots_dir
from harness.robots.scene import OBSTACLE_RADIUS, build_scene
from planning.formulation.clearance import (
    link_clearances,
    segment_distance,
    symbolic_link_clearances,
)
from planning.result import capsules

RNG = np.random.default_rng(43)
MESHED = ("ur5", "panda")
UR3 = str(erd_robots_dir() / "ur_description" / "urdf" / "ur3_robot.urdf")


def _link_points(robot: str) -> list[np.ndarray | None]:
    """The mesh points (n, 3) of each link's body in the world at q = 0 (m)."""
    model = Arm.of(robot).pinocchio
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    found = {j: points for j, (_, points) in Arm.of(robot).body_points.items()}
    out = []
    for i, _ in Arm.of(robot).capsules().links:
        placement = data.oMi[i + 1]
        points = found.get(i + 1)
        out.append(None if points is None
                   else points @ placement.rotation.T + placement.translation)
    return out


@pytest.mark.parametrize("robot", MESHED)
def test_capsules_hold_every_mesh_point_and_are_snug(robot):
    geometry = Arm.of(robot).capsules()
    a, b = (x[0] for x in geometry.link_ends(np.zeros(geometry.dof)))
    for k, points in enumerate(_link_points(robot)):
        assert points is not None  # every link of these arms has meshes
        capsule = fit_capsule(points)
        assert capsule.distance(points).max() <= 1e-9  # holds every point
        # the planner's capsule is this one, carried to the world at q = 0
        assert segment_distance(points, a[k], b[k]).max() <= geometry.radii[k] + 1e-9
        # not much fatter than the mesh: its convex hull fills a good part of the capsule
        assert ConvexHull(points).volume >= 0.25 * capsule.volume
    radii = np.asarray(geometry.radii)
    assert np.all(radii > 0.03) and np.all(radii < 0.1)  # the UR5's upper arm: not 0.18 m


def test_fit_is_exact_on_a_sampled_capsule():
    """Points on a capsule's surface give back that capsule (to the search's tolerance)."""
    direction = RNG.normal(size=(4000, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    t = RNG.uniform(-0.1, 0.1, 4000)
    side = direction * [1, 1, 0]
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    points = np.where(np.abs(direction[:, 2:]) > 0.5,
                      0.03 * direction + np.c_[0 * t, 0 * t, 0.1 * np.sign(direction[:, 2])],
                      0.03 * side + np.c_[0 * t, 0 * t, t])
    capsule = fit_capsule(points @ np.linalg.qr(RNG.normal(size=(3, 3)))[0].T)
    assert capsule.radius == pytest.approx(0.03, abs=1e-4)
    assert np.linalg.norm(capsule.b - capsule.a) == pytest.approx(0.2, abs=1e-3)


@pytest.mark.parametrize("robot", MESHED + (UR3,))
def test_planner_distance_is_mujoco_geom_distance(robot):
    """The CasADi clearance row of every link, minus the obstacle sphere's radius, is
    mj_geomDistance between the scene's capsule and the sphere; the replay's probe agrees.
    The UR3 (example-robot-data) has links of zero length on its wrist: spheres in the scene
    (MuJoCo refuses a capsule between coincident points; replay raised a traceback)."""
    geometry = Arm.of(robot).capsules()
    model = build_scene(Arm.of(robot), geometry=geometry).compile()
    data = mujoco.MjData(model)
    probe = ClearanceProbe.of(model, geometry)
    assert probe.has_surface and probe.axes is not None
    q, centre = ca.SX.sym("q", geometry.dof), ca.SX.sym("c", 3)
    rows = ca.Function("rows", [q, centre],
                       [ca.vertcat(*symbolic_link_clearances(geometry, q, centre))])
    lower, upper = Arm.of(robot).joint_limits
    for _ in range(20):
        angles = RNG.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi))
        mid = geometry.link_ends(angles)[0][0, RNG.integers(len(geometry.links))]
        obstacle = mid + RNG.uniform(-0.25, 0.25, 3)
        data.qpos[:] = angles
        probe.move_obstacle(data, obstacle)
        mujoco.mj_kinematics(model, data)
        planned = np.asarray(rows(angles, obstacle)).ravel()
        np.testing.assert_allclose(planned - OBSTACLE_RADIUS,
                                   probe.surface_distances(model, data), atol=1e-6)
        np.testing.assert_allclose(planned, probe.centre_distances(data, obstacle), atol=1e-9)
        np.testing.assert_allclose(planned, link_clearances(geometry, angles, obstacle)[0],
                                   atol=1e-12)


def test_fitted_capsules_are_the_link_capsules_of_every_link():
    """The UR5's six links keep their joint-origin links; the Panda gains its link 5 (the
    forearm, on a zero-length segment) and keeps link 1 out (it does not move)."""
    geometry = Arm.of("ur5").geometry
    meshes = {j: points for j, (_, points) in Arm.of("ur5").body_points.items()}
    capsules = link_capsules(meshes, Arm.of("ur5").pinocchio, geometry)
    fitted = Arm.of("ur5").capsules()
    assert fitted.links == geometry.links and fitted.covered == ()
    assert len(capsules) == len(fitted.ends) == len(geometry.links)
    for capsule, (a, b), radius in zip(capsules, fitted.ends, fitted.radii, strict=True):
        np.testing.assert_array_equal(capsule.a, a)
        np.testing.assert_array_equal(capsule.b, b)
        assert capsule.radius == radius
    panda = Arm.of("panda").capsules()
    assert panda.covered == (4,) and (4, 5) in panda.links and (0, 1) not in panda.links
    assert len(panda.links) == len(Arm.of("panda").geometry.links) + 1


def test_robot_without_meshes_keeps_its_centre_lines():
    assert Arm.of("lynxmotion").capsules() == Arm.of("lynxmotion").geometry


@pytest.mark.slow
def test_ur5_default_plan_keeps_the_surfaces_clear_in_replay(tmp_path):
    plan_path, replay_path = tmp_path / "plan.json", tmp_path / "replay.json"
    assert main(["plan", "--robot", "ur5", "--model", "pinocchio", "--obstacle-from",
                 "0.37,-0.06,0.15", "--obstacle-to", "0.37,-0.06,0.65",
                 "--out", str(plan_path)]) == 0
    plan = json.loads(plan_path.read_text())
    geometry = Arm.of("ur5").capsules()
    assert plan["link_radii"] == list(geometry.radii)
    assert [c["joint"] for c in plan["link_capsules"]] == [j for _, j in geometry.links]
    assert [c["radius"] for c in plan["link_capsules"]] == plan["link_radii"]
    assert plan["min_surface_clearance"] == plan["min_clearance"] > 0
    assert main(["replay", "--plan", str(plan_path), "--out", str(replay_path)]) == 0
    replayed = json.loads(replay_path.read_text())
    assert replayed["surface_clearance"] > 0  # mj_geomDistance: capsules to the sphere
    assert min(replayed["link_min_surface_clearance"]) == replayed["surface_clearance"]
    assert replayed["min_clearance"] >= plan["threshold"] - 5e-3


def test_replay_rebuilds_the_plans_capsules():
    """PLAN.json's link_capsules (planning.result.capsules) give back the planner's geometry,
    the Panda's extra link included; bad entries are one UserError."""
    for robot in MESHED:
        fitted = Arm.of(robot).capsules()
        recorded = json.loads(json.dumps(capsules(fitted)))
        assert plan_capsules(recorded, Arm.of(robot).geometry) == fitted
    assert plan_capsules(None, Arm.of("lynxmotion").geometry) == Arm.of("lynxmotion").geometry
    recorded = json.loads(json.dumps(capsules(Arm.of("ur5").capsules())))
    for change in ({"joint": 9}, {"a": [0, 0]}, {"radius": -1}, {"b": "x"}):
        with pytest.raises(UserError):
            plan_capsules([{**recorded[0], **change}, *recorded[1:]], Arm.of("ur5").geometry)
