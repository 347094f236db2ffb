"""Space-time A* among placed tubes (stt_codegen.design.fleet_paths): the grid's free cells,
the reservations, paths that keep clear of every taken cell at every step, and the reach
segments timed as the path."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

import stt_codegen as stt
from stt_codegen.design.fleet_paths import (ROOM, STATIC_ROOM, Reservations, SpaceTimeGrid,
                                            space_time_path, space_time_segments)
from stt_codegen.design.via import VIA_HALF_WIDTH


def _open(nx=7, ny=5):
    return SpaceTimeGrid(np.zeros(2), 1.0, np.ones((nx, ny), dtype=bool), (0, 1))


def _keeps_clear(path, grid, taken):
    """Every move keeps both its cells clear over its steps, waits their cell, and moves
    only to free neighbours (diagonals: both side cells free, two steps)."""
    busy = taken.taken
    assert busy[path[0][2], path[0][0], path[0][1]] == False  # noqa: E712
    for (i, j, k), (a, b, kk) in zip(path, path[1:]):
        di, dj = a - i, b - j
        assert max(abs(di), abs(dj)) <= 1 and grid.free[a, b]
        assert kk - k == (2 if di and dj else 1)
        if di and dj:
            assert grid.free[i + di, j] and grid.free[i, j + dj]
            assert not busy[k:kk + 1, i + di, j].any() and not busy[k:kk + 1, i, j + dj].any()
        assert not busy[k:kk + 1, i, j].any() and not busy[k:kk + 1, a, b].any()


def test_a_path_on_an_empty_grid_is_straight_and_earliest():
    grid = _open()
    path = space_time_path(grid, Reservations(grid, 1.0, 20), (0, 2), (6, 2), 20)
    assert [p[:2] for p in path] == [(i, 2) for i in range(7)]
    assert path[-1][2] == 6


def test_a_path_waits_or_goes_round_a_robot_crossing_its_way():
    grid = _open()
    taken = Reservations(grid, 1.0, 20)
    # a robot sweeping down column 3 over steps 1..6: the straight way meets it
    taken.add(np.array([1.0]), np.array([6.0]), np.array([[3.0, 0.0]]) + ROOM,
              np.array([[3.0, 4.0]]) - ROOM)
    assert taken.taken[1:7, 3, :].all() and not taken.taken[8:, 3, :].any()
    assert not taken.taken[:, 2, :].any() and not taken.taken[:, 4, :].any()
    path = space_time_path(grid, taken, (0, 2), (6, 2), 20)
    _keeps_clear(path, grid, taken)
    assert path[-1][:2] == (6, 2) and path[-1][2] > 6       # it had to wait
    # no path when the arrival is due before the column clears
    assert space_time_path(grid, taken, (0, 2), (6, 2), 6) is None


def test_a_diagonal_does_not_cut_a_taken_cells_corner():
    """A diagonal move sweeps the corners of the two cells beside it: with one of them
    taken over the move's steps it is not made (as beside a static obstacle); once that
    cell is free again, it is."""
    grid = _open(3, 3)
    taken = Reservations(grid, 1.0, 20)
    taken.taken[0:3, 1, 0] = True                    # beside the diagonal (0, 0) -> (1, 1)
    path = space_time_path(grid, taken, (0, 0), (1, 1), 20)
    _keeps_clear(path, grid, taken)
    assert [p[:2] for p in path] == [(0, 0), (0, 1), (1, 1)] and path[-1][2] == 2
    later = Reservations(grid, 1.0, 20)
    later.taken[0:3, 1, 0] = True
    later.taken[0:3, 0, 1] = True                    # both sides taken until step 2
    path = space_time_path(grid, later, (0, 0), (1, 1), 20)
    _keeps_clear(path, grid, later)
    assert path[-1][2] == 5                           # waits to step 3, then the diagonal
    assert [p[:2] for p in path][-2:] == [(0, 0), (1, 1)]


def test_the_goal_must_stay_clear_after_the_arrival():
    grid = _open()
    taken = Reservations(grid, 1.0, 20)
    taken.add(np.array([15.0]), np.array([np.inf]), np.array([[6.0, 2.0]]) + ROOM,
              np.array([[6.0, 2.0]]) - ROOM)               # a robot parks on the goal
    assert taken.taken[20, 6, 2] and not taken.taken[14, 6, 2]
    assert space_time_path(grid, taken, (0, 2), (6, 2), 20) is None
    assert space_time_path(grid, taken, (0, 2), (6, 3), 20) is not None


def test_a_walled_goal_or_an_occupied_start_has_no_path():
    free = np.ones((7, 5), dtype=bool)
    free[3, :] = False                                      # a wall across the grid
    grid = SpaceTimeGrid(np.zeros(2), 1.0, free, (0, 1))
    taken = Reservations(grid, 1.0, 30)
    assert space_time_path(grid, taken, (0, 2), (6, 2), 30) is None
    assert space_time_path(grid, taken, (3, 2), (0, 2), 30) is None
    assert space_time_path(grid, taken, (0, 2), None, 30) is None


def _earliest_arrival(grid, taken, start, goal, last_step, stay_steps):
    """The earliest arrival step by breadth-first search over (cell, step), the moves'
    rules written out (a wait keeps its cell clear at the next step, a move keeps both
    cells clear over its steps, a diagonal its two side cells too, free and clear); the
    goal clear for ``stay_steps`` steps after the arrival (to the horizon for None)."""
    busy, free = taken.taken, grid.free
    horizon = busy.shape[0] - 1
    nx, ny = free.shape

    def clear(cell, k0, k1):
        return free[cell] and not busy[k0:min(k1, horizon) + 1, cell[0], cell[1]].any()

    def stays(k):
        end = horizon if stay_steps is None else min(k + stay_steps, horizon)
        return not busy[k:end + 1, goal[0], goal[1]].any()

    now = {0: {start}}
    for k in range(0, last_step + 1):
        for cell in sorted(now.get(k, ())):
            if cell == goal and stays(k):
                return k
            if k >= min(last_step, horizon):
                continue
            if not busy[k + 1, cell[0], cell[1]]:
                now.setdefault(k + 1, set()).add(cell)
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    a, b, cost = cell[0] + di, cell[1] + dj, 1 + (di != 0 and dj != 0)
                    if (di, dj) == (0, 0) or not (0 <= a < nx and 0 <= b < ny) \
                            or k + cost > last_step:
                        continue
                    sides = [(cell[0] + di, cell[1]), (cell[0], cell[1] + dj)] if cost == 2 else []
                    if all(clear(c, k, k + cost) for c in [cell, (a, b)] + sides):
                        now.setdefault(k + cost, set()).add((a, b))
    return None


def test_the_path_is_the_earliest_among_random_robots_and_walls():
    """On random grids (walls, boxes of placed robots over random spans, some parked for
    good): the search finds a path exactly when breadth-first search over (cell, step)
    finds one, it arrives at the same earliest step, keeps clear of every taken cell and
    leaves the goal clear as asked."""
    rng = np.random.default_rng(11)
    found = 0
    for _ in range(150):
        nx, ny = (int(v) for v in rng.integers(3, 12, 2))
        free = rng.random((nx, ny)) > rng.uniform(0.0, 0.35)
        grid = SpaceTimeGrid(np.zeros(2), 1.0, free, (0, 1))
        horizon = int(rng.integers(4, 40))
        taken = Reservations(grid, 1.0, horizon)
        count = int(rng.integers(0, 12))
        t_start = rng.uniform(0, horizon, count)
        t_end = t_start + rng.uniform(0, 8, count)
        t_end[rng.random(count) < 0.2] = np.inf
        lower = rng.uniform(0, max(nx, ny), (count, 2))
        taken.add(t_start, t_end, lower, lower + rng.uniform(0, 2.5, (count, 2)))
        start = tuple(int(v) for v in rng.integers(0, (nx, ny)))
        goal = tuple(int(v) for v in rng.integers(0, (nx, ny)))
        last = int(rng.integers(0, horizon + 1))
        stay = None if rng.random() < 0.5 else int(rng.integers(0, 6))
        path = space_time_path(grid, taken, start, goal, last, stay_steps=stay)
        want = _earliest_arrival(grid, taken, start, goal, last, stay) \
            if free[start] and free[goal] else None
        assert (path is None) == (want is None)
        if path is not None:
            found += 1
            assert path[0] == (*start, 0) and path[-1] == (*goal, want)
            # the start's cell may be taken at step 0 (the robot is there): from its first move
            _keeps_clear(path if not taken.taken[0][start] else path[1:], grid, taken)
    assert found > 30


def test_the_grid_keeps_room_from_walls_and_obstacles():
    spec = stt.load_fleet("warehouse-fleet").robots[0].spec
    grid = SpaceTimeGrid.of(spec, (0, 1))
    lower, upper = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    ii, jj = np.nonzero(grid.free)
    centres = grid.origin + grid.cell * np.stack([ii, jj], axis=1)
    assert np.all(centres - STATIC_ROOM >= lower[:2] - 1e-9)
    assert np.all(centres + STATIC_ROOM <= upper[:2] + 1e-9)
    obstacles = spec.obstacle_boxes()
    assert obstacles
    for ob in obstacles:
        lo, hi = np.array(ob.lower)[:2], np.array(ob.upper)[:2]
        inside = np.all((centres - STATIC_ROOM < hi) & (centres + STATIC_ROOM > lo), axis=1)
        assert not inside.any()
    assert 0.2 < grid.free.mean() < 1.0
    # index: the start's nearest free cell lies within a cell of it
    start = grid.index(np.array(spec.initial_state)[:2])
    assert start is not None and grid.free[start]
    assert np.max(np.abs(grid.centre(start) - np.array(spec.initial_state)[:2])) <= grid.cell


def test_the_segments_follow_the_path_in_time_and_hold_the_waits():
    grid = _open()
    base = SimpleNamespace(initial_state=(0.0, 2.0), initial_lower=(-0.3, 1.7),
                           initial_upper=(0.3, 2.3), target_lower=(5.7, 3.7),
                           target_upper=(6.3, 4.3))
    path = [(0, 2, 0), (1, 2, 1), (2, 2, 2), (2, 2, 3), (2, 2, 4), (3, 2, 5), (4, 3, 7),
            (5, 4, 9), (6, 4, 10)]
    segs = space_time_segments(path, grid, base, 0.5, "smoothstep")
    assert segs[0].start == 0.0 and segs[-1].end == 10 * 0.5
    assert all(a.end == b.start for a, b in zip(segs, segs[1:]))
    assert segs[0].lower_from == base.initial_lower and segs[-1].upper_to == base.target_upper
    assert all(a.lower_to == b.lower_from for a, b in zip(segs, segs[1:]))
    # the wait at (2, 2) over steps 2..4 is a segment holding the via box around (2, 2)
    held = [s for s in segs if s.lower_from == s.lower_to]
    assert len(held) == 1 and (held[0].start, held[0].end) == (1.0, 2.0)
    assert np.allclose(held[0].lower_from, np.array([2.0, 2.0]) - VIA_HALF_WIDTH)
    assert np.allclose(held[0].upper_from, np.array([2.0, 2.0]) + VIA_HALF_WIDTH)
