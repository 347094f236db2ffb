"""bench covering and bench alpha: the reports' structure and invariants (never speed)."""

from __future__ import annotations

import json

import pytest

from stt_codegen_bench.alpha import RATE_FACTORS, format_alpha_report
from stt_codegen_bench.arenas import make_arena
from stt_codegen_bench.covering import format_covering_report
from stt_codegen.cli import main
from stt_codegen.spec.loader import parse_spec
from stt_codegen.tube.parameters import NEWTON_ITERATIONS


def test_polygons_spec_is_seeded():
    def polygons_toml(seed, count, tolerance):
        return make_arena("polygons", seed, polygons=count, tolerance=tolerance)
    spec = parse_spec(polygons_toml(seed=3, count=4, tolerance=0.05))
    assert spec.name == "polygons-3-4" and len(spec.unsafe_sets) == 4
    assert {u.kind for u in spec.unsafe_sets} == {"polytope"}
    assert polygons_toml(3, 4, 0.05) == polygons_toml(3, 4, 0.05) != polygons_toml(4, 4, 0.05)


@pytest.mark.bench
def test_covering_report(capsys):
    assert main(["bench", "covering", "--count", "6", "--seed", "1", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["spec"], report["polygons"], report["tolerance"]) == ("polygons-1-6", 6, 0.02)
    assert report["boxes"] >= 6 and report["designed"] and report["certified"]
    assert report["reason"] == "" and report["method"] in ("paper", "via")
    for step in ("covering", "design"):
        assert report[step]["cpu_s"] > 0 and report[step]["wall_s"] > 0
    text = format_covering_report(report)
    assert "6 polygons" in text and "covering (parse_spec)" in text and "machine:" in text


@pytest.mark.bench
def test_alpha_report(capsys):
    assert main(["bench", "alpha", "omnirobot-s1", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    newton = report["newton"]
    assert [r["iterations"] for r in newton] == list(range(1, NEWTON_ITERATIONS + 2))
    deployed = next(r for r in newton if r["deployed"])
    assert deployed["iterations"] == NEWTON_ITERATIONS
    assert deployed["max_relative_error"] <= 1e-12 < newton[NEWTON_ITERATIONS - 2]["max_relative_error"]
    rates = report["convergence"]["rates"]
    assert [r["rate_hz"] for r in rates] == [1000.0 * f for f in RATE_FACTORS]
    # backward Euler is first order: each halving of dt about halves the error
    assert all(1.8 <= r["ratio_to_previous"] <= 2.2 for r in rates[1:])
    assert report["convergence"]["richardson_max_abs_error"] < 0.1 * rates[0]["max_abs_error"]
    text = format_alpha_report(report)
    assert "(deployed)" in text and "halving dt" in text
