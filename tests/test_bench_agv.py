"""``stt-codegen bench agv``: the warehouse AGV's reach time against the straight-line time."""

from __future__ import annotations

import pytest

import stt_codegen as stt
from stt_codegen_bench.agv import agv_floor, format_agv_report, run_agv_bench
from stt_codegen.errors import SpecError


def test_floors_are_seeded_and_load_with_their_aisles():
    assert agv_floor(0, 3) == agv_floor(0, 3) and agv_floor(0, 4) != agv_floor(0, 3)
    assert agv_floor(1, 3) != agv_floor(0, 3)
    for k in range(20):
        doc = agv_floor(2, k, 50.0)
        racks = sorted(doc["obstacles"], key=lambda r: r["lower"][0])
        for left, right in zip(racks, racks[1:]):
            assert right["lower"][0] - left["upper"][0] >= 3.2 - 1e-9    # aisle width
        spec = stt.Spec.from_dict(doc)
        assert spec.prescribed_time == 50.0 and spec.input_bound == (1.2, 1.5)


def test_a_count_below_one_is_refused():
    with pytest.raises(SpecError) as raised:
        run_agv_bench(0, 0)
    assert raised.value.field == "count"


@pytest.mark.slow
def test_one_floor_is_certified_within_twice_the_straight_line_time():
    report = run_agv_bench(1, 0)
    floor = report["floors"][0]
    assert not floor["reason"] and floor["satisfied"]
    assert 1.0 < floor["t_c_ratio"] <= 2.0 and floor["reach_s"] <= floor["t_c"]
    assert floor["speed_per_sample"] <= floor["speed_of_peaks"]
    assert 0.0 <= floor["backing_sim"] <= floor["backing_proved"] <= floor["proved"][0]
    assert "median t_c / straight-line time" in format_agv_report(report)
