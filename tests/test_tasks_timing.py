"""Free timing of timed tasks (docs/tasks.md, "Timing and order"): overlapping windows, the
design's visit times and order, stay tasks with a duration; each proved as stated (a
tube that meets a stay duration only with a gap between two samples, or for less than its
duration, is rejected) and judged as stated on a run."""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from itertools import permutations
from pathlib import Path

import numpy as np
import pytest
from test_tasks import _centred, _inside_at_samples, _tube_with, arena, margins, spec_of

from stt_codegen.design.certificate import certify_tube
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.search import base_design, check_tube, design_tube
from stt_codegen.design.tasks import EXACT_ORDERS, task_schedule, visit_orders
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.runtime.tasks import judge_task, until_met
from stt_codegen.spec.loader import Spec, load_spec
from stt_codegen.tube import reference
from stt_codegen.design.via import ACCELERATION_TIMING
from stt_codegen.tube.parameters import CRUISE, SMOOTHSTEP

A = {"lower": [3.4, 0.6], "upper": [4.0, 1.2]}       # bottom right
B = {"lower": [0.6, 3.4], "upper": [1.2, 4.0]}       # top left
C = {"lower": [3.4, 3.4], "upper": [4.0, 4.0]}       # near the target


def reach(box: dict, window: list) -> dict:
    return {"kind": "reach", "window": window, **box}


def _travel(spec, order):
    from stt_codegen.design.tasks import _travel as travel
    return travel(spec, base_design(spec), order)


def test_overlapping_windows_listed_out_of_window_order_are_timed_by_the_design():
    """Two reach tasks with the same wide window, listed C then A: visited in the listed
    order, C's hold before A's, both inside their windows and certified."""
    tasks = [reach(C, [2.0, 12.0]), reach(A, [2.0, 12.0])]
    spec = spec_of(arena(2, tasks, obstacles=[], t_c=15.0))
    design = design_tube(spec)
    plan = design.task_plan
    assert plan.order == (0, 1)
    (c0, c1), (a0, a1) = plan.holds
    assert 2.0 <= c0 < c1 <= a0 < a1 <= 12.0
    for task in spec.tasks:
        m = margins(design.certificate)[task.name]
        assert m.passed and task.window[0] <= m.time <= task.window[1]
    doc = design.to_json()["tasks"]
    assert [(t["visit"], t["hold"]) for t in doc] == [(1, [c0, c1]), (2, [a0, a1])]


def test_order_any_visits_the_tasks_on_the_shortest_estimated_path():
    """Listed C, A, B (a zig-zag across the arena); with order = "any" the design visits
    them on the shortest estimated path among all orders, and certifies every task."""
    tasks = [reach(C, [1.0, 13.0]), reach(A, [1.0, 13.0]), reach(B, [1.0, 13.0])]
    listed = spec_of(arena(2, tasks, obstacles=[], t_c=15.0))
    spec = spec_of({**arena(2, tasks, obstacles=[], t_c=15.0), "task_order": {"order": "any"}})
    orders = visit_orders(spec, base_design(spec))
    assert visit_orders(listed, base_design(listed)) == [(0, 1, 2)]
    best = min(_travel(spec, o) for o in permutations(range(3)))
    assert _travel(spec, orders[0]) == best < _travel(spec, (0, 1, 2))
    design = design_tube(spec)
    assert design.task_plan.order == orders[0] and design.certificate.passed
    holds = [design.task_plan.holds[k] for k in design.task_plan.order]
    assert all(a[1] <= b[0] for a, b in zip(holds, holds[1:]))


