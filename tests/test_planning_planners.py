"""The segment planners behind one protocol: the factory picks one from the configuration,
the replanner's old names stay accepted, and PLAN.json keeps them."""

from __future__ import annotations

import pytest

from harness.robots.arm import Arm
from planning.anytime.planner import AnytimePlanner
from planning.bank.planner import BankPlanner
from planning.config import JSON_NAMES, PenaltyOptions
from planning.globalsearch.planner import GlobalSearchPlanner
from planning.penalty.planner import PenaltyLoop
from planning.penalty.polish import Polished
from planning.planners import segment_planner
from planning.types import SegmentPlanner
from tests.helpers import lynx_config, lynx_default_config


@pytest.fixture(scope="module")
def baseline():
    return Arm.of("lynxmotion").nominal


@pytest.mark.parametrize("name, kind", [("penalty", PenaltyLoop), ("fatrop", PenaltyLoop),
                                        ("anytime", AnytimePlanner), ("sqp", AnytimePlanner)])
def test_the_factory_picks_the_replanner_the_config_names(baseline, name, kind):
    config = lynx_default_config(replanner=name, compile_code=False).with_global_search(
        enabled=False).with_bank(size=1)
    planner = segment_planner(baseline, config)
    assert isinstance(planner, kind) and isinstance(planner, SegmentPlanner)
    assert planner.config.replanner in ("penalty", "anytime")
    assert JSON_NAMES[planner.config.replanner] in ("fatrop", "sqp")


def test_the_default_anytime_planner_is_a_bank_around_it(baseline):
    """plan's default: the anytime SQP in a bank of plans, the global search its own; a bank
    of one is the anytime SQP with the search handing over its better plans."""
    config = lynx_default_config(compile_code=False)
    bank = segment_planner(baseline, config)
    assert isinstance(bank, BankPlanner) and isinstance(bank, SegmentPlanner)
    assert isinstance(bank.inner, AnytimePlanner) and bank.search.bank
    one = segment_planner(baseline, config.with_bank(size=1))
    assert isinstance(one, GlobalSearchPlanner) and not one.bank


def test_the_split_rule_and_real_time_iterations_keep_the_penalty_loop(baseline):
    split = lynx_default_config(energy_quadrature="split", energy_samples=24, compile_code=False)
    iterating = lynx_default_config(compile_code=False).with_penalty(replan_iterations=1)
    assert isinstance(segment_planner(baseline, split), PenaltyLoop)
    assert isinstance(segment_planner(baseline, iterating), PenaltyLoop)


def test_the_anytime_sqps_cold_plans_are_polished_by_the_penalty_loop(baseline):
    config = lynx_default_config(compile_code=False).with_penalty(polish=1).with_global_search(
        enabled=False).with_bank(size=1)
    planner = segment_planner(baseline, config)
    assert isinstance(planner, Polished) and isinstance(planner.inner, AnytimePlanner)


def test_the_global_search_goes_around_the_anytime_sqp_only(baseline):
    """On by default (true_energy_config): the anytime SQP, polished or not, inside it; the
    penalty loop never gets one."""
    config = lynx_default_config(compile_code=False).with_anytime(iteration_ms=0.5).with_bank(
        size=1)
    planner = segment_planner(baseline, config.with_penalty(polish=1))
    assert isinstance(planner, GlobalSearchPlanner) and isinstance(planner, SegmentPlanner)
    assert isinstance(planner.inner, Polished)
    assert isinstance(segment_planner(baseline, config).inner, AnytimePlanner)
    penalty = segment_planner(baseline, config.with_penalty(replan_iterations=1))
    assert isinstance(penalty, PenaltyLoop)


def test_options_are_grouped_by_the_planner_they_belong_to():
    config = lynx_config(penalty=PenaltyOptions(solver="ipopt")).with_anytime(
        replan_budget_ms=20.0)
    assert config.penalty.solver == "ipopt" and config.anytime.replan_budget_ms == 20.0
    assert config.replanner == "penalty"
    with pytest.raises(ValueError, match="replanner"):
        lynx_config(replanner="newton")
