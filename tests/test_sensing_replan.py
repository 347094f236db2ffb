"""The replanner for sensed obstacles: reachable boxes, the start plan, kept and new tubes,
the region no unseen obstacle can reach (docs/sensing.md)."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design import sensed as sensed_module
from stt_codegen.design.sensed import (SLOWER, reachable_boxes, region_margin, switch_time)
from stt_codegen.tube import reference
from stt_codegen_bench.sensed_bench import scenario_with


@pytest.fixture(scope="module")
def hall():
    return stt.design_tube(stt.load_spec("hall-crossing"))


@pytest.fixture(scope="module")
def start(hall):
    return stt.start_plan(hall)


def oracle_tube(tube, t_end, rate_hz):
    """The deployed tube at every sample of ``[0, t_end]`` by the numpy oracle: ``alpha``
    stepped from 0 by the implicit step, as the controller steps it."""
    dt = 1.0 / rate_hz
    ts = np.arange(int(round(t_end * rate_hz)) + 1) * dt
    alphas = np.zeros((ts.size, 2 * tube.dimension))
    with reference.numpy_math():
        for k in range(ts.size - 1):
            alphas[k + 1] = reference.alpha_step(tube, ts[k:k + 1], np.array([dt]),
                                                 alphas[k:k + 1])[0]
        g_l, g_u, _, _ = reference.adaptive_tube(tube, ts, alphas)
    return ts, g_l, g_u


def test_the_reachable_boxes_cover_the_reachable_set_at_every_instant():
    person = stt.SensedObstacle.ball((3.0, 2.0), 0.3, seen_at=1.0)
    crate = stt.SensedObstacle.box((5.0, 1.0), (5.4, 1.6), seen_at=0.8)
    boxes = reachable_boxes([person, crate], 0.8, 0.25, (0, 1), start=1.5, t_from=0.2,
                            t_to=1.2, first_source=7)
    assert [b.source for b in boxes] == list(range(7, 7 + len(boxes)))
    assert all(b.active[1] - b.active[0] <= 0.25 + 1e-12 for b in boxes)
    for ob in (person, crate):
        for t in np.linspace(0.2, 1.2, 41):             # the tube's time; absolute 1.5 + t
            lo, hi = ob.reach_box(1.5 + t, 0.8)
            lo, hi = lo - 0.25, hi + 0.25
            held = [b for b in boxes if b.is_active(t)[0]
                    and np.all(b.centre(t)[0] - b.half_size <= lo + 1e-12)
                    and np.all(b.centre(t)[0] + b.half_size >= hi - 1e-12)]
            assert held, (ob, t)
    assert not any(b.is_active(1.3)[0] for b in boxes)   # nothing past the span


def test_with_an_acceleration_bound_the_boxes_follow_the_estimate():
    """With ``A`` the box of each span is the speed bound's box at the span's end cut by the
    drift box over the span (each holds the obstacle there: tests/test_sensing_spec.py),
    grown by the robot's radius; a walker's boxes are narrower than the speed bound's
    across its way; an obstacle without an estimate keeps the speed bound's boxes."""
    walker = stt.SensedObstacle.ball((3.0, 2.0), 0.3, seen_at=1.0, velocity=(0.7, 0.0))
    still = stt.SensedObstacle.ball((5.0, 1.0), 0.3, seen_at=1.0)
    args = ([walker, still], 0.8, 0.25, (0, 1))
    span = {"start": 1.5, "t_from": 0.2, "t_to": 1.2, "first_source": 0}
    plain = reachable_boxes(*args, **span)
    bounded = reachable_boxes(*args, **span, acceleration=0.5, velocity_error=0.05)
    half = len(plain) // 2
    assert len(bounded) == len(plain) and bounded[half:] == plain[half:]
    for b, p in zip(bounded[:half], plain[:half]):
        a, e = b.active
        speed_lo, speed_hi = walker.reach_box(1.5 + e, 0.8)
        drift_lo, drift_hi = walker.drift_box(1.5 + a, 1.5 + e, 0.5, 0.05)
        lo, hi = np.maximum(speed_lo, drift_lo) - 0.25, np.minimum(speed_hi, drift_hi) + 0.25
        c = b.centre(a)[0]
        assert c - b.half_size == pytest.approx(lo, abs=1e-12)
        assert c + b.half_size == pytest.approx(hi, abs=1e-12)
        assert b.half_size[1] < p.half_size[1]


