"""The evasion from a sensed pursuer (stt_codegen/design/sensed_evade.py, docs/sensing.md):
tracks taken for pursuers, the goals' ranking, and replans that evade."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from stt_codegen_bench.sensed_bench import _turning, scenario_with

import stt_codegen as stt
from stt_codegen.design import sensed as sensed_module
from stt_codegen.design import sensed_evade as evade
from stt_codegen.design.sensed import switch_time
from stt_codegen.runtime.sensed import WalkingObstacle, _World
from stt_codegen.tube import reference


@pytest.fixture(scope="module")
def circles():
    """Real-Time STT's arena (10 m, ``V = sqrt(2)``, ``A = 2``), its design and first plan."""
    design = stt.design_tube(stt.Spec.from_dict(scenario_with(2.0)))
    return design, stt.start_plan(design)


def measured(world, t, labels=True):
    return [stt.SensedObstacle.ball(tuple(world.p[j]), float(world.radius[j]), seen_at=t,
                                    velocity=tuple(world.v[j]), label=j if labels else None)
            for j in range(world.radius.size)]


def test_a_track_turning_as_the_envelopes_adversary_is_taken_for_a_pursuer():
    """The simulator's obstacles, the robot standing at (5, 5), measured at 0.5 and 0.75 s:
    a pursuer at ``V``, turning at ``A`` (track 0), is taken for one; a circle walking
    past at 1 m/s (1), one turning back before the east wall at 1 m/s^2 per axis (2, as
    the bench's circles) and one walking straight at the robot at ``V`` (3: its velocity
    does not change) are not. Known tracks are kept; untracked obstacles are not taken."""
    sensing = stt.Spec.from_dict(scenario_with(2.0)).sensing
    here = np.array([5.0, 5.0])
    walk = tuple((0.1 * k, 1.0 + 0.1 * k, 2.0) for k in range(21))
    wall = _turning(np.array([9.0, 3.0]), np.array([1.0, 0.6]), 0.3, 10.0, 2.0, 1.0)
    speed = sensing.max_obstacle_speed
    straight = tuple((0.1 * k, 5.0, 0.5 + speed * 0.1 * k) for k in range(21))
    obstacles = [WalkingObstacle((8.0, 8.0), 0.3, pursuit_speed=sensing.max_obstacle_speed,
                                 pursuit_acceleration=2.0),
                 WalkingObstacle((1.0, 2.0), 0.3, path=walk),
                 WalkingObstacle((9.0, 3.0), 0.3, path=wall),
                 WalkingObstacle((5.0, 0.5), 0.3, path=straight)]
    world, dt, seen = _World(obstacles, 2, 0.01), 0.01, {}
    for k in range(75):
        world.p = world.advance(k * dt, dt, here)
        if k + 1 in (50, 75):
            seen[k + 1] = measured(world, (k + 1) * dt)
    before, after = seen[50], seen[75]
    # the wall's circle is turning between the two measurements
    assert np.linalg.norm(np.subtract(after[2].velocity, before[2].velocity)) > 0.2
    # the straight walk heads at the robot at V, as the adversary's velocity would
    towards = here - np.asarray(after[3].centre)
    assert np.asarray(after[3].velocity) == pytest.approx(
        towards / np.linalg.norm(towards) * speed)
    assert evade.chasing(before, (), after, here, sensing) == (0,)
    assert evade.chasing(before, (2,), after, here, sensing) == (0, 2)
    assert evade.chasing((), (2,), after, here, sensing) == (2,)
    assert evade.chasing(measured(world, 0.5, False), (), measured(world, 0.75, False),
                         here, sensing) == ()


def test_a_pursuer_is_run_from_when_fast_approaching_and_near():
    """``pursuers``: a circle at 1.4 m/s heading at the robot 3 m away is run from; not
    when it heads away, walks slower than ``slowest``, or is farther than
    ``EVADE_DISTANCE`` (its shape's distance)."""
    here = np.array([5.0, 5.0])

    def circle(centre, velocity, radius=0.3):
        return stt.SensedObstacle.ball(centre, radius, seen_at=0.0, velocity=velocity)

    chaser = circle((8.0, 5.0), (-1.4, 0.0))
    assert evade.pursuers([chaser], here, 0.5) == [chaser]
    assert evade.pursuers([circle((8.0, 5.0), (1.4, 0.0))], here, 0.5) == []
    assert evade.pursuers([circle((8.0, 5.0), (-0.4, 0.0))], here, 0.5) == []
    far = 5.0 + evade.EVADE_DISTANCE + 0.3
    assert evade.pursuers([circle((far + 0.01, 5.0), (-1.4, 0.0))], here, 0.5) == []
    assert evade.pursuers([circle((far - 0.01, 5.0), (-1.4, 0.0))], here, 0.5) != []


