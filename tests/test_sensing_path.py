"""The replanner's space-time path among where the sensed obstacles are headed
(``design/sensed_path.py``, docs/sensing.md "How the next plan is made")."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design import sensed as sensed_module
from stt_codegen.design.fleet_paths import (Reservations, SpaceTimeGrid, shortcut,
                                             space_time_path)
from stt_codegen.design.sensed_path import MAX_SEGMENTS, MOTION_SENSED_PATH, path_design
from test_sensing_replan import CORRIDOR, oracle_tube


@pytest.fixture(scope="module")
def corridor():
    design = stt.design_tube(stt.Spec.from_dict(CORRIDOR))
    plan = stt.start_plan(design)
    here = np.asarray(sensed_module._box_at(plan, 1.0, design.spec.state_space).center)
    return design, plan, here


#: A person standing in the hall's middle, drifting at 0.05 m/s: they stay in the way.
STANDING = stt.SensedObstacle.ball((3.0, 2.0), 0.35, seen_at=1.0, velocity=(0.0, 0.05))


def test_a_slow_person_in_the_way_is_gone_round_before_the_deadline(corridor):
    """The new tube goes round where the person is headed over its whole time (the
    prediction, at every sample until it arrives), not only over the certified horizon,
    and arrives before ``t_c``; it is certified like every plan."""
    design, plan, here = corridor
    new = stt.replan(plan, 1.0, here, [STANDING])
    assert isinstance(new, stt.SensedPlan), new.reason
    assert new.design.motion == MOTION_SENSED_PATH and not new.kept
    assert new.arrival <= CORRIDOR["prescribed_time"]
    assert new.sensed_margin > 0 and new.region_margin > 0
    assert len(new.design.tube.segments) <= MAX_SEGMENTS and not new.design.tube.circumvents
    reach = CORRIDOR["robot"]["radius"]
    ts, lows, highs = oracle_tube(new.design.tube, new.arrival - new.start, 100.0)
    for t, lo, hi in zip(ts, lows, highs):
        seen = new.start + t - STANDING.seen_at
        centre = np.asarray(STANDING.centre) + np.asarray(STANDING.velocity) * seen
        nearest = np.clip(centre, lo[:2], hi[:2])
        assert np.linalg.norm(nearest - centre) > STANDING.extent + reach, t


def test_the_path_is_not_tried_under_an_actuator_bound(corridor):
    """Its tube carries no input proof, so a spec with ``[actuator]`` keeps the design
    step (whose tubes carry it)."""
    design, plan, here = corridor
    bounded = dataclasses.replace(plan.local, input_bound=(5.0, 5.0))
    assert path_design(bounded, (), lambda t_to: (), (0, 1)) is None
    assert path_design(plan.local, (), lambda t_to: (), (0, 1)) is not None


def test_the_goal_stays_clear_only_as_long_as_asked():
    """``stay_steps``: an obstacle crossing the goal long after the arrival does not stop
    the path; to the horizon (the default) it does, until it has crossed."""
    grid = SpaceTimeGrid(np.zeros(2), 1.0, np.ones((5, 3), dtype=bool), (0, 1))
    taken = Reservations(grid, 1.0, 20)
    taken.taken[15, 4, 1] = True
    assert space_time_path(grid, taken, (0, 1), (4, 1), 20, stay_steps=5)[-1] == (4, 1, 4)
    assert space_time_path(grid, taken, (0, 1), (4, 1), 20)[-1] == (4, 1, 17)
    assert space_time_path(grid, taken, (0, 1), (4, 1), 20, stay_steps=11)[-1] == (4, 1, 17)


def test_a_robot_waiting_in_the_target_steps_out_of_an_obstacles_way_early(corridor,
                                                                          monkeypatch):
    """In the target after ``t_c``, a person walks at it along the hall: their reachable
    box over the horizon misses the target, so the tube could be kept, but where they are
    headed 2 s later does not. Taken for a straight walk (no obstacle closing: the
    pursuit rule of docs/sensing.md, step 1, off), the robot leaves along a path that
    keeps clear of their prediction and comes back once they have passed. Closing on the
    robot at 0.6 m/s, they are taken to turn after it, and the robot leaves by an escape.
    A person walking past far from the target leaves the tube kept."""
    design, plan, _ = corridor
    person = stt.SensedObstacle.ball((3.0, 2.0), 0.35, seen_at=11.0, velocity=(0.6, 0.0))
    fled = stt.replan(plan, 11.0, (5.5, 2.0), [person])
    assert isinstance(fled, stt.SensedPlan) and not fled.kept and fled.goal is not None
    monkeypatch.setattr(sensed_module, "_closing", lambda ob, point: False)
    away = stt.replan(plan, 11.0, (5.5, 2.0), [person])
    assert isinstance(away, stt.SensedPlan), away.reason
    assert not away.kept and away.design.motion == MOTION_SENSED_PATH
    assert away.sensed_margin > 0 and away.region_margin > 0
    reach = CORRIDOR["robot"]["radius"]
    ts, lows, highs = oracle_tube(away.design.tube, away.arrival - away.start + 2.0, 100.0)
    for t, lo, hi in zip(ts, lows, highs):
        centre = np.asarray(person.centre) + np.asarray(person.velocity) * (
            away.start + t - person.seen_at)
        nearest = np.clip(centre, lo[:2], hi[:2])
        assert np.linalg.norm(nearest - centre) > person.extent + reach, t
    target = design.spec.target_set
    assert np.all(lows[-1] >= np.array(target.lower)) and np.all(highs[-1] <= target.upper)
    passing = dataclasses.replace(person, centre=(3.0, 0.45))
    assert stt.replan(plan, 11.0, (5.5, 2.0), [passing]).kept


def test_a_shortcut_keeps_clear_of_what_the_path_went_round():
    """Straight moves replace the path's steps where no taken cell lies on them (at every
    step, as a smooth-step segment), and only there."""
    grid = SpaceTimeGrid(np.zeros(2), 1.0, np.ones((9, 5), dtype=bool), (0, 1))
    taken = Reservations(grid, 1.0, 20)
    taken.taken[:, 4, 1:4] = True                     # a wall across the middle rows
    path = space_time_path(grid, taken, (0, 2), (8, 2), 20)
    short = shortcut(path, grid, taken)
    assert short[0] == path[0] and short[-1] == path[-1] and len(short) < len(path)
    assert set(short) <= set(path)
    merged = [(a, b) for a, b in zip(short, short[1:]) if path.index(b) > path.index(a) + 1]
    assert merged
    for a, b in merged:                  # the path's own moves are the search's to check
        for k in range(a[2], b[2] + 1):
            tau = (k - a[2]) / (b[2] - a[2])
            p = np.add(a[:2], tau ** 3 * (10 - 15 * tau + 6 * tau ** 2) * np.subtract(b[:2],
                                                                                     a[:2]))
            touched = {(i, j) for i in (math.floor(p[0] + 1e-9), math.ceil(p[0] - 1e-9))
                       for j in (math.floor(p[1] + 1e-9), math.ceil(p[1] - 1e-9))}
            assert not any(taken.taken[k, i, j] for i, j in touched), (a, b, k)
