"""bench arenas: the seeded arena generator, the baselines' planners and tracker, one arena job."""

from __future__ import annotations

import hashlib
import json
import tomllib

import numpy as np
import pytest
from conftest import arena_toml

from stt_codegen_bench.arena_job import (closed_loop_failure, design_failure, run_arena)
from stt_codegen_bench.arenas import (ARENA, ARENA_KINDS, OBSTACLE_SIZE, OFFICE_RATE_HZ,
                                      START_SIZE, TARGET, arena_spec, make_arena)
from stt_codegen_bench.astar import RESOLUTION, grid_graph, plan_astar
from stt_codegen_bench.planning import MARGIN, FreeSpace
from stt_codegen_bench.report import summarize
from stt_codegen_bench.tracker import track
from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import load_spec, parse_spec

WALL_SPEC = arena_toml("wall", extra="[[obstacles]]\nlower = [2.0, 0.0]\nupper = [3.0, OBSTACLE_TOP]\n"
                                    '[plant]\nmodel = "single-integrator"\n')


def test_arenas_follow_the_protocol():
    for k in range(20):
        arena = arena_spec("paper", 7, k)
        s = arena.initial_set
        assert np.allclose(np.subtract(s.upper, s.lower), START_SIZE)
        assert ARENA.contains_box(s) and not s.meets(TARGET)
        assert np.allclose(arena.initial_state, s.center)
        assert len(arena.obstacles) == 4
        for o in (ob.box(arena.state_space) for ob in arena.obstacles):
            assert np.allclose(np.subtract(o.upper, o.lower), OBSTACLE_SIZE)
            assert ARENA.contains_box(o) and not o.meets(s) and not o.meets(TARGET)


#: sha256 (first 16 hex digits) of the spec documents (``tomllib``, as sorted JSON) of arenas
#: 0-4 of seeds 0 and 3 of each kind (polygons: ``5 + i`` of them at tolerance ``0.02 + 0.01
#: i``, ``i`` = 0, 1), computed from the six generators ``make_arena`` replaced
#: (``generate_arena``, the moving study's, ``task_problem_toml``, ``office_doc`` for both
#: bases, ``polygons_toml``): the benchmarks' figures in docs/ were measured on these arenas.
#: The offices of the former generator ran at 50 Hz, where the look-ahead's sampled-data check
#: certifies none of them; they run at ``OFFICE_RATE_HZ``, and their digest is taken with
#: that rate put back to 50 Hz: the rooms, desks and headings are the former ones.
FORMER_DIGESTS = {
    "paper": "e34af5fce296d0ce",
    "moving": "5092cb19f0ce6aee",
    "tasks": "ac5ad0e1e2bd1e89",
    "office-drive": "2e440d01ab96cb6b",
    "office-holonomic": "cd2032757bb3486a",
    "polygons": "469685e589ccbeec",
}


@pytest.mark.parametrize("kind", ARENA_KINDS)
def test_each_kind_draws_the_arenas_of_the_former_generator(kind):
    digest = hashlib.sha256()
    for seed in (0, 3):
        for i in range(2 if kind == "polygons" else 5):
            text = (make_arena(kind, seed, polygons=5 + i, tolerance=0.02 + 0.01 * i)
                    if kind == "polygons" else make_arena(kind, seed, i))
            doc = tomllib.loads(text)
            if kind.startswith("office-"):
                assert doc["controller"]["rate_hz"] == OFFICE_RATE_HZ
                doc["controller"]["rate_hz"] = 50.0
            digest.update(json.dumps(doc, sort_keys=True).encode())
            assert parse_spec(text).name in text
    assert digest.hexdigest()[:16] == FORMER_DIGESTS[kind]


def test_arenas_are_seeded():
    assert make_arena("paper", 3, 4) == make_arena("paper", 3, 4) != make_arena("paper", 4, 4)
    assert make_arena("paper", 3, 4) != make_arena("paper", 3, 5)


