"""``stt-codegen bench sensed --rooms``: a drone's room in three dimensions with balls
flying through it, sensed at run time (docs/sensing.md, "In three dimensions").

The room, the drone and the envelope are ``tests/specs/drone-sensed.toml``'s: 10 m x 10 m
x 4 m; a drone under velocity control (a 3-D single integrator, radius 0.2 m, 100 Hz)
flies from ``[0.5, 1.5]^3`` to ``[8.5, 9.5]^2 x [2, 3]`` within ``t_c = 14`` s; range 5 m,
latency 0.05 s, a measurement every 0.25 s, ``r_max = 0.5`` m, ``V = 1`` m/s (no
acceleration bound), horizon 0.5 s. Each ball has a radius ``U[0.1, 0.5]`` m, a centre
drawn uniformly in the room at least :data:`CLEAR_OF_START` from the start's centre, and
velocity components ``U[-0.57, 0.57]`` m/s (its speed below ``V``); it flies straight, out
through the walls.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stt_codegen.runtime.sensed import WalkingObstacle

__all__ = ["CLEAR_OF_START", "ROOM", "flying_balls"]

#: The drone's spec (the room, the drone, the envelope).
ROOM = Path(__file__).resolve().parents[2] / "specs" / "drone-sensed.toml"
#: Balls start at least this far from the start set's centre, m.
CLEAR_OF_START = 2.5
#: The largest velocity component, m/s (``sqrt(3)`` times it is below the envelope's 1 m/s).
MOST_COMPONENT = 0.57


def flying_balls(rng: np.random.Generator, count: int, lower, upper, start,
                 max_radius: float) -> list[WalkingObstacle]:
    """``count`` balls flying straight through the room (module notes), seeded.

    Parameters
    ----------
    rng : numpy.random.Generator
    count : int
    lower, upper : sequence of float, length 3
        The room's corners, m.
    start : sequence of float, length 3
        The start set's centre, m.
    max_radius : float
        The envelope's ``r_max``, m.

    Returns
    -------
    list of WalkingObstacle
    """
    balls: list[WalkingObstacle] = []
    while len(balls) < count:
        centre = rng.uniform(lower, upper)
        if np.linalg.norm(centre - np.asarray(start, dtype=float)) < CLEAR_OF_START:
            continue
        radius = float(rng.uniform(0.1, max_radius))
        velocity = rng.uniform(-MOST_COMPONENT, MOST_COMPONENT, 3)
        balls.append(WalkingObstacle(tuple(float(c) for c in centre), radius,
                                     velocity=tuple(float(v) for v in velocity)))
    return balls