def test_order_any_beyond_the_exact_search_takes_a_feasible_heuristic_order():
    boxes = [{"lower": [x, y], "upper": [x + 0.5, y + 0.5]}
             for x, y in ((0.5, 3.5), (3.5, 0.5), (1.5, 1.0), (3.5, 3.5), (1.0, 2.0),
                          (3.0, 2.0), (2.0, 4.2))]
    assert len(boxes) > EXACT_ORDERS
    tasks = [reach(b, [1.0, 28.0]) for b in boxes]
    spec = spec_of({**arena(2, tasks, obstacles=[], t_c=30.0), "task_order": {"order": "any"}})
    (order,) = visit_orders(spec, base_design(spec))
    assert sorted(order) == list(range(len(boxes)))
    assert _travel(spec, order) < _travel(spec, tuple(range(len(boxes))))
    task_schedule(spec, base_design(spec), order, (0,) * len(boxes))   # a timing exists


def test_windows_that_admit_no_timing_name_the_task_and_its_window():
    """Listed C (window [6, 7]) then A (window [1, 2]): no timing in the listed order; the
    error names the task that cannot be met and its window. Any order meets them."""
    tasks = [reach(C, [6.0, 7.0]), reach(A, [1.0, 2.0])]
    with pytest.raises(DesignError) as info:
        design_tube(spec_of(arena(2, tasks, obstacles=[], t_c=12.0)))
    assert info.value.kind is FailureKind.TASK
    assert "task T2 (reach, window [1, 2] s)" in str(info.value), str(info.value)
    spec = spec_of({**arena(2, tasks, obstacles=[], t_c=12.0), "task_order": {"order": "any"}})
    design = design_tube(spec)
    assert design.task_plan.order == (1, 0) and design.certificate.passed


def _leg_speeds(design) -> list[float]:
    """Per leg (between two holds, and to the target): its via boxes' centres' path length
    (largest coordinate move per segment) over the leg's duration."""
    edges = [0.0] + [t for k in design.task_plan.order for t in design.task_plan.holds[k]]
    edges.append(design.spec.prescribed_time)
    speeds = []
    for t0, t1 in zip(edges[::2], edges[1::2]):
        length = sum(max(abs(0.5 * (b + d) - 0.5 * (a + c)) for a, c, b, d in
                         zip(s.lower_from, s.upper_from, s.lower_to, s.upper_to))
                     for s in design.tube.segments if t0 <= s.start and s.end <= t1)
        speeds.append(length / (t1 - t0))
    return speeds


def test_free_timing_gives_each_leg_time_in_proportion_to_its_via_path():
    """Free windows, the first leg around the obstacle: every leg moves at the same speed
    (its via path's length, largest coordinate moves, over its time), so no leg asks more
    of an input than the others, and the holds' spare time is all used."""
    tasks = [reach(C, [1.0, 13.0]), reach(B, [1.0, 13.0])]
    design = design_tube(spec_of(arena(2, tasks, t_c=15.0)))
    assert design.certificate.passed and design.task_plan.order == (0, 1)
    first = [s for s in design.tube.segments if s.end <= design.task_plan.holds[0][0]]
    assert len(first) >= 2                     # around the obstacle: via boxes
    speeds = _leg_speeds(design)
    assert len(speeds) == 3 and max(speeds) - min(speeds) <= 1e-9 * max(speeds), speeds
    assert {s.profile for s in design.tube.segments} == {CRUISE}


def test_timed_for_the_acceleration_every_move_takes_time_by_its_square_root():
    """The same spec timed for a force input (``via_timing = "acceleration"``): every move
    (in every leg) lasts in proportion to the square root of its length, so each asks the
    same peak acceleration of a smooth step; the legs are smooth steps, not cruises."""
    spec = spec_of(arena(2, [reach(C, [1.0, 13.0]), reach(B, [1.0, 13.0])], t_c=15.0))
    spec = dataclasses.replace(spec, tube=dataclasses.replace(
        spec.tube, method="via", via_timing=ACCELERATION_TIMING))
    design = design_tube(spec)
    assert design.certificate.passed and design.task_plan.order == (0, 1)
    moves = [(s.end - s.start, max(abs(0.5 * (b + d) - 0.5 * (a + c)) for a, c, b, d in
                                   zip(s.lower_from, s.upper_from, s.lower_to, s.upper_to)))
             for s in design.tube.segments]
    moves = [(duration, length) for duration, length in moves if length > 0.0]
    assert len(moves) >= 4                       # two legs' moves around the obstacle, ...
    ratios = [duration / math.sqrt(length) for duration, length in moves]
    assert max(ratios) - min(ratios) <= 1e-9 * max(ratios), ratios
    lengths = [length for _, length in moves]
    assert max(lengths) > 1.5 * min(lengths)     # so the square root differs from a ratio
    assert {s.profile for s in design.tube.segments
            if s.lower_from != s.lower_to} == {SMOOTHSTEP}


