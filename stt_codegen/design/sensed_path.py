"""A replanned tube along a space-time path through where the sensed obstacles are headed.

The replanner (:mod:`.sensed`) designs each new tube for the certified horizon ``H`` and
a short foresight past it. An obstacle that moves slowly across the robot's way then looks
gone a few seconds ahead, and the tube waits for it to go, at every measurement. This step
plans the new tube's way through space and time against each sensed obstacle's
prediction over the whole tube, with the fleet's space-time A* (:mod:`.fleet_paths`):

* **Where each obstacle is headed.** Its shape moved along its velocity estimate
  (standing where it was seen without one), grown by the envelope's ``velocity_error``
  times the time since it was seen and by the robot's radius, over spans of
  :data:`PREDICTION_SPAN` from the tube's start to the path's last step
  (:func:`~.sensed.foresight_boxes`). A prediction, not a bound: it only steers the path.
* **The path.** Cells of :data:`~.fleet_paths.CELL` on the first two sensing dimensions,
  free of the static obstacles, the reachable boxes and the predictions taken where and
  when they lie (the start's cell left free for :data:`START_SECONDS`: the robot is there);
  on a third (a drone's height) the via boxes fly at one level (the start's, or one every
  :data:`LEVEL_STEP`, :func:`levels`: the one whose tube arrives first), reached first in
  the start's cell, and only the boxes near the level take cells;
  steps of ``CELL / speed``, the speed :data:`SPEED_FACTOR` times the free grid's shortest
  way over the prescribed time, within [:data:`MIN_SPEED`, :data:`MAX_SPEED`] (a path
  faster than the deadline leaves time for the next obstacle); the earliest arrival, up
  to :data:`LATE_SECONDS` past the prescribed time, with the target's cell clear for
  :data:`STAY_SECONDS` after it; at most :data:`MAX_EXPANSIONS` states.
* **The tube.** Via boxes along the path's straight runs, waits held
  (:func:`~.fleet_paths.space_time_segments`), at most :data:`MAX_SEGMENTS` reach segments
  (the default capacity of a controller with the tube as data); a path with more is
  shortcut by straight moves that keep clear (:func:`~.fleet_paths.shortcut`).

Nothing here is trusted: the tube is accepted only when its check
(:func:`~.search.check_tube`) against the spec's obstacles and the sensed obstacles'
reachable boxes over the horizon passes; the replanner then holds it to the region
certificate like every new tube (docs/sensing.md).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from ..spec.loader import Spec
from ..spec.motion import MovingObstacle
from ..tube.parameters import SMOOTHSTEP, TubeDesign
from .fleet_paths import ROOM, Reservations, SpaceTimeGrid, shortcut, space_time_path, \
    space_time_segments
from .gain import with_gain
from .result import METHOD_VIA, Design
from .search import base_design, check_tube
from .via import VIA_HALF_WIDTH

__all__ = ["LATE_SECONDS", "LEVEL_STEP", "MAX_EXPANSIONS", "MAX_SEGMENTS", "MAX_SPEED",
           "MIN_SPEED", "MOTION_SENSED_PATH", "PREDICTION_SPAN", "SPEED_FACTOR",
           "START_SECONDS", "STAY_SECONDS", "levels", "path_design"]

#: How a tube found by this step is named (``Design.motion``).
MOTION_SENSED_PATH = "sensed path"
#: The path's speed: this times the free grid's shortest way over the prescribed time,
#: state units per second, within [MIN_SPEED, MAX_SPEED].
SPEED_FACTOR, MIN_SPEED, MAX_SPEED = 2.5, 1.0, 2.0
#: The longest span of one predicted box, s.
PREDICTION_SPAN = 0.25
#: The most (cell, step) states the search expands (it runs in the replanner's budget).
MAX_EXPANSIONS = 20_000
#: How long the target's cell must stay clear of the predictions after the path's arrival,
#: s (an obstacle headed through the target later is met by a later plan: the tube stays).
STAY_SECONDS = 2.0
#: How much later than the prescribed time a path may arrive, s (the earliest is taken).
LATE_SECONDS = 6.0
#: How long the start's cell is left free of the reservations, s.
START_SECONDS = 0.5
#: The most reach segments of a path's tube.
MAX_SEGMENTS = 8
#: The spacing of the levels a path may fly at on a third sensing dimension (a drone's
#: height, :func:`levels`), state units.
LEVEL_STEP = 1.0


def path_design(local: Spec, hard: tuple[MovingObstacle, ...],
                predict: Callable[[float], tuple[MovingObstacle, ...]],
                dims: Sequence[int], growth: float = 0.0) -> Design | None:
    """A tube for ``local`` along a space-time path among predicted obstacles, certified
    against ``local``'s obstacles and the ``hard`` boxes; ``None`` when no path is found,
    its tube has more than :data:`MAX_SEGMENTS` segments, or its check fails.

    On a third sensing dimension (a drone's height) the path's grid is the first two, and
    its via boxes fly at one *level* on the third (the others keep the start's place):
    each of :func:`levels` is tried, and the certified tube that arrives first is taken
    (the nearest the start's level on a tie; the robot climbs or sinks to it first). A box
    takes cells only if it meets the band the via boxes sweep at the level, grown by
    ``growth`` (a prediction that near the level will be a reachable box that meets it,
    when the robot comes by).

    Parameters
    ----------
    local : Spec
        The new tube's task in its own time (initial box, target, prescribed time, known
        obstacles).
    hard : tuple of MovingObstacle
        The sensed obstacles' reachable boxes (grown by the robot's radius): the tube is
        certified to miss them.
    predict : callable
        ``predict(t_to)``: the predicted boxes (grown by the robot's radius) from the
        tube's start to ``t_to`` in its time.
    dims : sequence of int
        The sensing dimensions, at least two.
    growth : float
        How much a sensed obstacle's reachable box grows past its shape within a
        replanning's span (``V (t_s - t_m + H)``), state units; used off the grid only.

    Returns
    -------
    Design or None
    """
    started = time.perf_counter()
    if len(dims) < 2 or local.input_bound is not None:
        return None
    d = list(dims[:2])
    t_c = float(local.prescribed_time)
    grid = SpaceTimeGrid.of(local, d)
    cells = grid.index(np.asarray(local.initial_state, dtype=float)[d])
    goal = grid.index(np.asarray(local.target_center, dtype=float)[d])
    if cells is None or goal is None:
        return None
    need = float(grid.steps_to(goal)[cells])
    if not math.isfinite(need):
        return None
    # the path's speed: the free grid's shortest way in a share of the prescribed time
    speed = min(max(SPEED_FACTOR * need * grid.cell / t_c, MIN_SPEED), MAX_SPEED)
    step = grid.cell / speed
    last = max(math.floor((t_c + LATE_SECONDS) / step), math.ceil(SPEED_FACTOR * need))
    # the boxes the path keeps clear of, and the base design, are the same at every level
    search = _Search(grid, cells, goal, speed, step, last, hard + predict(last * step),
                     base_design(local))
    best = None
    for level in levels(local, dims):
        found = _at_level(local, hard, dims, level, growth, search, started)
        if found is not None and (best is None or found.tube.segments[-1].end
                                  < best.tube.segments[-1].end):
            best = found
    return best


class _Search(NamedTuple):
    """The grid of :func:`path_design`, the start's and the target's cells, the path's
    speed (state units per second), its step (s), its latest step, the boxes it keeps
    clear of (the hard ones and the predictions) and the base design."""

    grid: SpaceTimeGrid
    cells: tuple[int, int]
    goal: tuple[int, int]
    speed: float
    step: float
    last: int
    boxes: tuple[MovingObstacle, ...]
    base: TubeDesign


def levels(local: Spec, dims: Sequence[int]) -> list[np.ndarray]:
    """The places of a path's via boxes off its grid: the start's; with a third sensing
    dimension, also every :data:`LEVEL_STEP` across the state space on it (the via box
    and :data:`~.fleet_paths.ROOM` inside it), the nearest the start's first (the order
    ties are broken in).

    Parameters
    ----------
    local : Spec
    dims : sequence of int
        The sensing dimensions.

    Returns
    -------
    list of ndarray, shape (len(dims) - 2,)
        One level each; a single empty one on two dimensions.
    """
    x0 = np.asarray(local.initial_state, dtype=float)
    rest = list(dims[2:])
    start = x0[rest]
    if not rest:
        return [start]
    k = rest[0]
    margin = VIA_HALF_WIDTH + ROOM
    lo, hi = local.state_space.lower[k] + margin, local.state_space.upper[k] - margin
    heights = lo + LEVEL_STEP * np.arange(max(0, math.floor((hi - lo) / LEVEL_STEP)) + 1)
    heights = sorted((h for h in heights if abs(h - start[0]) >= LEVEL_STEP / 2),
                     key=lambda h: (abs(h - start[0]), h))
    out = [start]
    for h in heights:
        level = start.copy()
        level[0] = h
        out.append(level)
    return out


def _at_level(local: Spec, hard: tuple[MovingObstacle, ...], dims: Sequence[int],
              level: np.ndarray, growth: float, search: _Search,
              started: float) -> Design | None:
    """:func:`path_design` with the via boxes at ``level`` on ``dims[2:]``: a box clear
    of the band they sweep there, grown by ``growth``, takes no cell (the check is on
    every dimension)."""
    d = list(dims[:2])
    grid, cells, goal, speed, step, last, boxes, base = search
    t_c = float(local.prescribed_time)
    room = VIA_HALF_WIDTH + ROOM + growth
    band = [(k, v - room, v + room) for k, v in zip(dims[2:], level)]
    taken = Reservations(grid, step, last + 1)
    for ob in boxes:
        centre, half = np.asarray(ob.centres[0]), np.asarray(ob.half_size)
        at = {k: j for j, k in enumerate(ob.dims)}
        if any(centre[at[k]] + half[at[k]] <= lo or centre[at[k]] - half[at[k]] >= hi
               for k, lo, hi in band):
            continue
        on = [at[k] for k in d]
        taken.add(np.array([ob.active[0]]), np.array([ob.active[1]]),
                  (centre - half)[on][None], (centre + half)[on][None])
    # to another level the robot first climbs (or sinks) in its start cell, at the path's
    # speed: the search starts from there, that many steps later
    off = np.asarray(local.initial_state, dtype=float)[list(dims[2:])]
    climb = (math.ceil(float(np.max(np.abs(level - off))) / speed / step)
             if len(level) else 0)
    if climb >= last:
        return None
    taken.taken, taken.steps = taken.taken[climb:], taken.steps - climb
    # the robot is in its start cell now: a box grown into it leaves the start free for
    # the first steps (the check decides whether the tube really keeps clear)
    taken.taken[:math.ceil(START_SECONDS / step) + 1, cells[0], cells[1]] = False
    path = space_time_path(grid, taken, cells, goal, last - climb, MAX_EXPANSIONS,
                           math.ceil(STAY_SECONDS / step))
    if path is None or len(path) < 2:        # none, or at the goal already: nothing new
        return None

    def climbed(moves: list[tuple[int, int, int]]) -> list[tuple[int, int, int]]:
        return ([(cells[0], cells[1], 0)] + [(i, j, k + climb) for i, j, k in moves]
                if climb else moves)

    # the via boxes take their place off the grid from the base's state (the level)
    flying = base
    if len(level):
        at_level = np.array(base.initial_state, dtype=float)
        at_level[list(dims[2:])] = level
        flying = replace(base, initial_state=tuple(float(v) for v in at_level))
    segments = space_time_segments(climbed(path), grid, flying, step, SMOOTHSTEP)
    if len(segments) > MAX_SEGMENTS:     # fewer knots: straight moves where they keep clear
        segments = space_time_segments(climbed(shortcut(path, grid, taken)), grid, flying,
                                       step, SMOOTHSTEP)
    if len(segments) > MAX_SEGMENTS:
        return None
    # a path later than the prescribed time is the tube's prescribed time (a late plan)
    spec = replace(local, moving_obstacles=local.moving_obstacles + hard,
                   prescribed_time=max(t_c, segments[-1].end))
    tube = replace(base, segments=segments, prescribed_time=spec.prescribed_time)
    found = check_tube(tube, spec)
    if not found.passed:
        return None
    return Design(with_gain(tube, found.min_width, spec), METHOD_VIA, found,
                  time.perf_counter() - started, spec=spec, motion=MOTION_SENSED_PATH)
