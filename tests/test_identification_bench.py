"""Bench section bookkeeping: one independent noise draw per level, the 5 % draw is the
default data, and the robustness summary agrees with its per-draw numbers."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from harness.datagen import generate
from harness.sections import identification as section


@pytest.fixture(scope="module")
def ctx():
    return section.context()


def test_five_percent_draw_is_the_default_data(ctx):
    d = section.noisy(ctx["clean"], 0.05, section.NOISE_SEEDS[0.05])
    with threadpool_limits(limits=1, user_api="blas"):  # generate's small SVDs: one thread is faster
        default = generate("lynxmotion", 4000, 0.05, seed=0)
    np.testing.assert_array_equal(d.tau, default.tau)


def test_levels_use_independent_draws(ctx):
    clean = ctx["clean"].tau_clean
    unit = {lv: ((section.noisy(ctx["clean"], lv, section.NOISE_SEEDS[lv]).tau - clean)
                 / (lv * clean.std(axis=0))).ravel() for lv in (0.01, 0.05, 0.10)}
    for a, b in ((0.01, 0.05), (0.01, 0.10), (0.05, 0.10)):
        assert abs(np.corrcoef(unit[a], unit[b])[0, 1]) < 0.05  # not one draw rescaled
    assert len(set(section.ROBUST_SEEDS)) == len(section.ROBUST_SEEDS)
    assert len(section.QUICK_ROBUST_SEEDS) >= 10


def test_robustness_summary_matches_its_draws(ctx):
    rob = section.robustness(ctx, seeds=(1, 3001, 4001))  # 3001, 4001: null general atoms at t ~ 2-3
    default = section.compare(0.05, ctx, with_pysindy=False)
    np.testing.assert_allclose(rob["oracle"][0], default["oracle"])
    for label, _, _ in section.METHODS:
        m = rob["methods"][label]
        rel, ratio = np.array(m["rel"]), np.array(m["rel"]) / np.array(rob["oracle"])
        np.testing.assert_allclose(rel[0], [j["rel"] for j in default[label]["joints"]])
        np.testing.assert_allclose(m["ratio_worst"], ratio.max(axis=0))
        assert np.all(np.array(m["ratio_median"]) <= np.array(m["ratio_worst"]))
        assert m["draws_within_limit"] == int(np.sum(np.all(ratio <= section.RATIO_LIMIT, axis=1)))
    # both coupled fits keep every true term on these draws and nothing else: the general
    # atoms' null atoms fall to the significance bound, leaving the symmetric fit's atoms
    for label in ("coupled", "coupled general"):
        assert min(rob["methods"][label]["recall_min"]) == 1.0
        assert min(rob["methods"][label]["precision_min"]) == 1.0
    general, symmetric = rob["methods"]["coupled general"], rob["methods"]["coupled"]
    assert [set(a) for a in general["atoms"]] == [set(a) for a in symmetric["atoms"]]