# --------------------------------------------------------------------------- stay duration


def test_stay_with_a_duration_is_held_for_it_inside_the_window_and_certified():
    tasks = [{"kind": "stay", "window": [2.0, 9.0], "duration": 1.5, **B},
             reach(A, [3.0, 11.0])]
    spec = spec_of(arena(2, tasks, obstacles=[], t_c=14.0))
    design = design_tube(spec)
    m = margins(design.certificate)["task T1 stay"]
    assert m.passed and m.margin > 0.01 and "at least 1.5 s" in m.detail
    a, b = design.task_plan.holds[0]
    assert 2.0 <= a and b <= 9.0 and b - a >= 1.5


def _stay_spec(duration: float):
    tasks = [{"kind": "stay", "window": [3.0, 8.0], "duration": duration,
              "lower": [2.0, 2.0], "upper": [3.0, 3.0]}]
    return spec_of(arena(2, tasks, obstacles=[]))


def test_stay_duration_met_only_with_a_gap_between_two_samples_is_rejected():
    """Inside the box at every sample from 4.0 to 6.0 s (2 s, the duration 1.5 s), but out
    of it between two samples at 5.0 s, so each run without the gap is 1 s: rejected. The
    same tube without the gap passes."""
    spec = _stay_spec(1.5)
    dt = 1.0 / spec.rate_hz
    inside, out = _centred((2.5, 2.5)), _centred((3.6, 2.5))
    k = 5000
    blip = [(k * dt, *inside), ((k + 0.5) * dt, *out), ((k + 1) * dt, *inside)]
    pieces = [(3.8, *out), (3.9, *inside)] + blip + [(6.1, *inside), (6.2, *out), (9.0, *out)]
    tube = _tube_with(spec, pieces)
    ok, t = _inside_at_samples(tube, spec.tasks[0], 3.9, 6.1)
    assert ok.all()                                           # in at every sample
    m = margins(certify_tube(tube, spec))["task T1 stay"]
    assert not m.passed, m
    steady = _tube_with(spec, [(3.8, *out), (3.9, *inside), (6.1, *inside), (6.2, *out),
                               (9.0, *out)])
    assert margins(certify_tube(steady, spec))["task T1 stay"].passed


def test_stay_shorter_than_its_duration_is_rejected():
    """Inside for about 1.3 s of the window: passes a duration of 1 s, not one of 1.5 s."""
    inside, out = _centred((2.5, 2.5)), _centred((3.6, 2.5))
    pieces = [(4.3, *out), (4.4, *inside), (5.6, *inside), (5.7, *out), (9.0, *out)]
    for duration, passed in ((1.0, True), (1.5, False)):
        spec = _stay_spec(duration)
        m = margins(certify_tube(_tube_with(spec, pieces), spec))["task T1 stay"]
        assert m.passed is passed, m


