"""The default identification on data made outside its own path (issue #56 item 15):
harness.identify.outside_default, the study `outside_default` and docs/identification.md."""

from __future__ import annotations

import pytest

from harness.identify.outside_default import DEV_JUDGE, DEV_SEEDS, FRESH_JUDGE, FRESH_SEEDS
from harness.robots.arm import Arm

# measured on development draw 9101 (judge 9150), the same at every commit from 2f74260 to
# 9be74ce: worst joint / oracle per family and noise
MEASURED_WORST = {"multisine 0.05": 0.972, "multisine 0.1": 0.931, "fourier 0.05": 1.213,
                  "fourier 0.1": 0.902}


def test_fresh_seeds_are_apart_from_development_and_every_scored_seed():
    from harness.bench.identification import FRESH_SEED, LEVELS, NEXT_RUNS
    from harness.identify.excitation import FRESH_DRAWS
    from harness.identify.excitation import FRESH_JUDGE as EXCITE_JUDGE

    used = (set(DEV_SEEDS) | {DEV_JUDGE, FRESH_SEED, EXCITE_JUDGE} | set(NEXT_RUNS)
            | set(FRESH_DRAWS) | {s for seeds in LEVELS.values() for s in seeds})
    assert not (set(FRESH_SEEDS) | {FRESH_JUDGE}) & used


@pytest.mark.slow
def test_the_default_identification_on_outside_data_is_no_worse_than_measured():
    """A default that fits outside data worse (the paper's per-joint regression, the
    shrinkage dropped, ...) fails here: 5 % above the figures measured at every commit."""
    from harness.identify.outside_default import outside_default

    r = outside_default(Arm.of("lynxmotion"), DEV_SEEDS[:1])
    worst = {key: s["worst"] for key, s in r["summary"].items()}
    assert worst.keys() == MEASURED_WORST.keys()
    for key, figure in MEASURED_WORST.items():
        assert worst[key] <= 1.05 * figure, (key, worst[key], figure)
    assert all(s["median"] <= 1.1 for s in r["summary"].values())
