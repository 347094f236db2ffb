"""``bench delay``: the plain and the predicted law's largest proved delays, side by side."""

from __future__ import annotations

import json

import pytest

from stt_codegen.cli import main

pytestmark = pytest.mark.bench


def test_the_prediction_proves_a_longer_delay_on_every_case(capsys) -> None:
    from stt_codegen_bench.delay_bench import DELAY_SPECS, run_delay_bench
    report = run_delay_bench(DELAY_SPECS[-2:])          # the two test specs: a base, a maze
    assert [row["variant"] for row in report["rows"]] == ["look-ahead", "first-order"]
    for row in report["rows"]:
        assert row["predicted_delay_s"] > row["plain_delay_s"] > 0.0
        assert row["predicted_whole_period"] and not row["plain_whole_period"]
        assert row["check_cpu_ratio"] > 0.0


def test_the_prediction_proves_a_whole_period_on_both_cascades() -> None:
    from stt_codegen_bench.delay_bench import DELAY_SPECS, run_delay_bench
    report = run_delay_bench(DELAY_SPECS[6:8])           # second-order-s1, the U-maze cascade
    assert [row["variant"] for row in report["rows"]] == ["cascade", "cascade"]
    for row in report["rows"]:
        assert row["predicted_delay_s"] > row["plain_delay_s"] > 0.0
        assert row["predicted_whole_period"] and not row["plain_whole_period"]
        assert row["check_cpu_ratio"] > 0.0


def test_the_json_report(capsys, monkeypatch) -> None:
    import stt_codegen_bench.delay_bench as bench
    monkeypatch.setattr(bench, "DELAY_SPECS", bench.DELAY_SPECS[-1:])
    monkeypatch.setattr(bench.run_delay_bench, "__defaults__", (bench.DELAY_SPECS,))
    assert main(["bench", "delay", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert len(rows) == 1 and rows[0]["predicted_whole_period"]