def test_the_start_plan_is_certified_until_the_first_switch_and_its_horizon(start):
    s = start.task.sensing
    assert start.kept and start.start == 0.0
    assert start.guarantee_until == pytest.approx(s.latency + s.replan_time + s.horizon)
    assert start.region_margin > 0 and math.isinf(start.sensed_margin)
    assert switch_time(s, 0.5, 100.0) == pytest.approx(1.1)


def test_the_start_plan_fails_with_a_person_beside_the_start(hall):
    beside = stt.start_plan(hall, [stt.SensedObstacle.ball((2.2, 3.0), 0.3)])
    assert isinstance(beside, stt.ReplanFailure) and beside.kind == "design"
    assert "avoids moving obstacle" in beside.reason and beside.guarantee_until == 0.0
    wall = stt.start_plan(hall, [stt.SensedObstacle.box((5.0, 0.0), (5.4, 6.0))])
    assert wall.kind == "envelope" and "max_obstacle_radius" in wall.reason


def test_a_person_far_away_keeps_the_tube(start):
    kept = stt.replan(start, 1.0, (1.0, 3.0), [stt.SensedObstacle.ball((7.5, 1.0), 0.3,
                                                                       seen_at=1.0)])
    assert kept.kept and kept.design.tube == start.design.tube
    assert (kept.certified_from, kept.guarantee_until) == pytest.approx((1.0, 2.6))
    assert kept.sensed_margin > 0 and kept.region_margin > 0


@pytest.fixture(scope="module")
def person():
    return stt.SensedObstacle.ball((4.0, 2.8), 0.3, seen_at=1.0)


@pytest.fixture(scope="module")
def new(start, person):
    return stt.replan(start, 1.0, (1.0, 3.0), [person])


def test_a_person_in_the_way_gives_a_new_certified_tube(start, person, new):
    """The new tube misses the person's reachable box at every sample of its horizon (the
    oracle's tube, checked apart from the certificate)."""
    sensing = start.task.sensing
    assert not new.kept and new.start == new.switch_at == pytest.approx(1.6)
    assert new.design.certificate.passed and new.sensed_margin > 0
    ts, lows, highs = oracle_tube(new.design.tube, sensing.horizon, 100.0)
    for t, lo, hi in zip(ts, lows, highs):
        p_lo, p_hi = person.reach_box(new.start + t, sensing.max_obstacle_speed)
        apart = np.any((hi[:2] + 0.25 < p_lo) | (lo[:2] - 0.25 > p_hi))
        assert apart, t


@pytest.mark.slow
def test_the_new_tube_starts_from_a_box_holding_the_old_tube(start, new):
    """The old tube at the switch (the oracle's) lies in the new tube's start box."""
    old_t, old_lo, old_hi = oracle_tube(start.design.tube, 1.6, 100.0)
    box = new.design.spec.initial_set
    assert np.all(old_lo[-1] >= np.array(box.lower) - 1e-12)
    assert np.all(old_hi[-1] <= np.array(box.upper) + 1e-12)


def test_the_region_certificate_refuses_a_tube_that_outruns_the_range():
    """A range just above what the envelope needs: the base's straight tube drives beyond
    where it can see before the next plan, at every speed tried, so no plan is certified."""
    doc = {"name": "corridor", "prescribed_time": 3.0,
           "state_space": {"lower": [0.0, 0.0], "upper": [12.0, 2.0]},
           "initial": {"lower": [0.0, 0.5], "upper": [1.0, 1.5], "half_width": [0.2, 0.2]},
           "target": {"lower": [11.0, 0.5], "upper": [12.0, 1.5]},
           "controller": {"rate_hz": 100.0},
           "sensing": {"range": 2.0, "latency": 0.1, "period": 0.5,
                       "max_obstacle_radius": 0.3, "max_obstacle_speed": 0.5}}
    design = stt.design_tube(stt.Spec.from_dict(doc))
    failed = stt.start_plan(design)
    assert isinstance(failed, stt.ReplanFailure) and failed.kind == "region"
    assert "region no unseen obstacle can reach" in failed.reason
    slow = stt.design_tube(stt.Spec.from_dict({**copy.deepcopy(doc),
                                               "prescribed_time": 60.0}))
    room, _ = region_margin(slow, slow.spec.sensing, 0.0, 0.0, 0.0, (0.5, 1.0), 0.0, 1.6)
    assert room > 0 and stt.start_plan(slow).region_margin == pytest.approx(room)
    assert SLOWER[0] == 1.0


