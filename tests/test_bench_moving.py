"""Random moving obstacles for benchmarks (stt_codegen_bench/moving.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen_bench.arenas import arena_spec, make_arena
from stt_codegen_bench.moving import random_moving_obstacles
from stt_codegen.spec.loader import Box


def _doc(arena_spec_toml: str) -> dict:
    import tomllib
    return tomllib.loads(arena_spec_toml)


@pytest.mark.parametrize("index", range(6))
def test_entries_load_and_keep_clear_of_start_and_target(index):
    spec = arena_spec("paper", 0, index)
    keep = Box((2.0, 2.0), (2.4, 2.4))
    entries = random_moving_obstacles(np.random.default_rng([7, index]), spec, count=4,
                                      keep_clear=[keep])
    assert 1 <= len(entries) <= 4
    doc = _doc(make_arena("paper", 0, index))
    doc["obstacles"] = doc.get("obstacles", []) + entries
    loaded = stt.Spec.from_dict(doc)
    assert len(loaded.moving_obstacles) == len(entries)
    for ob in loaded.moving_obstacles:
        for box in (spec.initial_set, spec.target_set, keep):
            assert ob.meeting_times(box.lower, box.upper, 0.0, math.inf) == []


def test_same_generator_same_entries_and_counts_in_range():
    spec = arena_spec("paper", 0, 0)
    a = random_moving_obstacles(np.random.default_rng(3), spec)
    b = random_moving_obstacles(np.random.default_rng(3), spec)
    assert a == b
    counts = {len(random_moving_obstacles(np.random.default_rng(s), spec)) for s in range(40)}
    assert counts <= set(range(5)) and {0, 4} <= counts
    kinds = {next(k for k in ("velocity", "path", "active") if k in e)
             for s in range(10) for e in random_moving_obstacles(np.random.default_rng(s), spec, 4)}
    assert kinds == {"velocity", "path", "active"}


def test_bad_count_is_a_spec_error():
    spec = arena_spec("paper", 0, 0)
    with pytest.raises(stt.SpecError) as err:
        random_moving_obstacles(np.random.default_rng(0), spec, count=5)
    assert err.value.field == "count"


@pytest.mark.slow
def test_the_study_reports_both_designs():
    from stt_codegen_bench.moving_study import study_moving
    result = study_moving(3, 0)
    assert result["arenas"] == 3 and result["moving_obstacles"] >= 1
    for name in ("stt", "swept_only"):
        r = result[name]
        assert sum(r["how"].values()) == 3
        assert r["satisfied"] <= r["designed"] <= 3
    # STT avoids in space-time what the swept baseline must go around (or cannot)
    assert result["stt"]["designed"] >= result["swept_only"]["designed"]