def test_arena_spec_files_load(tmp_path):
    path = tmp_path / "arena-0-2.toml"
    path.write_text(make_arena("paper", 0, 2))
    spec = load_spec(str(path))
    assert spec == arena_spec("paper", 0, 2) and spec.name == "arena-0-2"
    assert spec.plant_model == "single-integrator" and spec.tube.circumvent_sharpness == 0.1
    assert spec.prescribed_time == 9.0 and spec.dimension == 2


@pytest.mark.parametrize("kind,seed,index,field", [
    ("paper", -1, 0, "seed"), ("tasks", 0, -1, "index"), ("office-tank", 0, 0, "kind"),
    ("polygons", 0, 1, "index"),
])
def test_bad_kind_seed_or_index(kind, seed, index, field):
    with pytest.raises(SpecError) as exc:
        make_arena(kind, seed, index)
    assert exc.value.field == field


def test_grid_edges_join_free_neighbours_without_cutting_corners():
    space = FreeSpace.of(arena_spec("paper", 0, 1))
    graph, origin = grid_graph(space)
    nodes = set(graph.nodes)
    assert space.is_free(origin + RESOLUTION * np.array(sorted(nodes), float)).all()
    expected = set()
    for i, j in nodes:
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            b = (i + di, j + dj)
            if b in nodes and (not (di and dj) or ((i + di, j) in nodes and (i, j + dj) in nodes)):
                expected.add(frozenset([(i, j), b]))
    assert {frozenset(e) for e in graph.edges} == expected


def test_astar_path_keeps_the_margin_and_is_tracked():
    spec = arena_spec("paper", 0, 1)
    plan = plan_astar(spec)
    assert plan.reason == "" and plan.seconds > 0
    path = plan.path
    assert np.allclose(path[0], spec.initial_state) and np.allclose(path[-1], TARGET.center)
    dense = np.vstack([a + np.linspace(0, 1, 20)[:, None] * (b - a)
                       for a, b in zip(path[1:-2], path[2:-1])])
    assert FreeSpace.of(spec).is_free(dense).all()
    result = track(spec, path, seed=1)
    assert result.satisfied and result.min_obstacle_clearance > MARGIN / 2
    assert closed_loop_failure(result) == ""


def test_astar_reports_no_path_behind_a_wall():
    spec = parse_spec(WALL_SPEC.replace("OBSTACLE_TOP", "5.0"))
    plan = plan_astar(spec)
    assert plan.path is None and plan.reason == "no path found"


def test_tracker_through_an_obstacle_collides():
    spec = parse_spec(WALL_SPEC.replace("OBSTACLE_TOP", "4.0"))
    straight = np.array([spec.initial_state, spec.target_set.center])
    result = track(spec, straight, seed=0)
    assert not result.satisfied and closed_loop_failure(result) == "collision"


@pytest.mark.parametrize("message,category", [
    ("obstacle 2 comes within 0.1 of the target box eta +- d_T: shrink target.half_width",
     "design: obstacle next to target"),
    ("obstacle 1 cannot be circumvented: no dimension leaves room of delta_b = 0.2 beside it",
     "design: no room beside obstacle"),
    ("no choice of circumvent dimension and side passes the tube check (obstacle 0: a tube "
     "bound moves 3.57 tube widths in one sampling period at t = 1 s (limit 0.25))",
     "design: bound too fast for the sampling rate"),
    ("no choice of circumvent dimension and side passes the tube check (obstacle 3: avoids "
     "obstacle 1 fails: margin -0.1 at t = 2; obstacle 4: non-empty fails: x)",
     "design: avoids obstacle"),
    ("no choice of circumvent dimension and side passes the tube check (obstacle 0: initial "
     "state inside fails: x(0) is 0.01 from the tube's boundary)",
     "design: initial state inside"),
    ("the reach tube fails its check: inside target after t_c fails: margin -1",
     "design: inside target after t_c"),
    ("something new", "design: other"),
])
def test_design_failure_categories(message, category):
    assert design_failure(message) == category