#: A 6 m x 4 m hall crossed from left to right; people walk at most 0.6 m/s and accelerate
#: at most 0.5 m/s^2.
CORRIDOR = {"name": "corridor", "prescribed_time": 10.0,
            "state_space": {"lower": [0.0, 0.0], "upper": [6.0, 4.0]},
            "initial": {"lower": [0.2, 1.6], "upper": [0.8, 2.4]},
            "target": {"lower": [5.2, 1.6], "upper": [5.8, 2.4]},
            "plant": {"model": "single-integrator"}, "robot": {"radius": 0.1},
            "sensing": {"range": 3.0, "latency": 0.1, "period": 0.5,
                        "max_obstacle_radius": 0.4, "max_obstacle_speed": 0.6,
                        "max_obstacle_acceleration": 0.5, "velocity_error": 0.05}}


def test_an_escape_when_no_tube_reaches_the_target():
    """A person walks down the hall's middle at the robot: no tube to the target keeps
    clear of where they may be, so the robot escapes to a temporary goal beside them,
    certified like any plan; with the hall clear again the next plan goes to the target."""
    design = stt.design_tube(stt.Spec.from_dict(CORRIDOR))
    plan = stt.start_plan(design)
    here = np.asarray(sensed_module._box_at(plan, 1.0, design.spec.state_space).center)
    person = stt.SensedObstacle.ball((2.8, 2.0), 0.35, seen_at=1.0, velocity=(-0.6, 0.0))
    escape = stt.replan(plan, 1.0, here, [person])
    assert isinstance(escape, stt.SensedPlan), escape.reason
    assert escape.goal is not None and not escape.kept
    assert escape.sensed_margin > 0 and escape.region_margin > 0
    assert escape.arrival == pytest.approx(escape.start + sensed_module.ESCAPE_TIME)
    goal = np.asarray(escape.goal.center)
    # the goal lies off the person's way, out of where they may be when the robot is there
    assert abs(goal[1] - 2.0) > 0.35 + 0.1
    assert escape.design.spec.target_set == escape.goal
    there = sensed_module._box_at(escape, 2.0 - escape.start, design.spec.state_space)
    back = stt.replan(escape, 2.0, there.center, [])
    assert isinstance(back, stt.SensedPlan) and back.goal is None and not back.kept
    assert back.design.spec.target_set == design.spec.target_set


def test_escape_goals_rank_by_where_the_obstacles_are_headed():
    """A circle seen at (7, 9.3) walking at 1 m/s towards the corner (10, 10): the corner
    ahead of it ranks below the open floor behind it, though the corner is the farther
    from where it was seen (the reachable ball's ranking, which chose the corner before);
    the circle stops at the wall, not beyond it; without an estimate the circle stands."""
    spec = stt.Spec.from_dict(scenario_with(2.0))
    sensing = spec.sensing
    seen = stt.SensedObstacle.ball((7.0, 9.3), 0.3, seen_at=10.0, velocity=(1.0, 0.0))
    corner, floor = np.array([9.5, 9.5]), np.array([7.5, 8.0])
    headed = [sensed_module._headed_clearance(seen, p, 10.3, 11.8, spec.state_space, 0.1,
                                              sensing)
              for p in (corner, floor)]
    assert np.linalg.norm(corner - seen.centre) > np.linalg.norm(floor - seen.centre)
    assert headed[0] < headed[1]
    # four seconds after it was seen the estimate puts it past the wall: it stops at
    # x = 10 - 0.3 (the state space is the reference point's, the walls less the robot's
    # radius 0.1)
    late = sensed_module._headed_clearance(seen, np.array([9.7, 9.3]), 14.0, 14.0,
                                           spec.state_space, 0.1, sensing)
    assert late == pytest.approx(-0.3 - sensing.velocity_error * 4.0)
    standing = dataclasses.replace(seen, velocity=None)
    gap = sensed_module._headed_clearance(standing, floor, 10.0, 11.0, spec.state_space,
                                          0.1, sensing)
    assert gap == pytest.approx(np.linalg.norm(floor - seen.centre) - 0.3
                                - sensing.velocity_error * 1.0)