def test_reach_met_early_in_a_wide_window_is_certified_as_stated():
    """The certificate proves a reach task over some interval of its window, wherever it
    lies (here [3.5, 4.0] s of [3, 10] s), not only at the middle; outside it, not."""
    tasks = [{"kind": "reach", "window": [3.0, 10.0], "lower": [2.0, 2.0],
              "upper": [3.0, 3.0]}]
    spec = spec_of(arena(2, tasks, obstacles=[]))
    inside, out = _centred((2.5, 2.5)), _centred((3.6, 2.5))
    early = _tube_with(spec, [(2.0, *out), (3.5, *inside), (4.0, *inside), (5.0, *out),
                              (9.0, *out)])
    assert margins(certify_tube(early, spec))["task T1 reach"].passed
    late = _tube_with(spec, [(10.1, *out), (10.2, *inside), (11.0, *inside), (12.0, *out)])
    assert not margins(certify_tube(late, spec))["task T1 reach"].passed


def test_the_run_judge_reads_a_stay_duration_as_stated():
    spec = _stay_spec(1.0)
    t = np.linspace(0.0, 10.0, 10001)
    for start, end, met in ((4.0, 5.1, True), (4.0, 4.9, False), (7.5, 8.6, False)):
        x = np.where(((t >= start) & (t <= end))[:, None], [2.5, 2.5], [3.6, 2.5])
        outcome = judge_task(spec.tasks[0], t, x)
        assert outcome.met is met, (start, end, outcome)
        if met:
            assert outcome.time == pytest.approx(start) and outcome.margin == pytest.approx(0.5)


# --------------------------------------------------------------------------- or-goals


def test_stay_any_of_switching_boxes_mid_window_is_rejected():
    """Two adjacent stay boxes ([2, 3] x [2, 3] and [3, 4] x [2, 3]): a tube in the first
    for the window's first half and in the second for its second half is always in one
    of them, but in no one box over the window: rejected. Held in the second: passes,
    and the certificate names the box."""
    tasks = [{"kind": "stay", "window": [4.0, 6.0],
              "any_of": [{"lower": [2.0, 2.0], "upper": [3.0, 3.0]},
                         {"lower": [3.0, 2.0], "upper": [4.0, 3.0]}]}]
    spec = spec_of(arena(2, tasks, obstacles=[]))
    first, second = _centred((2.5, 2.5)), _centred((3.5, 2.5))
    switch = _tube_with(spec, [(3.5, *first), (4.99, *first), (5.01, *second),
                               (6.5, *second), (8.0, *second)])
    m = margins(certify_tube(switch, spec))["task T1 stay"]
    assert not m.passed, m
    held = _tube_with(spec, [(3.5, *second), (6.5, *second), (8.0, *second)])
    m = margins(certify_tube(held, spec))["task T1 stay"]
    assert m.passed and "any_of[1]" in m.detail, m
    t = np.linspace(0.0, 8.0, 8001)
    x = np.where((t < 5.0)[:, None], [2.5, 2.5], [3.5, 2.5])
    assert not judge_task(spec.tasks[0], t, x).met          # the run judge agrees
    outcome = judge_task(spec.tasks[0], t, np.tile([3.5, 2.5], (t.size, 1)))
    assert outcome.met and outcome.box == 1


def test_stay_any_of_box_meeting_an_obstacle_is_dropped_and_the_design_says_so():
    tasks = [{"kind": "stay", "window": [4.0, 6.0],
              "any_of": [{"lower": [2.2, 2.2], "upper": [2.8, 2.8]},      # in the obstacle
                         {"lower": [0.5, 3.3], "upper": [1.5, 4.3]}]}]
    spec = spec_of(arena(2, tasks, t_c=12.0))
    design = design_tube(spec)
    m = margins(design.certificate)["task T1 stay"]
    assert m.passed and m.margin > 0.01
    (doc,) = design.to_json()["tasks"]
    assert doc["alternative"] == 1 and doc["dropped"] == [{"any_of": 0, "obstacle": 0}]


def _two_targets(obstacles: list) -> dict:
    doc = arena(2, [], obstacles=obstacles, t_c=10.0)
    doc.pop("tasks")
    doc["target"] = {"any_of": [{"lower": [4.4, 4.4], "upper": [5.0, 5.0]},
                                {"lower": [4.4, 0.0], "upper": [5.0, 0.6]}]}
    doc["tube"] = {"method": "auto"}
    return doc


