"""``stt-codegen bench fleet`` (docs/fleets.md): seeded warehouse floors for fleets."""

from __future__ import annotations

import pytest

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen_bench.fleet_bench import fleet_floor, format_fleet_report, run_fleet_bench


@pytest.mark.parametrize("robots", [1, 8, 32])
def test_floors_are_seeded_fleets_with_distinct_docks(robots):
    assert fleet_floor(0, 3, robots) == fleet_floor(0, 3, robots)
    assert fleet_floor(0, 4, robots) != fleet_floor(0, 3, robots)
    assert fleet_floor(1, 3, robots) != fleet_floor(0, 3, robots)
    doc = fleet_floor(2, 0, robots)
    fleet = stt.FleetSpec.from_dict(doc)
    assert len(fleet.robots) == robots
    docks = [tuple(r["initial"]["lower"]) for r in doc["robots"]]
    docks += [tuple(r["target"]["lower"]) for r in doc["robots"]]
    assert len(set(docks)) == 2 * robots
    kinds = [r.spec.variant for r in fleet.robots]
    assert kinds.count("look-ahead") == robots // 4


def test_too_many_robots_or_floors_below_one_are_refused():
    with pytest.raises(SpecError) as raised:
        fleet_floor(0, 0, 0)
    assert raised.value.field == "robots"
    with pytest.raises(SpecError) as raised:
        run_fleet_bench(0, 0)
    assert raised.value.field == "count"
    with pytest.raises(SpecError) as raised:
        run_fleet_bench(1, 0, workers=0)
    assert raised.value.field == "workers"
    with pytest.raises(SpecError) as raised:
        run_fleet_bench(1, 0, first=-1)
    assert raised.value.field == "first"


@pytest.mark.slow
def test_floors_in_parallel_processes_are_the_floors_in_turn():
    # the same floors, the same verdicts and margins, whichever process designs them
    apart = run_fleet_bench(2, 3, robots=2, workers=2)
    turn = run_fleet_bench(2, 3, robots=2)
    keys = ("index", "certified", "margin", "reordered", "astar_certified", "solo_failed")
    assert [[f[k] for k in keys] for f in apart["floors"]] == \
        [[f[k] for k in keys] for f in turn["floors"]]
    assert all(f["fleet_s"] > 0 for f in apart["floors"])
    # every robot of a certified floor is placed once, its near robots among those placed
    for f in turn["floors"]:
        if f["certified"]:
            assert len(f["placements"]) == 2
            assert [p[0] for p in f["placements"]] == [0, 1]
            assert all(0 <= near <= placed and cpu >= 0 for placed, near, cpu in f["placements"])
    assert sum(b["robots"] for b in turn["by_near"]) == sum(
        len(f.get("placements", ())) for f in turn["floors"])
    assert "placement CPU by the placed robots near its way" in format_fleet_report(turn)
    # a floor of the run designed again on its own: the same row
    (again,) = run_fleet_bench(1, 3, robots=2, first=1)["floors"]
    assert [again[k] for k in keys] == [turn["floors"][1][k] for k in keys]


@pytest.mark.slow
def test_a_small_floor_runs_and_reports():
    report = run_fleet_bench(1, 0, robots=2, simulate=True)
    (floor,) = report["floors"]
    assert floor["fleet_s"] > 0 and floor["solo_s"] > 0
    if floor["certified"]:
        assert floor["margin"] > 0 and floor["closest"] >= floor["margin"] - 1e-9
    text = format_fleet_report(report)
    assert "certified" in text and "robots alone" in text
