"""``stt-codegen bench sensed --script``: Real-Time STT's own 2-D scenario, its five
circles, sensed at run time (docs/sensing.md).

Real-Time Spatiotemporal Tubes for Dynamic Unsafe Sets (RA-L 2025, arXiv 2512.06151) ship
a 2-D script (``main2D.m`` in FocasLab's repository): a point robot starts at
``(0.5, 1.5)`` (its tube at ``(1, 1)``), its target is the disc of radius 1 around
``(7, 10)``, ``t_c = 16`` s, the plot spans ``[0, 8] x [0, 11.25]``, and five circles of
radius 0.5 move straight at constant velocities (speeds 0.2 to 0.45 m/s) from fixed
starts. Here: the same arena as the state space, the start set ``[0.5, 1.5]^2`` (it holds
both starts), the target the square inscribed in the script's disc, and a single
integrator of radius 0.1 m at 100 Hz (the script's ``rho_min``). The five circles are the
script's, seeded: episode ``e`` moves each start by ``U[-0.5, 0.5]`` m per axis and turns
each heading by ``U[-45, 45]`` degrees, keeping the script's speeds (episode streams
``[seed, 5, e]``), so that 1,000 episodes are not one. The envelope (``[sensing]``): range
5 m, latency 0.05 s, a measurement every 0.25 s, ``r_max = 0.5`` m, ``V = 0.45`` m/s (the
script's largest speed, ``sqrt(0.2)`` = 0.447, rounded up), no acceleration bound (the
circles never turn, but nothing is claimed from that), replanning budget 0.25 s, horizon
0.5 s. With ``--adversary`` a sixth circle (radius 0.5 m) starts at the target's centre
and heads for the robot at ``V``, turning at once: it meets the robot on its way and
guards the target.
"""

from __future__ import annotations

import math

import numpy as np

from stt_codegen.runtime.sensed import WalkingObstacle

__all__ = ["CIRCLES", "HEADING_JITTER", "POSITION_JITTER", "PURSUER_RADIUS", "PURSUER_START",
           "SCRIPT", "script_circles"]

#: The script's circles: ``(x, y, radius, vx, vy)``, m and m/s.
CIRCLES = ((4.0, 3.0, 0.5, -0.4, -0.2),
           (5.0, 6.0, 0.5, -0.4, -0.2),
           (6.0, 4.0, 0.5, 0.2, -0.4),
           (3.0, 6.0, 0.5, -0.2, 0.4),
           (4.5, 9.0, 0.5, -0.2, 0.0))
#: How far an episode moves a circle's start per axis at most, m.
POSITION_JITTER = 0.5
#: How far an episode turns a circle's heading at most, radians.
HEADING_JITTER = math.pi / 4.0
#: The target's half side, m: the square inside the script's disc of radius 1 around
#: ``(7, 10)`` (``1 / sqrt(2)`` = 0.707, rounded down).
_HALF = 0.7
#: The arena, the robot and the envelope (a spec dictionary).
SCRIPT = {
    "name": "rtstt-script", "prescribed_time": 16.0,
    "state_space": {"lower": [0.0, 0.0], "upper": [8.0, 11.25]},
    "initial": {"lower": [0.5, 0.5], "upper": [1.5, 1.5], "half_width": [0.2, 0.2]},
    "target": {"lower": [7.0 - _HALF, 10.0 - _HALF], "upper": [7.0 + _HALF, 10.0 + _HALF]},
    "controller": {"rate_hz": 100.0},
    "plant": {"model": "single-integrator", "disturbance_amplitude": 0.05},
    "robot": {"radius": 0.1},
    "sensing": {"range": 5.0, "latency": 0.05, "period": 0.25, "max_obstacle_radius": 0.5,
                "max_obstacle_speed": 0.45, "replan_time": 0.25, "horizon": 0.5},
}
#: Where the adversary starts (the target's centre), m, and its radius, m.
PURSUER_START, PURSUER_RADIUS = (7.0, 10.0), 0.5


def script_circles(rng: np.random.Generator) -> list[WalkingObstacle]:
    """The script's five circles, each start moved and each heading turned by the episode's
    stream (module notes).

    Parameters
    ----------
    rng : numpy.random.Generator
        The episode's stream.

    Returns
    -------
    list of WalkingObstacle
        Five, each at a constant velocity of the script's speed.

    Examples
    --------
    >>> import numpy as np
    >>> circles = script_circles(np.random.default_rng(0))
    >>> [round(float(np.hypot(*c.velocity)), 3) for c in circles]
    [0.447, 0.447, 0.447, 0.447, 0.2]
    """
    out = []
    for x, y, radius, vx, vy in CIRCLES:
        shift = rng.uniform(-POSITION_JITTER, POSITION_JITTER, 2)
        turn = float(rng.uniform(-HEADING_JITTER, HEADING_JITTER))
        c, s = math.cos(turn), math.sin(turn)
        out.append(WalkingObstacle((float(x + shift[0]), float(y + shift[1])), radius,
                                   velocity=(float(c * vx - s * vy), float(s * vx + c * vy))))
    return out
