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
