"""``stt-codegen bench sensed`` (docs/sensing.md): Real-Time STT's 2-D scenario."""

from __future__ import annotations

import math

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen_bench.sensed_bench import (SCENARIO, format_sensed_report, moving_circles,
                                            run_sensed_bench)


def test_the_circles_are_seeded_and_drawn_by_the_generator():
    a = moving_circles(np.random.default_rng([0, 5, 1]), 5, 17.0)
    assert a == moving_circles(np.random.default_rng([0, 5, 1]), 5, 17.0)
    assert a != moving_circles(np.random.default_rng([0, 5, 2]), 5, 17.0)
    for ob in moving_circles(np.random.default_rng(3), 40, 17.0):
        assert 0.1 <= ob.radius <= 0.4
        assert np.linalg.norm(np.subtract(ob.start, (1.0, 1.0))) >= 2.5 + ob.radius
        rows = np.array(ob.path)
        t = np.linspace(0.0, 17.0, 3401)
        centre = ob.scripted(t)
        # inside the arena, and no faster than the generator's largest speed sqrt(2)
        assert np.all(centre >= ob.radius - 1e-9) and np.all(centre <= 10 - ob.radius + 1e-9)
        speeds = np.linalg.norm(np.diff(rows[:, 1:], axis=0), axis=1) / np.diff(rows[:, 0])
        assert np.all(speeds <= math.sqrt(2.0) + 1e-9)
    assert stt.Spec.from_dict(SCENARIO).sensing.max_obstacle_speed == math.sqrt(2.0)


@pytest.mark.slow
def test_one_episode_is_reported():
    report = run_sensed_bench(1, 0, counts=(5,))
    row = report["rows"][0]
    assert row["episodes"] == 1 and row["outside_envelope"] == 0
    assert row["collisions_certified"] == 0
    assert row["on_time"] + row["late"] + row["not_reached"] == 1
    assert "bench sensed: seed 0" in format_sensed_report(report)
