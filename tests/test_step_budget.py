"""The step's share of the period at the stated clock (embedded/budget.py): the worst
measured count over the clock, over the period; nothing invented without counts."""

from __future__ import annotations

from stt_codegen.embedded.budget import CLOCK_HZ, budget_words, step_budget


def test_the_worst_count_sets_the_share():
    report = step_budget([2000, 3360, 2500], 500.0)
    assert report["instructions_worst"] == 3360 and report["steps_measured"] == 3
    assert report["step_time_lower_s"] == 3360 / CLOCK_HZ
    assert abs(report["period_share_lower"] - 3360 / CLOCK_HZ * 500.0) < 1e-15
    words = budget_words(report)
    assert "worst 3360 instructions over 3 measured steps" in words
    assert ">= 20 us at 168 MHz" in words and ">= 1.00% of the period" in words


def test_without_counts_nothing_is_stated():
    report = step_budget([], 1000.0)
    assert report["instructions_worst"] is None and report["period_share_lower"] is None
    assert budget_words(report) == "no step measured"