def test_target_any_of_ends_in_the_first_box_that_designs_and_says_which():
    """The first target box is walled in (an L of obstacles around it): the tube ends in
    the second, the design's spec has it as its target and the report says so; the tube
    is not accepted against the first box."""
    walls = [{"lower": [3.6, 3.6], "upper": [5.0, 3.9]}, {"lower": [3.6, 3.9], "upper": [3.9, 5.0]}]
    spec = spec_of(_two_targets(walls))
    assert [q for q, _ in spec.target_any_of] == [0, 1]
    design = design_tube(spec)
    assert design.target_choice == 1 and design.certificate.passed
    assert design.spec.target_set.lower == (4.4, 0.0)
    doc = design.to_json()["target_choice"]
    assert doc["alternative"] == 1 and doc["dropped"] == []
    first = spec.target_any_of[0][1]
    m = margins(certify_tube(design.tube, first))["inside target after t_c"]
    assert not m.passed, m


def test_target_any_of_box_meeting_an_obstacle_is_dropped_with_a_note():
    blocks = [{"lower": [4.6, 4.6], "upper": [4.8, 4.8]}]        # inside the first box
    spec = spec_of(_two_targets(blocks))
    assert spec.target_dropped == ((0, "obstacles[0]"),)
    design = design_tube(spec)
    assert design.target_choice == 1 and design.certificate.passed
    assert design.to_json()["target_choice"]["dropped"] == [{"any_of": 0,
                                                              "obstacle": "obstacles[0]"}]


def test_a_target_any_of_refusal_names_the_nearest_time_a_box_certifies():
    """Both target boxes too far for the bound within t_c: each box's refusal names a later
    prescribed_time; the spec's refusal names the nearer one (the second, nearer box's,
    said so), and the spec with it is certified within the bound."""
    doc = {**_two_targets([]), "prescribed_time": 2.0, "actuator": {"input_bound": [1.0, 1.0]},
           "controller": {"rate_hz": 200.0}}
    doc["target"] = {"any_of": [{"lower": [4.4, 4.4], "upper": [5.0, 5.0]},
                                {"lower": [0.0, 2.4], "upper": [0.6, 3.0]}]}
    with pytest.raises(DesignError) as info:
        design_tube(spec_of(doc))
    named = info.value.advice["prescribed_time"]
    words = str(info.value)
    first = re.match(r"target any_of\[0\]: .*?prescribed_time = ([0-9.]+) s works", words)
    assert first is not None and named < float(first.group(1)), words
    assert f"with target any_of[1], prescribed_time = {named:g} s is certified" in words
    design = design_tube(spec_of({**doc, "prescribed_time": named}))
    assert design.certificate.passed and design.input_proof.meets((1.0, 1.0))


def test_free_timing_with_an_actuator_bound_keeps_the_tasks():
    """Overlapping windows under [actuator]: the design is proved within the bound and
    every task is still certified, with the visits the tasks' plan chose."""
    tasks = [reach(C, [2.0, 12.0]), reach(A, [2.0, 12.0])]
    doc = {**arena(2, tasks, obstacles=[], t_c=15.0), "actuator": {"input_bound": [3.0, 3.0]}}
    design = design_tube(spec_of(doc))
    assert design.input_proof.meets((3.0, 3.0)) and design.certificate.passed
    assert design.task_plan is not None and design.task_plan.order == (0, 1)
    assert all(margins(design.certificate)[t.name].passed for t in design.spec.tasks)


@pytest.mark.slow
def test_free_example_spec_picks_an_order_and_meets_every_task():
    """tests/specs/tasks-free.toml (overlapping windows, a 1 s stay, order = "any"): the
    design visits the stay first and every task is certified; the closed loop meets them."""
    spec = load_spec(Path(__file__).parent / "specs" / "tasks-free.toml")
    design = design_tube(spec)
    assert design.certificate.passed and design.task_plan.order == (2, 0, 1)
    result = simulate(design, backend="python")
    assert result.satisfied and all(t.met for t in result.tasks)


