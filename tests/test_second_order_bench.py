"""The second-order study and the double-integrator arenas bench."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from stt_codegen_bench.second_order_study import (DRAG_MAX, format_second_order_report,
                                                  random_parameters, run_second_order_study)
from stt_codegen.errors import SpecError

needs_cc = pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                              reason="no C compiler (install gcc or clang)")


def test_random_plants_stay_within_the_declared_bounds() -> None:
    rng = np.random.default_rng(0)
    for _ in range(500):
        mass, drag, gravity = random_parameters("quadrotor", (0.625, 1.25), rng)
        assert 0.8 <= mass <= 1.6 and 0 <= drag <= DRAG_MAX and gravity == 9.81
        (mass,) = random_parameters("double-integrator", (0.8, 1.25), rng)
        assert 0.8 <= mass <= 1.25
    with pytest.raises(SpecError):
        random_parameters("two-link-arm", (1.0, 1.0), rng)
    wide = [random_parameters("double-integrator", (0.8, 1.25), rng, spread=4.0)[0]
            for _ in range(500)]
    assert 1 / 5.0 <= min(wide) and max(wide) <= 1 / 0.2 and max(wide) > 1.25


def test_study_refuses_a_first_order_spec_and_a_bad_count() -> None:
    with pytest.raises(SpecError) as info:
        run_second_order_study("omnirobot-s1", 1)
    assert info.value.field == "plant.model"
    with pytest.raises(SpecError):
        run_second_order_study("second-order-s1", 0)
    with pytest.raises(SpecError) as info:
        run_second_order_study("second-order-s1", 1, spread=0.5)
    assert info.value.field == "spread"


@pytest.mark.slow
@needs_cc
def test_small_study_counts_what_it_ran() -> None:
    report = run_second_order_study("second-order-s1", 3, seed=1)
    assert report["count"] == 3 and 0 <= report["satisfied"] <= 3
    assert len(report["failures"]) >= 3 - min(report["satisfied"], report["in_both_tubes"])
    for failure in report["failures"]:
        assert not (failure["satisfied"] and failure["stayed_in_tube"]
                    and failure["stayed_in_velocity_tube"])
    assert "random plants" in format_second_order_report(report)


@pytest.mark.slow
@needs_cc
def test_double_integrator_arena_runs_both_methods() -> None:
    from stt_codegen_bench.second_order_arenas import run_arena_double_integrator
    out = run_arena_double_integrator(0, 0)
    assert out["stt"]["satisfied"] and out["stt"]["in_tube"]
    times = out["design_cpu"]
    assert times["first_order"] > 0.0 and times["cascade"] > 0.0 and times["cascade_designed"]
    assert out["astar"]["satisfied"]
    assert "in_tube" not in out["astar"]          # a tracker has no tube to stay in


@pytest.mark.slow
@needs_cc
def test_bench_arenas_dispatches_on_the_plant(capsys) -> None:
    from stt_codegen.cli import main
    assert main(["bench", "arenas", "--plant", "double-integrator", "--count", "1"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("double integrator, 1 arenas, seed 0: satisfied STT cascade")
    assert "median ratio cascade / first order" in out