def test_an_obstacle_closing_on_a_robot_that_has_arrived_is_taken_to_pursue_it(
        monkeypatch):
    """Real-Time STT's script, the robot holding in the target at 17 s (after t_c): a circle
    2.4 m away walking at 0.45 m/s, its heading 40 degrees off the robot, would pass beside
    the held box on a straight walk, but catches it if it turns after the robot, so the
    kept tube is headed into it. Not so when it heads away, or while the tube is still due
    by t_c. A circle faster than ``CLOSING_SPEED`` times the slowest path closes only
    within ``FAST_CLOSING_ANGLE`` (15 degrees), and is followed for ``FAST_PURSUIT`` (1 s)
    past the horizon, not ``FORESIGHT`` (2 s): 3 m below the robot at 1.35 m/s it catches
    the held box within that, 4 m below it does not (but would within ``FORESIGHT``)."""
    from stt_codegen_bench.sensed_script import SCRIPT
    design = stt.design_tube(stt.Spec.from_dict(SCRIPT))
    own = stt.start_plan(design)
    sensing = design.spec.sensing
    until = switch_time(sensing, 17.0, design.spec.rate_hz) + sensing.horizon
    here = np.array([7.0, 10.0])
    circle = stt.SensedObstacle.ball((6.18, 7.74), 0.5, seen_at=17.0,
                                     velocity=(-0.154, 0.423))
    assert sensed_module._closing(circle, here)
    assert sensed_module._headed_into(own, [circle], sensing, until, 500, here)
    with monkeypatch.context() as m:        # nobody closing: the straight walk alone
        m.setattr(sensed_module, "CLOSING_ANGLE", 0.1)
        assert not sensed_module._headed_into(own, [circle], sensing, until, 500, here)
    away = dataclasses.replace(circle, velocity=(0.154, -0.423))
    assert not sensed_module._closing(away, here)
    assert not sensed_module._pursued(own.design, own.start, own.arrival, own.task,
                                      [away], sensing, until, here)

    def fast(below):
        return stt.SensedObstacle.ball((7.0, 10.0 - below), 0.5, seen_at=17.0,
                                       velocity=(0.0, 1.35))

    near, far = fast(3.0), fast(4.0)
    assert sensed_module._closing(far, here) and sensed_module._fast(far)
    # 40 degrees off the robot: a slow one closes, a fast one (a straight walk) does not
    assert not sensed_module._closing(dataclasses.replace(
        circle, velocity=(-0.154 * 3, 0.423 * 3)), here)
    assert not sensed_module._fast(circle)
    assert sensed_module._pursued(own.design, own.start, own.arrival, own.task, [near],
                                  sensing, until, here)
    assert not sensed_module._pursued(own.design, own.start, own.arrival, own.task, [far],
                                      sensing, until, here)
    with monkeypatch.context() as m:        # followed as long as a slow one
        m.setattr(sensed_module, "FAST_PURSUIT", sensed_module.FORESIGHT)
        assert sensed_module._pursued(own.design, own.start, own.arrival, own.task, [far],
                                      sensing, until, here)
    due = switch_time(sensing, 5.0, design.spec.rate_hz) + sensing.horizon
    early = dataclasses.replace(circle, seen_at=5.0)
    assert not sensed_module._pursued(own.design, own.start, own.arrival, own.task,
                                      [early], sensing, due, here)
    # a robot that has been in the target (on its way back after an escape, in a tube
    # due by t_c) is pursued all the same
    assert sensed_module._pursued(own.design, own.start, own.arrival, own.task, [early],
                                  sensing, due, here, reached=True)


