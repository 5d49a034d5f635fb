"""Linear guidance (planning.formulation.guidance): the guided clearance rows against numpy's
distances and offsets, and the normals read off a plan."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from harness.robots.arm import Arm
from planning.formulation.clearance import guided_link_clearances, link_clearances, symbolic_link_clearances
from planning.formulation.guidance import normals
from planning.formulation.trajectory import PolynomialTrajectory

RNG = np.random.default_rng(7)


def _rows(geometry):
    q, centre = ca.SX.sym("q", geometry.dof), ca.SX.sym("c", 3)
    n = ca.SX.sym("n", 3 * len(geometry.links))
    guided = ca.Function("g", [q, centre, n],
                         [ca.vertcat(*guided_link_clearances(geometry, q, centre, n))])
    plain = ca.Function("d", [q, centre], [ca.vertcat(*symbolic_link_clearances(geometry, q,
                                                                                centre))])
    return guided, plain


def _offsets(geometry, q, centre):
    """numpy: from the centre to each link's nearest point (links, 3)."""
    a, b = geometry.link_ends(q[None])
    ab = b[0] - a[0]
    s = np.clip(np.einsum("li,li->l", centre - a[0], ab) / np.einsum("li,li->l", ab, ab), 0, 1)
    return a[0] + s[:, None] * ab - centre


@pytest.mark.parametrize("robot", ("lynxmotion", "ur5"))
def test_guided_rows_are_offsets_along_the_normals(robot):
    """Unguided (zero normals) the rows are the distances bit for bit (the NLP's plans are the
    same as before guidance); guided by the directions at a pose q they equal the distances
    at q, and at another pose the offsets along them, n'(p - c) - r, never above the
    distances (a guided row that holds keeps the link clear)."""
    arm = Arm.of(robot)
    geometry, (lower, upper) = arm.geometry, arm.joint_limits
    guided, plain = _rows(geometry)
    radii = np.asarray(geometry.link_radii) if geometry.radii else 0.0
    links = len(geometry.links)
    for _ in range(5):
        q, moved = RNG.uniform(lower, upper), RNG.uniform(lower, upper)
        centre = RNG.uniform(-0.5, 0.5, 3)
        free = np.asarray(guided(q, centre, np.zeros(3 * links))).ravel()
        np.testing.assert_array_equal(free, np.asarray(plain(q, centre)).ravel())
        np.testing.assert_allclose(free, link_clearances(geometry, q[None], centre)[0],
                                   atol=1e-13)
        offset = _offsets(geometry, q, centre)
        unit = offset / np.linalg.norm(offset, axis=1)[:, None]
        np.testing.assert_allclose(np.asarray(guided(q, centre, unit.ravel())).ravel(), free,
                                   atol=1e-12)
        along = np.asarray(guided(moved, centre, unit.ravel())).ravel()
        np.testing.assert_allclose(
            along, np.einsum("li,li->l", unit, _offsets(geometry, moved, centre)) - radii,
            atol=1e-12)
        assert np.all(along <= link_clearances(geometry, moved[None], centre)[0] + 1e-12)


def test_normals_point_from_the_obstacle_to_the_near_links_only():
    """normals: slot-major, 3 per link; a unit vector from the centre to the link's nearest
    point on the plan where the link's clearance is below `near`, zero elsewhere and in the
    slots left empty."""
    arm = Arm.of("lynxmotion")
    geometry, (lower, upper) = arm.geometry, arm.joint_limits
    start, goal = np.asarray(lower) * 0.3, np.asarray(upper) * 0.3
    coefficients = np.zeros((len(start), 4))  # a cubic from start to goal over 2 s
    coefficients[:, 0], coefficients[:, 2], coefficients[:, 3] = start, 3 * (goal - start), \
        -2 * (goal - start)
    trajectory = PolynomialTrajectory(0.0, 2.0, coefficients)
    times = np.array([0.5, 1.0, 1.5])
    q = trajectory.position(times)
    points = geometry.points(q)  # put each centre 5 cm off a link's middle
    centres = 0.5 * (points[:, 1] + points[:, 2]) + np.array([0.0, 0.0, 0.05])
    clearance = link_clearances(geometry, q, centres)
    within = 0.5 * (clearance.min() + clearance.max())
    guide = normals(geometry, trajectory, times, centres, 5, within).reshape(5, -1, 3)
    near = clearance < within
    assert near.any() and not near.all()
    np.testing.assert_allclose(np.linalg.norm(guide[:3][near], axis=1), 1.0)
    assert not guide[:3][~near].any() and not guide[3:].any()
    for k, link in zip(*np.nonzero(near), strict=True):
        offset = _offsets(geometry, q[k], centres[k])[link]
        np.testing.assert_allclose(guide[k, link], offset / np.linalg.norm(offset), atol=1e-12)


