"""The prior-metric study's draws (issue #56 item 3) are fresh: apart from every seed a bench
section, the TIE study or the excitation's fresh draws score or chose on."""

from __future__ import annotations


def test_prior_metric_seeds_are_apart_from_every_scored_or_chosen_seed():
    from harness.bench.identification import FRESH_SEED, LEVELS, NEXT_RUNS
    from harness.identify.excitation import FRESH_DRAWS
    from harness.identify.excitation import FRESH_JUDGE as EXCITE_JUDGE
    from harness.identify.prior_metric import JUDGE, SEEDS
    from harness.identify.prior_tie import CHOOSE, RESCORE

    tie = {s for d in (CHOOSE, RESCORE) for seeds in d["seeds"].values() for s in seeds}
    used = ({FRESH_SEED, EXCITE_JUDGE, CHOOSE["judge"], RESCORE["judge"]} | set(NEXT_RUNS) | tie
            | set(FRESH_DRAWS) | {s for seeds in LEVELS.values() for s in seeds})
    assert not (set(SEEDS) | {JUDGE}) & used