def test_a_plan_remembers_that_the_robot_has_been_in_the_target():
    """``SensedPlan.reached``: a measurement inside the target sets it, and the plans
    replanned from one that has it keep it wherever the robot is measured next."""
    from stt_codegen_bench.sensed_script import SCRIPT
    design = stt.design_tube(stt.Spec.from_dict(SCRIPT))
    own = stt.start_plan(design)
    space = design.spec.state_space
    first = stt.replan(own, 1.0, sensed_module._box_at(own, 1.0, space).center, [])
    assert isinstance(first, stt.SensedPlan) and not own.reached and not first.reached
    there = stt.replan(first, 16.0, design.spec.target_center, [])
    assert isinstance(there, stt.SensedPlan) and there.reached
    back = stt.replan(dataclasses.replace(first, reached=True), 1.25,
                      sensed_module._box_at(own, 1.25, space).center, [])
    assert isinstance(back, stt.SensedPlan) and back.reached


def test_an_escape_from_a_pursuer_counts_its_way_there_and_the_wait():
    """A circle of radius 0.5 at the origin, seen at 0 s, closing at 0.45 m/s on a robot at
    (2, 0) that escapes from 0 s to a goal in 1 s and holds it until 3.5 s. Away from the
    circle, to (2.5, 0): the circle walks after it, 28 steps of 0.125 s by 3.5 s, so the
    least distance comes at the end, 2.5 - 28 x 0.05625 less its extent; a shorter wait
    leaves more. Past the circle, to (-2.5, 0.3), farther from where it was seen: the way
    passes through it, which the ball it may reach (the ranking before) does not see."""
    from stt_codegen_bench.sensed_script import SCRIPT
    sensing = stt.Spec.from_dict(SCRIPT).sensing
    circle = stt.SensedObstacle.ball((0.0, 0.0), 0.5, seen_at=0.0, velocity=(0.45, 0.0))
    here = np.array([2.0, 0.0])

    def clearance(goal, until=3.5):
        return sensed_module._pursuit_clearance(circle, here, np.asarray(goal, float), 0.0,
                                                1.0, until, sensing)

    walked = 28 * (0.45 + sensing.velocity_error) * sensed_module.HEADED_STEP
    away = clearance((2.5, 0.0))
    assert away == pytest.approx(2.5 - walked - 0.5 - sensing.velocity_error * 3.5)
    assert clearance((2.5, 0.0), until=1.0) > away > 0.0
    assert clearance((-2.5, 0.3)) < -0.25 < away


def test_a_replanned_tube_due_near_t_c_gives_way_to_a_sooner_path():
    """A replanned tube (started after 0) that arrives at t_c, with nothing in the way:
    a space-time path that arrives at least ``EARLIER`` sooner takes over; the same tube
    due ``EARLIER`` before t_c, and the spec's own tube (which starts at 0), are kept."""
    design = stt.design_tube(stt.Spec.from_dict(scenario_with(2.0)))
    own = stt.start_plan(design)
    t_c = design.spec.prescribed_time
    late = dataclasses.replace(own, start=0.25, switch_at=0.25, arrival=t_c)
    here = np.asarray(sensed_module._box_at(late, 0.25, design.spec.state_space).center)
    sooner = stt.replan(late, 0.5, here, [])
    assert isinstance(sooner, stt.SensedPlan) and not sooner.kept, sooner
    assert sooner.design.motion == "sensed path"
    assert sooner.arrival <= t_c - sensed_module.EARLIER
    assert sooner.region_margin > 0
    due = dataclasses.replace(late, arrival=t_c - sensed_module.EARLIER)
    assert stt.replan(due, 0.5, here, []).kept
    here = np.asarray(sensed_module._box_at(own, 0.5, design.spec.state_space).center)
    assert stt.replan(own, 0.5, here, []).kept