def test_free_example_with_a_moving_box_is_retimed_in_its_visit_order():
    """A box crossing the leg from the stay box to the inspection box while it is active:
    the tasks' plan (visit order T3, T1, T2, a 1 s stay) is re-timed around it and every
    task and the moving box are certified."""
    doc = tomllib.loads((Path(__file__).parent / "specs" / "tasks-free.toml").read_text())
    doc["obstacles"].append({"lower": [2.0, 3.6], "upper": [2.4, 4.0],
                             "velocity": [0.0, -0.5], "active": [3.0, 9.0]})
    design = design_tube(Spec.from_dict(doc))
    assert design.motion == "timed via" and design.certificate.passed
    names = [m.name for m in design.certificate.margins if m.passed]
    assert {"task T1 reach", "task T2 reach", "task T3 stay"} <= set(names)
    assert any(name.startswith("avoids moving obstacle") for name in names)
    # the re-timed visits are reported: each hold lies in its task's window, holds its box
    # (rho constant over it) and, for the stay, lasts its duration
    plan = design.task_plan
    assert plan is not None and plan.order == (2, 0, 1)
    rows = {row["task"]: row for row in design.to_json()["tasks"]}
    for k, task in enumerate(design.spec.tasks):
        start, end = plan.holds[k]
        t0, t1 = task.window
        assert rows[task.label]["hold"] == [start, end]
        assert rows[task.label]["visit"] == plan.order.index(k) + 1
        inside = min(end, t1) - max(start, t0)
        assert inside > 0 and (task.duration is None or inside >= task.duration), task.label
        times = np.linspace(start, end, 7)
        lower, upper = reference.reach_tube(design.tube, times)[:2]
        assert np.all(lower == lower[0]) and np.all(upper == upper[0]), task.label
    assert [plan.holds[k] for k in plan.order] == sorted(plan.holds)


# --------------------------------------------------------------------------- until


DOOR_TASK = {"kind": "reach", "window": [2.0, 4.0], "lower": [0.5, 3.5], "upper": [1.5, 4.5]}
DOOR = {"lower": [2.0, 0.0], "upper": [3.0, 5.0], "active_until": "T1"}


def test_an_obstacle_until_a_task_is_designed_around_and_certified():
    """A wall across the arena exists until T1 (a box left of it) is met: the tube visits
    T1, then crosses where the wall was; the wall is a box active over [0, 4] s (T1's
    window end)."""
    spec = spec_of(arena(2, [DOOR_TASK], obstacles=[DOOR], t_c=12.0))
    (wall,) = spec.moving_obstacles
    assert wall.active == (0.0, 4.0)
    design = design_tube(spec)
    found = margins(design.certificate)
    assert found["avoids moving obstacle 0"].passed and found["task T1 reach"].passed
    for bad, reason in (({**DOOR, "active_until": "T2"}, "no task T2"),
                        ({**DOOR, "active": [0.0, 1.0]}, "either active or active_until")):
        with pytest.raises(SpecError) as info:
            spec_of(arena(2, [DOOR_TASK], obstacles=[bad], t_c=12.0))
        assert info.value.field == "obstacles[0].active_until" and reason in info.value.reason


def test_a_tube_through_the_wall_before_its_task_is_met_is_rejected():
    """The tube crosses the wall's band at about 1 s, before it reaches T1 (at 3 s, inside
    the window): the task alone is met, the wall is not avoided while it exists:
    rejected. The same route crossing after 4 s passes."""
    spec = spec_of(arena(2, [DOOR_TASK], obstacles=[DOOR], t_c=12.0))
    band, left, task = _centred((2.5, 1.0)), _centred((1.0, 1.0)), _centred((1.0, 4.0))
    right = _centred((3.8, 4.0))
    early = _tube_with(spec, [(0.8, *left), (1.2, *band), (1.6, *right), (2.6, *task),
                              (3.4, *task), (8.0, *right)])
    check = check_tube(early, spec)
    assert not check.passed and "moving obstacle 0" in check.reason, check.reason
    assert margins(certify_tube(early, spec))["task T1 reach"].passed
    late = _tube_with(spec, [(2.6, *task), (3.4, *task), (4.0, *_centred((1.5, 4.0))),
                             (6.0, *right)])
    assert check_tube(late, spec).passed, check_tube(late, spec).reason