def test_a_pursuit_turning_at_the_envelopes_acceleration():
    """``turning``: the obstacle keeps its velocity (its estimate at first) and turns it
    towards the robot by at most ``A`` times the step, at its estimated speed plus
    ``velocity_error`` but at most ``V``. A pursuer at
    (0, 0) going north at 1 m/s, the robot due east: one step of 0.05 s at ``A = 2`` turns
    the velocity by 0.1 towards ``(1.05, 0)``; at once, it is that velocity."""
    sensing = stt.Spec.from_dict(scenario_with(2.0)).sensing
    ob = stt.SensedObstacle.ball((0.0, 0.0), 0.3, seen_at=0.0, velocity=(0.0, 1.0))
    top = 1.0 + sensing.velocity_error

    def aim(t):
        return np.array([5.0, 0.0])

    path = list(evade.turning(ob, sensing, 0.1, aim, 2.0, 0.05))
    assert [t for t, _ in path] == pytest.approx([0.0, 0.05, 0.1])
    turn = np.array([top, -1.0])
    v = np.array([0.0, 1.0]) + turn / np.linalg.norm(turn) * 0.1
    assert path[1][1] == pytest.approx(v * 0.05)
    at_once = list(evade.turning(ob, sensing, 0.05, aim, math.inf, 0.05))
    assert at_once[1][1] == pytest.approx(np.array([top, 0.0]) * 0.05)
    # never faster than V, whatever the estimate
    quick = dataclasses.replace(ob, velocity=(0.0, 3.0))
    steps = list(evade.turning(quick, sensing, 2.0, aim, math.inf, 0.05))
    assert max(np.linalg.norm(b - a) for (_, a), (_, b) in zip(steps, steps[1:])) \
        == pytest.approx(sensing.max_obstacle_speed * 0.05)


def test_an_evasion_ranks_a_run_along_the_wall_above_the_wall_and_the_pursuer():
    """A robot at (9, 5), 1 m from the east wall of the 10 m arena, a pursuer 2.5 m west of
    it coming east at 1.4 m/s: running north along the wall (2.4 m/s, sliding) keeps more
    than 1 m over ``EVADE_LOOK_AHEAD``; running into the wall or at the pursuer, it is
    caught. Carried 1 m west first by the move under way, running north is caught too."""
    spec = stt.Spec.from_dict(scenario_with(2.0))
    sensing = spec.sensing
    here = np.array([9.0, 5.0])
    chaser = stt.SensedObstacle.ball((6.5, 5.0), 0.3, seen_at=0.0, velocity=(1.4, 0.0))
    lower, upper = np.array([0.2, 0.2]), np.array([9.8, 9.8])
    t_s = switch_time(sensing, 0.0, spec.rate_hz)

    def clearance(heading, carry=None):
        return evade.evasion_clearance(chaser, here, 0.0, here, t_s,
                                       np.asarray(heading, float), 2.4, lower, upper,
                                       sensing, carry)

    north, east, west = clearance((0.0, 1.0)), clearance((1.0, 0.0)), clearance((-1.0, 0.0))
    assert north > 1.0 and east < 0.0 and west < 0.0
    assert clearance((0.0, 1.0), (np.array([-1.0, 0.0]), 0.25)) < north


def test_the_ring_ahead_goes_round_the_way_the_robot_is_carried_unless_the_chaser_is_ahead():
    """The arena's state space is [0.1, 9.9]^2 (the robot's radius off the walls): the ring
    has radius 0.6 * 4.9 = 2.94 about (5, 5). From (8, 5), a chaser at (5, 2) (south): 60
    degrees round, away from it. Carried south-west by the move under way, round towards
    that chaser (90 degrees ahead on that way): it turns back, away from it. A chaser at
    (2.2, 4), nearly across the centre (160 degrees ahead that way, 200 the other), is
    not ahead: the robot goes on the way it is carried, towards the chaser's far side,
    not away from it. On one sensing dimension, the target's centre."""
    spec = stt.Spec.from_dict(scenario_with(2.0))
    assert spec.state_space.lower == (0.1, 0.1) and spec.state_space.upper == (9.9, 9.9)
    chaser = stt.SensedObstacle.ball((5.0, 2.0), 0.3, seen_at=0.0, velocity=(0.0, 1.0))
    across = stt.SensedObstacle.ball((2.2, 4.0), 0.3, seen_at=0.0, velocity=(1.0, 0.0))
    origin, south_west = np.array([8.0, 5.0]), np.array([-0.1, -0.2])
    up = (5.0 + 2.94 * math.cos(math.pi / 3), 5.0 + 2.94 * math.sin(math.pi / 3))
    down = (up[0], 10.0 - up[1])
    assert evade.ring_ahead(spec, [0, 1], origin, [chaser], np.zeros(2)) == pytest.approx(up)
    assert evade.ring_ahead(spec, [0, 1], origin, [chaser], south_west) == pytest.approx(up)
    assert evade.ring_ahead(spec, [0, 1], origin, [across], south_west) == pytest.approx(down)
    assert evade.ring_ahead(spec, [0], origin[:1], [chaser], np.zeros(1)) == pytest.approx(
        np.asarray(spec.target_center)[:1])