def test_bad_calls_name_the_field(hall, start):
    plain = dataclasses.replace(hall, spec=dataclasses.replace(hall.spec, sensing=None))
    with pytest.raises(stt.SpecError) as caught:
        stt.start_plan(plain)
    assert caught.value.field == "sensing"
    with pytest.raises(stt.SpecError) as caught:
        stt.start_plan(hall, [stt.SensedObstacle.ball((1.0, 2.0, 0.0), 0.2)])
    assert caught.value.field == "sensed[0].centre"
    with pytest.raises(stt.SpecError) as caught:
        stt.replan(start, 1.0, (1.0, 3.0), [stt.SensedObstacle.ball((5.0, 2.0), 0.2,
                                                                    seen_at=2.0)])
    assert caught.value.field == "sensed[0].seen_at"
    with pytest.raises(stt.SpecError) as caught:
        stt.replan(start, -1.0, (1.0, 3.0), [])
    assert caught.value.field == "measured_at"
    with pytest.raises(stt.SpecError) as caught:
        stt.replan(start, 1.0, (1.0,), [])
    assert caught.value.field == "position"
    with pytest.raises(TypeError, match="SensedPlan"):
        stt.replan(hall, 1.0, (1.0, 3.0), [])


#: Real-Time STT's arena of ``bench sensed``: a 10 m square at 100 Hz, measurements every
#: 0.25 s, ``H = 0.5`` s, obstacles up to ``sqrt(2)`` m/s turning at 2 m/s^2.
ARENA = scenario_with(2.0)


def arena_plan(**sensing):
    doc = copy.deepcopy(ARENA)
    doc["sensing"].update(sensing)
    return stt.start_plan(stt.design_tube(stt.Spec.from_dict(doc)))


@pytest.mark.parametrize("obstacles, kept", [
    ([((2.24, 0.4), (-0.49, 0.52))], True),
    ([((0.52, 1.27), (-0.19, 1.07)), ((2.75, 0.8), (0.19, 0.38))], False),
])
def test_a_plan_over_the_shortest_horizon_when_none_holds_over_the_horizon(obstacles, kept):
    """No plan from this measurement is certified over ``H`` = 0.5 s (with ``H_min = H`` the
    replanner fails); over the default ``H_min = T_u`` = 0.25 s one is (the reachable sets
    of the shorter span are smaller), certified until ``t_s + H_min``: the kept tube or a
    new one. The oracle's tube over that span misses each obstacle's reachable set (the
    speed bound's box cut by the drift box), apart from the certificate."""
    t_m = 1.0
    plan = arena_plan()
    sensing = plan.task.sensing
    assert sensing.shortest_horizon == sensing.period == 0.25
    here = np.asarray(sensed_module._box_at(plan, t_m, plan.task.state_space).center)
    seen = [stt.SensedObstacle.ball(c, 0.4, seen_at=t_m, velocity=v) for c, v in obstacles]
    full = stt.replan(arena_plan(shortest_horizon=0.5), t_m, here, seen)
    assert isinstance(full, stt.ReplanFailure), full
    assert "shortest horizon" not in full.reason
    short = stt.replan(plan, t_m, here, seen)
    assert isinstance(short, stt.SensedPlan), short.reason
    t_s = switch_time(sensing, t_m, 100.0)
    assert short.shortened and not plan.shortened and short.kept == kept
    assert short.guarantee_until == pytest.approx(t_s + sensing.shortest_horizon)
    assert short.sensed_margin > 0 and short.region_margin > 0
    reach = 0.1
    ts, lows, highs = oracle_tube(short.design.tube, short.guarantee_until - short.start,
                                  100.0)
    for t, lo, hi in zip(ts + short.start, lows, highs):
        if t < short.certified_from:
            continue
        for ob in seen:
            s_lo, s_hi = ob.reach_box(t, sensing.max_obstacle_speed)
            d_lo, d_hi = ob.drift_box(t, t, sensing.max_obstacle_acceleration,
                                      sensing.velocity_error)
            o_lo, o_hi = np.maximum(s_lo, d_lo) - reach, np.minimum(s_hi, d_hi) + reach
            assert np.any((hi < o_lo) | (lo > o_hi)), (t, ob)