def test_the_wall_may_be_crossed_once_the_task_is_certified_met_inside_its_window():
    """The wall exists until T1 is met, not until T1's window ends: a tube that holds the
    task's box over [2.6, 3.4] s and crosses the wall's band right after, at about 3.7 s
    (before the window's end, 4 s), is certified; the same crossing with the task's box
    reached only after it (at 3.9 s) is rejected."""
    spec = spec_of(arena(2, [DOOR_TASK], obstacles=[DOOR], t_c=12.0))
    task, band = _centred((1.0, 4.0)), _centred((2.5, 4.0))
    right = _centred((3.8, 4.0))
    met_first = _tube_with(spec, [(2.6, *task), (3.4, *task), (3.7, *band), (4.0, *right),
                                  (8.0, *right)])
    check = check_tube(met_first, spec)
    assert check.passed, check.reason
    wall = margins(check.certificate)["avoids moving obstacle 0"]
    assert "until T1 is met, which the tube certifies by t = " in wall.detail
    met_late = _tube_with(spec, [(2.6, *_centred((1.0, 2.6))), (3.4, *band),
                                 (3.9, *task), (3.95, *task), (8.0, *right)])
    late = check_tube(met_late, spec)
    assert not late.passed and "moving obstacle 0" in late.reason, late.reason


@pytest.mark.slow
def test_a_door_until_its_key_with_the_whole_run_as_window_is_designed():
    """A wall with a door closed until T1 (a key left of the wall) is met, T1's window
    almost the whole run: the door exists until 11 s at the latest, too late to reach the
    target by 12 s through it, so only the key met first opens the way. The design plans
    the legs to the key around the door and the rest through it; the run meets the key,
    then passes where the door was, and is satisfied."""
    walls = [{"lower": [2.0, 0.0], "upper": [3.0, 2.2]}, {"lower": [2.0, 3.2], "upper": [3.0, 5.0]}]
    door = {"lower": [2.0, 2.2], "upper": [3.0, 3.2], "active_until": "T1"}
    key = {"kind": "reach", "window": [0.5, 11.0], "lower": [0.4, 3.8], "upper": [1.0, 4.4]}
    spec = spec_of(arena(2, [key], obstacles=walls + [door], t_c=12.0))
    (closed,) = spec.moving_obstacles
    assert closed.until == 0 and closed.active == (0.0, 11.0)
    design = design_tube(spec)
    found = margins(design.certificate)
    assert design.certificate.passed and found["task T1 reach"].passed
    assert design.to_json()["moving_obstacles"][0]["until"] == "T1"
    result = simulate(design, backend="python")
    assert result.satisfied and result.tasks[0].met, result.to_json()
    # the run goes through the doorway, after it has met the key
    t = result.trajectory.t
    x = result.trajectory.x
    in_door = np.all((x[:, :2] >= [2.0, 2.2]) & (x[:, :2] <= [3.0, 3.2]), axis=1)
    assert in_door.any() and t[in_door].min() > result.tasks[0].time
    # the judge keeps the door until the run meets the key: a run that had not met it
    # would have hit the door
    from dataclasses import replace as _replace
    unmet = [_replace(result.tasks[0], met=False, time=None)]
    (kept,) = until_met(design.spec, unmet)
    assert kept.active == closed.active
    assert kept.signed_clearance(x[in_door], t[in_door]).min() <= 0.0
