"""Seeded random moving obstacles for benchmarks (``bench tasks`` draws 0-4).

:func:`random_moving_obstacles` returns spec-dict ``[[obstacles]]`` entries
(docs/moving-obstacles.md) for an arena given as a :class:`~stt_codegen.spec.loader.Spec`.
The protocol, fixed here:

* a box of side uniform in ``[SIZE_MIN, SIZE_MAX]`` m on the first two state dimensions
  (it spans the others);
* one of three motions, equally likely: a *crossing* (``velocity``: it enters at a random
  point of one of the four edges of the arena and drives towards a random point of the
  opposite edge at a speed uniform in ``[SPEED_MIN, SPEED_MAX]`` m/s, active until it has
  left), a *path* (``path``: three waypoints uniform in the arena at times 0, ``t_c / 2``,
  ``t_c``) or a *blink* (``active`` only: a still box present on a window of length uniform
  in ``[0.1, 0.4] t_c`` starting uniformly in ``[0, 0.8 t_c]``);
* an obstacle that ever meets the start set or the target (or a box of ``keep_clear``), at
  any time it is active, is drawn again (up to :data:`MAX_DRAWS` times, then left out).

Every number comes from ``rng`` in a fixed order, so the same generator state gives the
same entries.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import Box, Spec
from stt_codegen.spec.motion import moving_obstacle
from stt_codegen.spec.schema import BoxObstacle

__all__ = ["random_moving_obstacles"]

#: Side of a moving box, metres (state units).
SIZE_MIN, SIZE_MAX = 0.3, 0.6
#: Speed of a crossing box, state units per second.
SPEED_MIN, SPEED_MAX = 0.3, 1.0
#: Draws allowed for one obstacle before it is left out.
MAX_DRAWS = 100
#: Most obstacles drawn.
MAX_COUNT = 4


def _crossing(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, side: float,
              t_c: float) -> dict[str, Any]:
    edge = int(rng.integers(4))                  # 0: left, 1: right, 2: bottom, 3: top
    axis, far = edge // 2, edge % 2              # axis 0: a vertical edge
    along = 1 - axis
    a = float(rng.uniform(lo[along], hi[along] - side))
    b = float(rng.uniform(lo[along], hi[along] - side))
    speed = float(rng.uniform(SPEED_MIN, SPEED_MAX))
    start = np.empty(2)
    end = np.empty(2)
    start[along], end[along] = a, b
    start[axis] = hi[axis] - side if far else lo[axis]
    end[axis] = lo[axis] if far else hi[axis] - side
    distance = float(np.linalg.norm(end - start))
    duration = distance / speed
    velocity = (end - start) / duration
    t_on = float(rng.uniform(0.0, 0.5 * t_c))
    return {"lower": [float(start[0]), float(start[1])],
            "upper": [float(start[0] + side), float(start[1] + side)],
            "velocity": [float(velocity[0]), float(velocity[1])],
            "active": [t_on, t_on + duration]}


def _path(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, side: float,
          t_c: float) -> dict[str, Any]:
    corners = [rng.uniform(lo, hi - side) for _ in range(3)]
    rows = [[t] + [float(c + side / 2) for c in corner]
            for t, corner in zip((0.0, 0.5 * t_c, t_c), corners)]
    first = corners[0]
    return {"lower": [float(first[0]), float(first[1])],
            "upper": [float(first[0] + side), float(first[1] + side)], "path": rows}


def _blink(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, side: float,
           t_c: float) -> dict[str, Any]:
    corner = rng.uniform(lo, hi - side)
    t_on = float(rng.uniform(0.0, 0.8 * t_c))
    length = float(rng.uniform(0.1, 0.4)) * t_c
    return {"lower": [float(corner[0]), float(corner[1])],
            "upper": [float(corner[0] + side), float(corner[1] + side)],
            "active": [t_on, t_on + length]}


_MOTIONS = (_crossing, _path, _blink)


def random_moving_obstacles(rng: np.random.Generator, arena: Spec, count: int | None = None,
                            keep_clear: Sequence[Box] = ()) -> list[dict[str, Any]]:
    """Random moving obstacles for ``arena``, as spec-dict ``[[obstacles]]`` entries.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness (e.g. ``numpy.random.default_rng([seed, index])``).
    arena : Spec
        Its state space (at least 2-D: the boxes move on dimensions 0 and 1), initial set,
        target set and ``t_c``.
    count : int, optional
        How many, ``0 <= count <= 4``; default drawn uniformly from 0..4 with ``rng``.
    keep_clear : sequence of Box, optional
        More boxes (full state dimension) no obstacle may ever meet, e.g. a task's reach
        boxes.

    Returns
    -------
    list of dict
        At most ``count`` entries (``lower``, ``upper`` and ``velocity`` + ``active``, or
        ``path``, or ``active``), each never meeting the initial set, the target or a box
        of ``keep_clear`` while active; an obstacle not found in :data:`MAX_DRAWS` draws is
        left out. Append them to the spec dict's ``obstacles``.

    Raises
    ------
    SpecError
        ``count`` outside ``0..4`` (field ``count``), or ``arena`` of dimension 1 (field
        ``arena``).
    """
    if arena.dimension < 2:
        raise SpecError("arena", "moving obstacles need at least 2 state dimensions")
    if count is None:
        count = int(rng.integers(0, MAX_COUNT + 1))
    if not 0 <= count <= MAX_COUNT:
        raise SpecError("count", f"must be in 0..{MAX_COUNT}, got {count!r}")
    lo = np.array(arena.state_space.lower[:2])
    hi = np.array(arena.state_space.upper[:2])
    t_c = arena.prescribed_time
    clear = [arena.initial_set, arena.target_set, *keep_clear]
    out: list[dict[str, Any]] = []
    for j in range(count):
        for _ in range(MAX_DRAWS):
            side = float(rng.uniform(SIZE_MIN, min(SIZE_MAX, *(0.5 * (hi - lo)))))
            entry = _MOTIONS[int(rng.integers(len(_MOTIONS)))](rng, lo, hi, side, t_c)
            box = (tuple(entry["lower"]), tuple(entry["upper"]))
            ob = moving_obstacle(BoxObstacle.model_validate(entry), f"obstacles[{j}]", j,
                                 (0, 1), *box)
            if not any(ob.meeting_times(b.lower, b.upper, 0.0, math.inf) for b in clear):
                out.append(entry)
                break
    return out