def test_a_failure_over_both_horizons_says_so():
    """An obstacle standing on the robot: nothing holds over either horizon, and the
    failure says what failed over each."""
    t_m = 1.0
    plan = arena_plan()
    here = np.asarray(sensed_module._box_at(plan, t_m, plan.task.state_space).center)
    on_it = [stt.SensedObstacle.ball(tuple(here + 0.45), 0.4, seen_at=t_m)]
    failed = stt.replan(plan, t_m, here, on_it)
    assert isinstance(failed, stt.ReplanFailure)
    assert "; over the shortest horizon (0.25 s): " in failed.reason
    assert failed.guarantee_until == plan.guarantee_until


def test_a_failure_carries_an_uncertified_escape_away_from_the_obstacle():
    """An obstacle closing on the robot from beside it: its reachable set already meets
    where the robot will be at the switch, so no plan is certified over either horizon.
    The failure carries a best-effort escape: it takes over only at the first sample the
    active plan is no longer certified, covers no span (``guarantee_until`` is its
    switch), and goes away from the obstacle."""
    plan = arena_plan()
    here = np.asarray(sensed_module._box_at(plan, 1.0, plan.task.state_space).center)
    kept = stt.replan(plan, 1.0, here, [])
    assert isinstance(kept, stt.SensedPlan) and kept.kept
    t_m = 1.25
    here = np.asarray(sensed_module._box_at(kept, t_m, plan.task.state_space).center)
    centre = here + 0.45
    closing = [stt.SensedObstacle.ball(tuple(centre), 0.4, seen_at=t_m,
                                       velocity=(-0.2, -0.2))]
    failed = stt.replan(kept, t_m, here, closing)
    assert isinstance(failed, stt.ReplanFailure) and failed.kind == "design"
    best = failed.fallback
    assert best is not None and best.best_effort and best.goal is not None
    sensing = plan.task.sensing
    assert switch_time(sensing, t_m, plan.task.rate_hz) < kept.guarantee_until
    assert best.switch_at == pytest.approx(kept.guarantee_until, abs=1e-12)
    assert best.start == best.certified_from == best.guarantee_until == best.switch_at
    assert not best.shortened and not best.kept and best.measured_at == t_m
    assert best.cpu_s == failed.cpu_s         # the failure's time includes the escape's
    goal = np.asarray(best.goal.center)
    assert np.linalg.norm(goal - centre) > np.linalg.norm(here - centre) + 1.0
    # the next measurement, with the way clear: the escape itself is certified, from
    # that measurement on, so that its certificate covers the time since it took over
    t_m = 1.5
    there = np.asarray(sensed_module._box_at(best, 0.0, plan.task.state_space).center)
    next_plan = stt.replan(best, t_m, there, [])
    assert isinstance(next_plan, stt.SensedPlan) and next_plan.kept
    assert not next_plan.best_effort and next_plan.goal == best.goal
    assert next_plan.certified_from == t_m < best.switch_at < next_plan.guarantee_until
    # a measurement outside the envelope gets no escape
    large = [stt.SensedObstacle.ball(tuple(centre), 2.0, seen_at=t_m)]
    outside = stt.replan(kept, t_m, here, large)
    assert outside.kind == "envelope" and outside.fallback is None


