"""``stt-codegen bench tasks``: the seeded problems, the baseline's plan, the
report's arithmetic, the command's refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen_bench.arenas import arena_spec, make_arena
from stt_codegen_bench.task_baseline import plan_timed
from stt_codegen_bench.task_timing import MARGIN, departure, gap, positions
from stt_codegen.spec.loader import parse_spec
from stt_codegen.spec.motion import MovingObstacle
from stt_codegen_bench.tasks_bench import METHODS, run_tasks_bench
from stt_codegen.cli import main
from stt_codegen.errors import SpecError


def test_problems_are_seeded_and_follow_the_protocol():
    assert make_arena("tasks", 0, 3) == make_arena("tasks", 0, 3)
    assert make_arena("tasks", 0, 3) != make_arena("tasks", 1, 3)
    counts = set()
    for k in range(12):
        spec = arena_spec("tasks", 0, k)
        m = len(spec.tasks)
        counts.add(m)
        assert m in (2, 3) and spec.prescribed_time == 4.0 * (m + 1)
        assert len(spec.tasks[0].boxes) == 2 and all(len(t.boxes) == 1 for t in spec.tasks[1:])
        assert [t.window for t in spec.tasks] == [(4.0 * j + 3.5, 4.0 * j + 4.5)
                                                  for j in range(m)]
    assert counts == {2, 3}


def test_problems_draw_zero_to_four_moving_obstacles_clear_of_start_target_and_tasks():
    counts = []
    for k in range(12):
        spec = arena_spec("tasks", 0, k)
        counts.append(len(spec.moving_obstacles))
        assert len(spec.obstacles) == 4           # the arena's static boxes, unchanged
        keep = [spec.initial_set, spec.target_set] + [b for t in spec.tasks for b in t.boxes]
        for ob in spec.moving_obstacles:
            assert ob.source >= 4
            for box in keep:
                assert ob.meeting_times(box.lower, box.upper, 0.0, math.inf) == []
    assert set(counts) <= {0, 1, 2, 3, 4} and 0 in counts and max(counts) >= 3


def test_moving_obstacles_come_after_the_task_boxes_in_the_stream():
    """The moving obstacles are drawn after the tasks: the text before them is the
    problem without moving obstacles, whatever they are."""
    text = make_arena("tasks", 0, 1)
    spec = arena_spec("tasks", 0, 1)
    assert spec.moving_obstacles
    head = text[:text.index("\n[[obstacles]]\nlower", text.index("[[tasks]]"))]
    assert [t.boxes for t in parse_spec(head).tasks] == \
        [t.boxes for t in spec.tasks]


def test_baseline_plans_one_leg_per_task_and_one_to_the_target():
    spec = arena_spec("tasks", 0, 3)
    assert not spec.moving_obstacles
    plan = plan_timed(spec)
    assert plan.reason == "" and len(plan.legs) == len(spec.tasks) + 1
    assert plan.start == 0.0 and all(plan.clear)
    assert plan.switch == tuple(sum(t.window) / 2 for t in spec.tasks)
    # each leg ends where the next starts: at the chosen box's centre
    for leg, nxt, task, q in zip(plan.legs, plan.legs[1:], spec.tasks, plan.choices):
        assert np.allclose(leg[-1], task.boxes[q].center) and np.allclose(nxt[0], leg[-1])
    assert np.allclose(plan.legs[-1][-1], spec.target_set.center)


def _crossing(t_on: float) -> MovingObstacle:
    """A 0.4 m box crossing x = 2.3 downwards at 1 m/s, at y = 2 at ``t_on + 1.5`` s."""
    return MovingObstacle(source=0, dims=(0, 1), half_size=(0.2, 0.2),
                          times=(t_on, t_on + 5.0),
                          centres=((2.3, 3.5), (2.3, -1.5)), active=(t_on, t_on + 5.0),
                          motion="velocity")


def test_a_leg_waits_at_its_start_until_the_crossing_box_has_passed():
    path = np.array([[0.5, 2.0], [4.5, 2.0]])         # 4 m at 1.5 m/s: 2.67 s
    ob = _crossing(0.0)          # at y = 2 at 1.5 s, when the leg would pass x = 2.3
    depart, ok = departure(path, 0.0, 8.0, [ob])
    assert ok and depart > 0.0
    t = np.arange(0.0, 8.0, 0.01)
    assert gap(positions(path, depart, t), t, [ob]) > MARGIN
    # leaving at once would meet it
    assert gap(positions(path, 0.0, t), t, [ob]) < 0.0
    # no obstacle: no wait
    assert departure(path, 1.0, 8.0, []) == (1.0, True)


def test_a_leg_with_no_clear_departure_says_so():
    path = np.array([[0.5, 2.0], [4.5, 2.0]])
    # the box crosses while the leg must be under way (deadline 3 s): no clear departure
    depart, ok = departure(path, 0.0, 3.0, [_crossing(0.0)])
    assert not ok and 0.0 <= depart <= 3.0 - 4.0 / 1.5 + 1e-9


def test_count_and_seed_are_checked():
    with pytest.raises(SpecError) as info:
        run_tasks_bench(0, 0)
    assert info.value.field == "count"
    with pytest.raises(SpecError) as info:
        run_tasks_bench(1, -1)
    assert info.value.field == "seed"


def test_cli_refuses_a_bad_count_with_exit_2(capsys):
    assert main(["bench", "tasks", "--count", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err and "--count" in err


@pytest.mark.slow
def test_report_counts_what_the_problems_say():
    report = run_tasks_bench(2, 0)
    assert [p["index"] for p in report["problems"]] == [0, 1]
    for name in METHODS:
        rows = [p["methods"][name] for p in report["problems"]]
        assert report["summary"][name]["satisfied"] == sum(r["satisfied"] for r in rows)
        for r in rows:
            assert r["satisfied"] == (r["reason"] == "")
    assert report["stt_misses_baseline"] == [
        p["index"] for p in report["problems"]
        if p["methods"]["astar"]["satisfied"] and not p["methods"]["stt"]["satisfied"]]
    assert [p["moving"] for p in report["problems"]] == [
        len(arena_spec("tasks", 0, k).moving_obstacles) for k in (0, 1)]
    assert report["with_moving"] == sum(p["moving"] > 0 for p in report["problems"])
