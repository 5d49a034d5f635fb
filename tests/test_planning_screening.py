"""Screening of obstacle samples: which ones a solve sees, and when a re-plan is settled."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.robots.arm import Arm
from planning.config import Scenario
from planning.formulation.clearance import link_clearances
from planning.formulation.screening import Screen, near_samples, screen, uncovered
from planning.penalty.solver import Planner
from planning.types import ObstacleForecast, Segment
from tests.helpers import lynx_config, lynx_scenario


def _screen(dips, gap):
    return Screen(ObstacleForecast(np.zeros(0), np.zeros((0, 3))), np.asarray(dips, float), gap, np.inf)


def _known_path(scenario: Scenario) -> ObstacleForecast:
    times = scenario.obstacle.sample_times
    return ObstacleForecast(times, scenario.obstacle.position(times))


def test_covered_needs_every_dip_unless_thinned():
    assert _screen([], 0.0).covered(np.zeros(0))
    assert _screen([0.1, 0.2], 0.0).covered(np.array([0.2, 0.1, 0.5]))
    assert not _screen([0.1, 0.2], 0.0).covered(np.array([0.1, 0.5]))
    assert not _screen([0.1], 0.05).covered(np.zeros(0))
    # thinned: a chosen sample within the gap stands for the dips around it
    assert _screen([0.11, 0.13, 0.2], 0.04).covered(np.array([0.1, 0.17, 0.3]))
    assert not _screen([0.11, 0.25], 0.04).covered(np.array([0.1, 0.17, 0.3]))


def test_screen_thins_to_the_slots_and_reports_the_gap():
    scenario = lynx_scenario()
    baseline = Arm.of("lynxmotion").nominal
    planner = Planner(baseline, lynx_config())
    free = planner.solve(Segment.of(scenario))
    forecast = _known_path(scenario)
    geometry, threshold = planner.config.geometry, planner.config.threshold
    wide = screen(forecast, free.trajectory, geometry, threshold, slots=1000)
    thin = screen(forecast, free.trajectory, geometry, threshold, slots=6)
    clearance = link_clearances(geometry, free.trajectory.position(forecast.times),
                                forecast.centres).min(axis=1)
    assert wide.gap == 0.0 and len(wide.subset.times) > 6
    assert np.array_equal(wide.subset.times, forecast.times[clearance < threshold + 0.03])
    assert np.array_equal(wide.dips, forecast.times[clearance < threshold])
    assert wide.lowest == thin.lowest == clearance.min()
    assert len(thin.subset.times) == 6 and set(thin.subset.times) <= set(wide.subset.times)
    assert thin.gap == pytest.approx(np.max(np.diff(thin.subset.times)))
    assert thin.covered(thin.subset.times) == bool(np.all(
        [np.min(np.abs(thin.subset.times - t)) <= thin.gap for t in thin.dips]))


def test_samples_above_the_threshold_leave_the_optimum_unchanged():
    """Screen.covered's premise: a solve that also sees samples where its result stays above
    the threshold returns the same result (their penalty terms and gradients are zero)."""
    scenario = lynx_scenario()
    baseline = Arm.of("lynxmotion").nominal
    planner = Planner(baseline, lynx_config(obstacle_slots=40))
    segment = Segment.of(scenario)
    free = planner.solve(segment)
    forecast = _known_path(scenario)
    geometry, threshold = planner.config.geometry, planner.config.threshold
    seen = screen(forecast, free.trajectory, geometry, threshold, slots=12, margin=0.0).subset
    plan = planner.solve(dataclasses.replace(segment, forecast=seen), reference=free.trajectory)
    clearance = link_clearances(geometry, plan.trajectory.position(forecast.times),
                                forecast.centres).min(axis=1)
    clear = np.flatnonzero((clearance > threshold + 1e-3) & ~np.isin(forecast.times, seen.times))
    added = clear[np.argsort(clearance[clear])[:20]]  # the nearest ones that stay clear
    assert len(added) == 20 and clearance[added].min() < threshold + 0.05
    keep = np.sort(np.concatenate([np.flatnonzero(np.isin(forecast.times, seen.times)), added]))
    more = planner.solve(dataclasses.replace(segment, forecast=ObstacleForecast(
        forecast.times[keep], forecast.centres[keep])), reference=free.trajectory)
    assert plan.success and more.success and plan.penalty > 0
    assert np.allclose(more.trajectory.coefficients, plan.trajectory.coefficients, atol=1e-5)
    assert more.energy + more.penalty == pytest.approx(plan.energy + plan.penalty, rel=1e-6)


def test_the_anytime_screen_covers_dips_per_link_and_within_the_thinning_gap():
    """Per (sample, link): a dip is covered by a row of its link at its sample, or, when the
    near samples were thinned to the slots, within the largest gap between slots; never by a
    row of another link. Agrees with Screen.covered on one link."""
    slots, rows = np.array([0, 5, 10]), np.array([[True, False]] * 3)
    dips = np.zeros((12, 2), bool)
    dips[3, 0] = True
    assert not uncovered(dips, slots, rows, count=3)  # thinned: within 5 of a slot
    assert uncovered(dips, slots, rows, count=4)  # not thinned: sample 3 had no row
    assert _screen([3.0], 5.0).covered(slots) == (not uncovered(dips, slots, rows, 3))
    dips[3, 0], dips[5, 1] = False, True
    assert uncovered(dips, slots, rows, count=3)  # link 2 had no row anywhere
    assert not uncovered(np.zeros((12, 2), bool), slots, rows, count=3)
    near = near_samples(np.array([0.2, 0.09, 0.1, 0.5, 0.05]), 0.08, slots=2)
    assert list(near) == [1, 4]  # below threshold + 3 cm: 1, 2, 4, thinned evenly to 2


def test_thinning_is_numpys_even_rounding():
    # the compiled thinning against np.round(np.linspace(...)), halves included (26 of 23)
    from planning.formulation.screening import _thinned
    for count in range(2, 120):
        for slots in range(0, count):
            expected = np.round(np.linspace(0, count - 1, slots)).astype(int)
            assert np.array_equal(_thinned(count, slots), expected), (count, slots)