def test_a_new_tube_is_proved_from_where_the_old_proof_leaves_the_state(start, new):
    """The chain of sampled-data proofs (design/sensed_switch.py): the spec's tube is
    proved from its x(0); a new tube from the box where the active tube's proof keeps the
    state at the switch, cut to the switch test, so its proved box at t' = 0 holds every
    state of that box the switch admits, and it carries its own bound to the next switch."""
    from stt_codegen.design.sensed_switch import ROUNDING, state_at, switch_error
    rate = start.task.rate_hz
    assert start.state_bounds is not None and new.state_bounds is not None
    lo, hi = state_at(start.state_bounds, rate, new.switch_at - start.start)
    with reference.numpy_math():
        samples = stt.design.samples.sample_tube(new.design.tube, horizon=0.01)
    centre = 0.5 * (samples.gamma_lower[0] + samples.gamma_upper[0])
    half = 0.5 * (samples.gamma_upper[0] - samples.gamma_lower[0])
    admitted_lo = np.maximum(lo, centre - 0.5 * half)
    admitted_hi = np.minimum(hi, centre + 0.5 * half)
    assert np.all(admitted_lo <= admitted_hi)
    assert np.all(new.state_bounds[0][0] <= admitted_lo + 1e-12)
    assert np.all(new.state_bounds[1][0] >= admitted_hi - 1e-12)
    # not the point x(0): the proof starts from a box
    assert np.all(new.state_bounds[1][0] - new.state_bounds[0][0] > 1e-3)
    box = switch_error(new.design, (lo, hi))
    edge = 0.5 + ROUNDING
    assert all(-edge <= a <= b <= edge for a, b in box)
    # a state box the switch test refuses everywhere: no tube can take over from it
    assert switch_error(new.design, (hi + 2.0 * half, hi + 3.0 * half)) is None
    assert switch_error(new.design, None) == ((-edge, edge),) * new.design.tube.dimension


def test_a_tube_not_proved_from_the_switch_is_not_taken(start, person, new, monkeypatch):
    """Where every new tube's sampled-data check fails from the switch's box, the replanner
    takes none of them: the person in the way that gives a new tube (above) now leaves the
    active tube, certified again (it is not in the person's reachable set yet)."""
    def unproved(design, spec, initial_error=None):
        return None, "the sampled loop is not proved from the switch: (forced)"
    assert not new.kept
    monkeypatch.setattr(sensed_module, "proved_error", unproved)
    plan = stt.replan(start, 1.0, (1.0, 3.0), [person])
    assert plan.kept and plan.design.tube == start.design.tube and plan.goal is None
    assert plan.state_bounds is start.state_bounds


def test_an_escape_counts_a_fast_pursuer_over_its_way_and_not_the_wait(monkeypatch):
    """A goal's clearance from a closing obstacle (``_goal_clearance``): a slow one turning
    after the robot is followed while the goal is held for ``FORESIGHT`` more, a fast one
    (1.35 m/s, faster than ``CLOSING_SPEED`` times the slowest path) only until the
    escape's horizon: it reaches every goal the robot would wait at, and the ranking would
    say nothing. An obstacle that is not closing is ranked where it is headed."""
    from stt_codegen_bench.sensed_script import SCRIPT
    spec = stt.Spec.from_dict(SCRIPT)
    sensing = spec.sensing
    here, goal = np.array([2.0, 0.0]), np.array([4.4, 0.0])
    later = 0.0 + sensed_module.ESCAPE_TIME + sensing.horizon
    for speed in (0.45, 1.35):
        ob = stt.SensedObstacle.ball((0.0, 0.0), 0.5, seen_at=0.0, velocity=(speed, 0.0))
        hold = 0.0 if sensed_module._fast(ob) else sensed_module.FORESIGHT
        assert sensed_module._fast(ob) == (speed > 1.0)
        got = sensed_module._goal_clearance(ob, True, here, goal, 0.0, spec.state_space,
                                            0.1, sensing)
        assert got == pytest.approx(sensed_module._pursuit_clearance(
            ob, here, goal, 0.0, sensed_module.ESCAPE_TIME, later + hold, sensing))
        walked = sensed_module._goal_clearance(ob, False, here, goal, 0.0, spec.state_space,
                                               0.1, sensing)
        assert walked == pytest.approx(sensed_module._headed_clearance(
            ob, goal, 0.0, later, spec.state_space, 0.1, sensing))
    # the fast one waited for: caught at the goal; over the way alone: clear of it
    fast = stt.SensedObstacle.ball((0.0, 0.0), 0.5, seen_at=0.0, velocity=(1.35, 0.0))
    assert sensed_module._goal_clearance(fast, True, here, goal, 0.0, spec.state_space,
                                         0.1, sensing) > 0.0
    monkeypatch.setattr(sensed_module, "CLOSING_SPEED", 10.0)     # taken for a slow one
    assert sensed_module._goal_clearance(fast, True, here, goal, 0.0, spec.state_space,
                                         0.1, sensing) < 0.0
