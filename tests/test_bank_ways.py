"""harness.studies.bank_ways' count of the bank against the causal reference, on rows made
by hand: within 0.5 % or below counts, above does not, a refusal does not, and a scenario
whose reference is infeasible is reported apart."""

from __future__ import annotations

from harness.studies.bank_ways import lines


def _row(i: int, energy: float | None, reference: float, feasible: bool = True) -> dict:
    bank = {} if energy is None else {"energy": energy, "min_clearance": 0.0805,
                                      "threshold": 0.08}
    return {"scenario": i, "bank": bank, "reference_J": reference,
            "reference_feasible": feasible,
            "excess_pct": None if energy is None else 100 * (energy / reference - 1)}


def test_the_count_is_of_the_feasible_references_within_half_a_percent_or_below():
    rows = [_row(0, 1.004, 1.0), _row(1, 1.006, 1.0), _row(2, 0.5, 1.0), _row(3, None, 1.0),
            _row(4, 0.9, 1.0, feasible=False)]
    text = lines(rows)
    assert text[-1].strip() == ("within 0.5 % of the causal reference or below: 2 of 4 whose "
                                "reference is feasible (1 apart)")
    assert "| 0 | 1.0040 | +0.5 | 1.0000 | yes | +0.40 % |" in text
    assert "| 3 | refused | - | 1.0000 | yes | - |" in text
