"""``stt-codegen bench sensed --warehouse``: a warehouse floor with people crossing its
aisles, sensed at run time (docs/sensing.md).

The floor is the one of ``tests/specs/agv-warehouse.toml``: 20 m x 12 m, three racks
(1.2 m x 8 m, from the south wall), the cross aisle north of them. An omnidirectional base
(a single integrator, radius 0.3 m, 100 Hz) drives from the first aisle
(``[1.5, 2.5]^2``) to the last (``[17.5, 18.5] x [1.5, 2.5]``) within ``t_c = 40`` s, so
through the cross aisle. Each person is a disc of radius ``U[0.2, 0.35]`` m walking at
``U[0.5, 1]`` m/s along a straight line from a door to the door across, waiting 1 m
outside the first until a time ``U[0, 24]`` s and outside the other after: half of them
along one of the two middle aisles (crossing the cross aisle), half along the cross aisle
at a height ``U[8.5, 11.5]`` m, each way with even odds. The envelope (``[sensing]``): range 5 m,
latency 0.1 s, a measurement every 0.25 s, ``r_max = 0.35`` m, ``V = 1`` m/s (no
acceleration bound: a person starts and stops at once), replanning budget 0.25 s, horizon
0.5 s.
"""

from __future__ import annotations

import math

import numpy as np

from stt_codegen.runtime.sensed import WalkingObstacle

__all__ = ["AISLES", "DEPTH", "DOOR", "RACKS", "RACK_END", "WAREHOUSE", "WIDTH",
           "aisle_people"]

#: The floor's size, m.
WIDTH, DEPTH = 20.0, 12.0
#: The racks' extents along x, m (each from the south wall to :data:`RACK_END`).
RACKS = ((4.5, 5.7), (9.4, 10.6), (14.3, 15.5))
#: Where the racks end and the cross aisle begins, m.
RACK_END = 8.0
#: The middle aisles' centre lines, m (between the racks).
AISLES = (7.55, 12.45)
#: How far outside the floor's walls a person waits before walking in and after walking
#: out (at doors), m.
DOOR = 1.0
#: The floor, the base and the envelope (a spec dictionary).
WAREHOUSE = {
    "name": "warehouse-people", "prescribed_time": 40.0,
    "state_space": {"lower": [0.0, 0.0], "upper": [WIDTH, DEPTH]},
    "initial": {"lower": [1.5, 1.5], "upper": [2.5, 2.5], "half_width": [0.25, 0.25]},
    "target": {"lower": [17.5, 1.5], "upper": [18.5, 2.5]},
    "obstacles": [{"lower": [a, 0.0], "upper": [b, RACK_END]} for a, b in RACKS],
    "controller": {"rate_hz": 100.0},
    "plant": {"model": "single-integrator", "disturbance_amplitude": 0.05},
    "robot": {"radius": 0.3},
    "sensing": {"range": 5.0, "latency": 0.1, "period": 0.25, "max_obstacle_radius": 0.35,
                "max_obstacle_speed": 1.0, "replan_time": 0.25, "horizon": 0.5},
}


def aisle_people(rng: np.random.Generator, count: int, until: float
                 ) -> list[WalkingObstacle]:
    """``count`` people crossing the floor's aisles (module notes), seeded.

    Parameters
    ----------
    rng : numpy.random.Generator
        The episode's stream.
    count : int
        How many.
    until : float
        The episode's length, s: each starts walking before ``0.6 until``.

    Returns
    -------
    list of WalkingObstacle
        Each with a path of two rows (held before the first and after the last).

    Examples
    --------
    >>> import numpy as np
    >>> people = aisle_people(np.random.default_rng(0), 3, 40.0)
    >>> [len(p.path) for p in people]
    [2, 2, 2]
    """
    out = []
    for _ in range(count):
        radius = float(rng.uniform(0.2, 0.35))
        speed = float(rng.uniform(0.5, 1.0))
        start = float(rng.uniform(0.0, 0.6 * until))
        if rng.uniform() < 0.5:                 # along a middle aisle, door to door
            x = float(AISLES[rng.integers(len(AISLES))])
            a, b = (x, -DOOR), (x, DEPTH + DOOR)
        else:                                   # along the cross aisle, 0.5 m off its sides
            y = float(rng.uniform(RACK_END + 0.5, DEPTH - 0.5))
            a, b = (-DOOR, y), (WIDTH + DOOR, y)
        if rng.uniform() < 0.5:
            a, b = b, a
        end = start + math.dist(a, b) / speed
        out.append(WalkingObstacle(a, radius, path=((start, *a), (end, *b))))
    return out
