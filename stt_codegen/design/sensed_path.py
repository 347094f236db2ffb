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
* **The path.** Cells of :data:`~.fleet_paths.CELL` on the two sensing dimensions, free
  of the static obstacles, the reachable boxes and the predictions taken where and when
  they lie (the start's cell left free for :data:`START_SECONDS`: the robot is there);
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

import numpy as np

from ..spec.loader import Spec
from ..spec.motion import MovingObstacle
from ..tube.parameters import SMOOTHSTEP
from .fleet_paths import Reservations, SpaceTimeGrid, shortcut, space_time_path, \
    space_time_segments
from .gain import with_gain
from .result import METHOD_VIA, Design
from .search import base_design, check_tube

__all__ = ["LATE_SECONDS", "MAX_EXPANSIONS", "MAX_SEGMENTS", "MAX_SPEED", "MIN_SPEED",
           "MOTION_SENSED_PATH", "PREDICTION_SPAN", "SPEED_FACTOR", "START_SECONDS",
           "STAY_SECONDS", "path_design"]

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


def path_design(local: Spec, hard: tuple[MovingObstacle, ...],
                predict: Callable[[float], tuple[MovingObstacle, ...]],
                dims: Sequence[int]) -> Design | None:
    """A tube for ``local`` along a space-time path among predicted obstacles, certified
    against ``local``'s obstacles and the ``hard`` boxes; ``None`` when no path is found,
    its tube has more than :data:`MAX_SEGMENTS` segments, or its check fails.

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
        The two sensing dimensions.

    Returns
    -------
    Design or None
    """
    started = time.perf_counter()
    if len(dims) != 2 or local.input_bound is not None:
        return None
    d = list(dims)
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
    taken = Reservations(grid, step, last + 1)
    for ob in hard + predict(last * step):
        centre, half = np.asarray(ob.centres[0]), np.asarray(ob.half_size)
        taken.add(np.array([ob.active[0]]), np.array([ob.active[1]]),
                  (centre - half)[None], (centre + half)[None])
    # the robot is in its start cell now: a box grown into it leaves the start free for
    # the first steps (the check decides whether the tube really keeps clear)
    taken.taken[:math.ceil(START_SECONDS / step) + 1, cells[0], cells[1]] = False
    path = space_time_path(grid, taken, cells, goal, last, MAX_EXPANSIONS,
                           math.ceil(STAY_SECONDS / step))
    if path is None or len(path) < 2:        # none, or at the goal already: nothing new
        return None
    base = base_design(local)
    segments = space_time_segments(path, grid, base, step, SMOOTHSTEP)
    if len(segments) > MAX_SEGMENTS:     # fewer knots: straight moves where they keep clear
        segments = space_time_segments(shortcut(path, grid, taken), grid, base, step,
                                       SMOOTHSTEP)
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