def test_the_tracks_taken_for_pursuers_stay_taken(circles):
    """A plan's ``chasers`` pass to the next plan, whatever it measures."""
    design, plan = circles
    here = np.asarray(sensed_module._box_at(plan, 1.0, design.spec.state_space).center)
    nxt = stt.replan(dataclasses.replace(plan, chasers=(4,)), 1.0, here, [])
    assert isinstance(nxt, stt.SensedPlan) and nxt.chasers == (4,)


def test_a_replan_evades_a_pursuer_and_the_next_goes_on_with_its_move(circles):
    """Real-Time STT's circles: at 2 s track 0, taken for a pursuer, is 2.5 m east of the
    robot and comes at it at 1.4 m/s. The replan is an evasion: a certified tube to a goal
    one of ``EVADE_DISTANCES`` from where the robot will be at the switch, not towards the
    pursuer. A measurement later (the pursuer 0.35 m nearer), the next evasion goes on with
    the move under way: its first segment began before its time 0, and at the switch its
    box and its rate are the active tube's (the robot keeps its speed). The same track
    walking away, or not taken for a pursuer, is not evaded."""
    design, plan = circles
    sensing = design.spec.sensing
    here = np.asarray(sensed_module._box_at(plan, 2.0, design.spec.state_space).center)
    chased = dataclasses.replace(plan, chasers=(0,))
    coming = stt.SensedObstacle.ball(tuple(here + [2.5, 0.0]), 0.3, seen_at=2.0,
                                     velocity=(-1.4, 0.0), label=0)
    evasion = stt.replan(chased, 2.0, here, [coming])
    assert isinstance(evasion, stt.SensedPlan), evasion.reason
    assert evasion.goal is not None and evasion.sensed_margin > 0
    assert evasion.chasers == (0,)
    t_s = switch_time(sensing, 2.0, design.spec.rate_hz)
    point = sensed_module._taking_over(chased, t_s, here, 2.0, sensing)[1]
    way = np.asarray(evasion.goal.center) - point
    assert min(abs(float(np.linalg.norm(way)) - d) for d in evade.EVADE_DISTANCES) < 1e-9
    away_from = np.asarray(coming.centre)             # not towards the pursuer
    assert np.linalg.norm(point + way - away_from) > np.linalg.norm(point - away_from)

    there = np.asarray(sensed_module._box_at(evasion, 2.25 - evasion.start,
                                             design.spec.state_space).center)
    nearer = dataclasses.replace(coming, centre=tuple(coming.centre + np.array([-0.35, 0.0])),
                                 seen_at=2.25)
    going = stt.replan(evasion, 2.25, there, [nearer])
    assert isinstance(going, stt.SensedPlan) and going.goal is not None, going
    tube = going.design.tube
    assert going.design.certificate.passed and tube.blends_corners
    assert tube.segments[0].start < 0.0 == tube.segments[1].start < tube.segments[0].end
    at = np.array([going.start - evasion.start])
    old, now = (reference.reach_tube(evasion.design.tube, at, rates=True),
                reference.reach_tube(tube, np.zeros(1), rates=True))
    assert np.abs(old[2][0, :2]).max() > 0.3                # the robot is moving, m/s
    for a, b in zip(old, now):
        assert np.allclose(a, b, rtol=0.0, atol=1e-12)

    away = dataclasses.replace(coming, velocity=(1.4, 0.0))
    on_way = stt.replan(chased, 2.0, here, [away])
    assert isinstance(on_way, stt.SensedPlan) and on_way.goal is None
    untracked = stt.replan(plan, 2.0, here, [coming])
    assert not (isinstance(untracked, stt.SensedPlan) and untracked.goal is not None
                and min(abs(float(np.linalg.norm(np.asarray(untracked.goal.center) - point))
                            - d) for d in evade.EVADE_DISTANCES) < 1e-9)
