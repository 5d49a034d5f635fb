"""next_run.noise_draws: the runs again with only the sensor noise drawn afresh (what
pair_against_first and least_squares_draws take their median over)."""

from __future__ import annotations

import numpy as np

from harness.identify.next_run import NOISE, noise_draws, several_runs
from harness.robots.arm import Arm


def test_a_noise_draw_keeps_the_motion_friction_and_offset_and_redraws_the_noise_alone():
    runs, _ = several_runs(Arm.of("lynxmotion"), 5, samples=1500)
    spread = runs[0].motion.tau_clean.std(axis=0)
    first, second = noise_draws(runs, np.random.default_rng(0), 2)
    for a, b, r in zip(first, second, runs, strict=True):
        assert a.motion is r.motion and np.array_equal(a.truth, r.truth)
        noise_a, noise_b = a.tau - r.truth, b.tau - r.truth
        # white noise of NOISE x the first run's clean torque std per joint, fresh each draw
        np.testing.assert_allclose(noise_a.std(axis=0), NOISE * spread, rtol=0.08)
        assert abs(np.corrcoef(noise_a.ravel(), noise_b.ravel())[0, 1]) < 0.05
        assert abs(np.corrcoef(noise_a.ravel(), (r.tau - r.truth).ravel())[0, 1]) < 0.05
