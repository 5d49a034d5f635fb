"""The split energy quadrature: Gauss-Legendre between the power's sign changes."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from harness.robots.arm import Arm
from planning.config import PenaltyOptions
from planning.formulation.breaks import power_breaks, settled, sign_changes
from planning.formulation.energy import dense_energy, power
from planning.formulation.quadrature import energy_nodes, split_nodes
from planning.formulation.trajectory import PolynomialTrajectory
from planning.penalty.loop import plan_multistart, plan_segment
from planning.penalty.solver import Planner
from planning.starts import rank
from planning.types import Segment
from tests.helpers import lynx_config, lynx_scenario, random_crossing


@pytest.fixture(scope="module")
def baseline():
    return Arm.of("lynxmotion").nominal


def test_split_rule_is_exact_for_a_polynomial_with_kinks_at_its_breaks():
    roots = np.array([0.23, 0.61, 0.87])

    def p(s):
        return np.prod(s[..., None] - roots, axis=-1) * (1.0 + s**2)

    exact = sum(quad(lambda s: abs(p(np.array(s))), a, b, epsabs=1e-14)[0]
                for a, b in zip([0.0, *roots], [*roots, 1.0], strict=True))
    s, w = split_nodes(roots, 12)  # 3 nodes per interval: exact to degree 5
    assert np.isclose(sum(w), 1.0) and np.all(np.diff(s) > 0)
    assert np.isclose(np.dot(w, np.abs(p(np.array(s)))), exact, rtol=1e-12, atol=0)
    # plain Gauss with the same nodes straddles the kinks: a visible error
    s, w = energy_nodes("gauss", 12)
    assert abs(w @ np.abs(p(s)) - exact) > 1e-4 * exact
    with pytest.raises(ValueError, match="multiple of 4"):
        split_nodes(roots, 10)


def _motion() -> PolynomialTrajectory:
    c = np.array([[0.3, 0.0, 0.25, -0.26, 1.28, 0.21], [1.0, 0.0, -1.07, 0.72, 2.61, 1.89],
                  [-1.0, 0.0, -1.41, -2.53, -1.25, 0.08]])  # three sign changes of the power
    return PolynomialTrajectory(0.3, 1.7, c)


def test_breaks_are_the_power_sign_changes_then_even_fills(baseline):
    motion = _motion()

    def p(s):
        return power(baseline, *motion.state(motion.t_begin + motion.duration * s))[0]

    grid = np.linspace(0.0, 1.0, 4001)
    values = np.array([p(s) for s in grid])
    brackets = np.flatnonzero(values[:-1] * values[1:] < 0)
    roots = np.array([brentq(p, grid[i], grid[i + 1], xtol=1e-12) for i in brackets])
    assert len(roots) == 3
    found, _ = sign_changes(baseline, motion)
    assert np.allclose(np.sort(found), roots, atol=1e-3)
    breaks = power_breaks(baseline, motion, len(roots) + 2)
    assert np.all(np.min(np.abs(breaks[:, None] - roots[None, :]), axis=0) < 1e-3)
    assert np.all(np.diff(breaks) > 0) and 0 < breaks[0] and breaks[-1] < 1
    assert settled(baseline, motion, breaks)
    assert not settled(baseline, motion, np.sort(breaks + 0.05))


def test_split_plan_prices_its_own_energy_and_beats_gauss_on_the_paper_scenario(baseline):
    """The planned energy of a split-quadrature plan is its true energy (a dense integral of
    Pinocchio's power); a Gauss N = 24 plan, same nodes, underprices its own."""
    scenario = lynx_scenario()
    results = {}
    for rule in ("split", "gauss"):
        config = lynx_config(energy_quadrature=rule, energy_samples=24, power_breaks=7)
        planner = Planner(baseline, config)
        plan, _, _ = plan_segment(planner, Segment.of(scenario))
        t = np.linspace(0.0, scenario.duration, 8001)
        dense = np.trapezoid(np.abs(power(baseline, *plan.trajectory.state(t))), t)
        results[rule] = plan.energy, dense
    planned, dense = results["split"]
    assert abs(planned - dense) < 1e-4 * dense
    assert dense <= results["gauss"][1] * (1 + 1e-4)


def test_plan_command_with_the_split_quadrature(tmp_path, capsys):
    from harness.cli import main

    out = tmp_path / "plan.json"
    split = ["plan", "--no-compile", "--model", "pinocchio", "--energy-quadrature", "split"]
    assert main([*split, "--energy-samples", "10", "--out", str(out)]) == 2
    assert "multiple of --power-breaks + 1" in capsys.readouterr().err and not out.exists()
    assert main([*split, "--power-breaks", "4", "--starts", "1",
                 "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["energy_quadrature"] == "split" and plan["min_clearance"] > 0
    gauss = ["plan", "--no-compile", "--model", "pinocchio", "--starts", "1", "--polish", "1"]
    assert main([*gauss, "--power-breaks", "6", "--out", str(out)]) == 2  # 40 nodes, 7 parts
    assert "--polish-samples a positive multiple" in capsys.readouterr().err
    assert main([*gauss, "--polish-samples", "16", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["polish"] == 1 and plan["polish_samples"] == 16 and plan["feasible"]


def test_dense_energy_matches_an_adaptive_integral_across_the_kinks(baseline):
    """planning.formulation.energy.dense_energy (513 even points) against scipy's adaptive quad split
    at brentq roots of the power: within 2e-4 relative on a motion with three kinks (1.2e-4
    measured), far finer than the 0.5 % that separate the plans it ranks."""
    motion = _motion()

    def p(t):
        return power(baseline, *motion.state(np.array([t])))[0]

    t = motion.t_begin + motion.duration * np.linspace(0.0, 1.0, 2001)
    values = power(baseline, *motion.state(t))
    roots = [brentq(p, t[i], t[i + 1], xtol=1e-13)
             for i in np.flatnonzero(values[:-1] * values[1:] < 0)]
    edges = [motion.t_begin, *roots, motion.t_begin + motion.duration]
    exact = sum(quad(lambda x: abs(p(x)), a, b, epsabs=1e-12)[0]
                for a, b in zip(edges[:-1], edges[1:], strict=True))
    assert len(roots) == 3
    assert abs(dense_energy(baseline, motion) - exact) < 2e-4 * exact


def test_polished_cold_plan_spends_less_and_replans_warm_from_it(baseline):
    """config.penalty.polish: the best cold plan re-solved with the split rule at 40 nodes. On a
    random crossing (seed 2, the obstacle's path known) the kept plan is the polished one,
    it spends less than the best unpolished plan (dense integral, 0.4 % measured) and
    prices its own energy; a re-plan of the Gauss planner starts warm from it (from its
    motion: the multipliers are another NLP's)."""
    config = lynx_config(energy_quadrature="gauss", energy_samples=20, starts=2,
                           penalty=PenaltyOptions(polish=1))
    planner = Planner(baseline, config)
    case, forecast = random_crossing(planner, 2)
    segment = Segment.of(case, forecast)
    best, _, _, plans = plan_multistart(planner, segment)
    unpolished = min(plans, key=lambda plan: rank(planner, plan))
    assert best.success and rank(planner, best)[2] < rank(planner, unpolished)[2]
    assert best.layout == ("split", 40, False) != unpolished.layout
    assert abs(best.energy - dense_energy(baseline, best.trajectory)) < 1e-3 * best.energy
    # plans are ranked by what they spend, not by their own quadrature's figure
    assert rank(planner, dataclasses.replace(best, energy=1e3)) == rank(planner, best)
    # ... and one beyond a joint limit after every plan within them: q1 (the base's vertical
    # axis, no gravity work) shifted 5 mrad past its upper limit spends what `best` does
    coefficients = best.trajectory.coefficients.copy()
    coefficients[0, 0] += config.upper[0] + 5e-3 - best.trajectory.position(
        np.linspace(0.0, case.duration, 401))[:, 0].max()
    beyond = dataclasses.replace(best, trajectory=dataclasses.replace(
        best.trajectory, coefficients=coefficients))
    assert rank(planner, beyond)[1] and not rank(planner, best)[1]
    assert np.isclose(rank(planner, beyond)[2], rank(planner, best)[2], rtol=1e-9)
    assert min([beyond, *plans], key=lambda plan: rank(planner, plan)) is not beyond
    q, qd, _ = best.trajectory.state(0.5)
    replan, _, _ = plan_segment(planner, Segment(q[0], qd[0], 0.5, case.duration - 0.5, case.goal,
                                                 forecast), warm=best)  # (its multipliers would not fit)
    assert replan.success
    with pytest.raises(ValueError, match="multiple of power_breaks"):
        _ = Planner(baseline, dataclasses.replace(config, power_breaks=6)).polisher