def test_a_guided_replan_gives_its_rows_the_normals_of_the_plan_it_starts_from(monkeypatch):
    """The anytime SQP's re-plan of a segment marked guided (a guided bank's other classes)
    puts into its NLP the normals read off the plan it re-plans from, at the obstacle samples
    its rows hold, near links only; unguided, none. Without guidance the NLP has no normals
    (its distance rows as before guidance, whose evaluations cost less)."""
    from planning.anytime.solver import Anytime
    from planning.formulation.screening import MARGIN
    from planning.replanning import forecast_at
    from planning.types import ObstacleForecast, Segment
    from tests.helpers import lynx_default_config, lynx_scenario

    plain, case = lynx_default_config(), lynx_scenario()
    config = dataclasses.replace(plain, bank=dataclasses.replace(plain.bank, guided=True))
    assert not Anytime(Arm.of("lynxmotion").nominal, plain).problem(case.goal, False).nlp.guide.numel()
    anytime = Anytime(Arm.of("lynxmotion").nominal, config)
    times = case.obstacle.sample_times
    first, _, _ = anytime.solve(Segment.of(case, ObstacleForecast(
        times, case.obstacle.position(times)), budget_ms=1e5))
    given, guide = [], anytime._guide

    def recorded(problem, warm, slot_times, centres):
        given.append((warm, slot_times, centres, guide(problem, warm, slot_times, centres)))
        return given[-1][3]

    monkeypatch.setattr(anytime, "_guide", recorded)
    q, qd, _ = first.trajectory.state(0.5)
    later = Segment(q[0], qd[0], 0.5, 1.5, case.goal, forecast_at(case.obstacle, 0.5),
                    guided=True)
    anytime.solve(later, warm=first)
    warm, slot_times, centres, guided = given[0]
    assert warm is first and np.any(guided)
    np.testing.assert_array_equal(guided, normals(
        config.geometry, first.trajectory, slot_times, centres, config.obstacle_slots,
        config.threshold + MARGIN))
    given.clear()
    anytime.solve(dataclasses.replace(later, guided=False), warm=first)
    assert given and not any(np.any(normals_) for *_, normals_ in given)


def test_plan_bank_guidance_guides_the_re_plans_of_other_classes(monkeypatch, tmp_path):
    """`plan --bank 4 --bank-guidance` on the Lynxmotion's scenario: a re-plan's NLP is given
    guidance normals (non-zero, read off the plan it re-plans from) once the bank holds another
    class, a few re-plans in; the plan is stopped there (the whole plan takes 20 s). Without
    guidance every re-plan's normals are zero (test_a_guided_replan_gives_its_rows_...)."""
    from harness.cli import main
    from planning.anytime.solver import Anytime

    class Guided(Exception):
        pass

    guide = Anytime._guide

    def stop_when_guided(self, problem, warm, times, centres):
        given = guide(self, problem, warm, times, centres)
        if np.any(given):
            raise Guided
        return given

    monkeypatch.setattr(Anytime, "_guide", stop_when_guided)
    with pytest.raises(Guided):
        main(["plan", "--no-compile", "--model", "pinocchio", "--bank", "4", "--bank-guidance",
              "--out", str(tmp_path / "plan.json")])
