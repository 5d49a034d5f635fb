"""The realtime study's count of executions within 0.5 % of the causal reference."""

from __future__ import annotations

from harness.studies.realtime.references import compare


def test_a_safe_execution_where_the_reference_lost_the_clearance_counts_as_within():
    """Ours feasible where the reference is not: within; both infeasible: not, counted apart;
    0.4 % above: within; 0.6 % above: not; below: within."""
    out = compare([1.004, 1.006, 0.9, 2.0, None, None], [1.0, 1.0, 1.0, None, None, 1.0])
    assert out["within"] == 3  # 0.4 % above, below, and the rescued one
    assert out["feasible_where_the_reference_is_not"] == 1 and out["both_infeasible"] == 1
    assert out["excess_pct"][3] is None and out["scenarios"] == 6


def test_the_realtime_study_scores_scenarios_no_setting_was_chosen_on():
    """The study's default scenarios are not the development set its settings were chosen on,
    and a target scored on that set says so (#56 item 2)."""
    from harness.studies.realtime.measure import DEVELOPMENT_SEED, Setup
    from harness.studies.realtime.section import _scenarios

    assert Setup().seed != DEVELOPMENT_SEED
    assert "not a held-out score" in _scenarios(DEVELOPMENT_SEED)
    assert "no setting was chosen on it" in _scenarios(Setup().seed)