def test_summary_statistics():
    outcomes = [{"success": True, "seconds": float(s), "reason": ""} for s in range(1, 20)]
    outcomes += [{"success": False, "seconds": 100.0, "reason": "collision"}] * 2
    outcomes += [{"success": False, "seconds": 0.5, "reason": "no path found"}]
    s = summarize(outcomes)
    assert s["runs"] == 22 and s["successes"] == 19
    assert s["success_rate"] == pytest.approx(19 / 22)
    assert s["time_median_s"] == pytest.approx(np.median([o["seconds"] for o in outcomes]))
    assert s["time_median_s"] <= s["time_p95_s"] <= 100.0
    assert list(s["failures"].items()) == [("collision", 2), ("no path found", 1)]
    assert s["effort_runs"] == 0 and s["peak_u_median"] is None   # none carries peak_u
    assert s["max_abs_e_median"] is None and s["max_abs_e_max"] is None  # no tube reported


def test_summary_of_the_normalized_error_counts_satisfied_runs_only():
    outcomes = [{"success": True, "seconds": 1.0, "reason": "", "max_abs_e": e}
                for e in (0.1, 0.3, 0.2)]
    outcomes += [{"success": False, "seconds": 1.0, "reason": "collision", "max_abs_e": 0.99}]
    s = summarize(outcomes)
    assert s["max_abs_e_median"] == pytest.approx(0.2) and s["max_abs_e_max"] == 0.3


def test_effort_statistics_are_over_the_satisfied_runs():
    outcomes = [{"success": True, "seconds": 1.0, "reason": "", "peak_u": float(k),
                 "effort": 10.0 * k} for k in range(1, 21)]
    outcomes += [{"success": False, "seconds": 1.0, "reason": "collision", "peak_u": 1e6,
                  "effort": 1e9}]
    outcomes += [{"success": False, "seconds": 1.0, "reason": "no path found",
                  "peak_u": None, "effort": None}]
    s = summarize(outcomes)
    assert s["effort_runs"] == 20
    assert s["peak_u_median"] == pytest.approx(10.5)
    assert s["peak_u_p95"] == pytest.approx(np.percentile(np.arange(1, 21), 95))
    assert s["effort_median"] == pytest.approx(105.0)
    assert s["effort_p95"] == pytest.approx(10 * np.percentile(np.arange(1, 21), 95))


@pytest.mark.bench
def test_one_arena_job(tmp_path, monkeypatch):
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    result = run_arena(0, 1, ("stt", "astar"))
    assert result["name"] == "arena-0-1" and set(result["methods"]) == {"stt", "astar"}
    for outcome in result["methods"].values():
        assert set(outcome) == {"success", "seconds", "reason", "reach_time", "clearance",
                                "peak_u", "effort", "max_abs_e"}
        assert outcome["seconds"] > 0 and outcome["success"] == (outcome["reason"] == "")
        if outcome["success"]:
            assert 0 < outcome["reach_time"] <= 9.0 and outcome["clearance"] > 0
            # from x(0) = (0.40, 1.76) into [4.5, 5]^2 by t_c = 9 s with |w| <= 0.1 sqrt(2):
            # |integral u dt| >= 4.93 - 1.27 m, so integral |u|^2 dt >= 3.66^2 / 9 s
            # (Cauchy-Schwarz) and max_i |u_i| >= 3.66 / (9 sqrt(2)) m/s
            assert outcome["peak_u"] >= 0.28 and outcome["effort"] >= 1.48
    # the tube controller's state keeps off its tube's wall; a tracker has no tube
    assert 0.0 <= result["methods"]["stt"]["max_abs_e"] <= 0.7
    assert result["methods"]["astar"]["max_abs_e"] is None
