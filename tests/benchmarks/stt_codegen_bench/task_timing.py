"""When the timed-task baseline leaves each leg: waiting for moving obstacles to pass.

The baseline (:mod:`.task_baseline`) plans its legs on the static grid (A* does not see
the moving obstacles). This module times them in space-time, as a user of sequential A*
with waiting would: leg ``j`` is followed at the tracker's cruise speed
(:data:`~.tracker.SPEED`) from a departure time ``d_j`` on; before it the robot waits at
the leg's first point, after its arrival at the leg's last point. :func:`departure` picks
the earliest ``d_j`` on a grid of :data:`DEPARTURE_STEP` seconds, from the time the leg may
start, such that

* the leg arrives by its deadline (the middle of the task's window, or ``t_c``), and
* over the whole leg period (waiting, moving and waiting at the end, until the deadline)
  the nominal position keeps :data:`~.planning.MARGIN` from every moving obstacle's box,
  taken as its hull over ``[t - SLACK, t + SLACK]`` (the tracker lags or leads its nominal
  schedule a little), checked every :data:`CHECK_STEP` seconds.

When no departure on the grid is clear, the leg leaves at the one (arriving by the
deadline) whose nominal schedule comes least close to the obstacles, and the closed loop
judges it (collisions with moving obstacles counted): the baseline is not given a
guarantee it does not have. Deterministic (fixed grids, no randomness).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from stt_codegen.spec.motion import MovingObstacle
from .planning import MARGIN
from .tracker import SPEED

#: Departure times tried, seconds apart.
DEPARTURE_STEP = 0.05
#: The nominal position is checked against the obstacles this often, seconds.
CHECK_STEP = 0.02
#: Timing slack: the obstacle is taken over ``[t - SLACK, t + SLACK]``, seconds.
SLACK = 0.15


def positions(path: np.ndarray, depart: float, t: np.ndarray) -> np.ndarray:
    """Nominal positions (len(t), 2) on ``path`` (K, 2): at ``path[0]`` until ``depart``
    (s), then along it at :data:`~.tracker.SPEED` m/s, then at ``path[-1]``.

    Parameters
    ----------
    path : numpy.ndarray, shape (K, 2)
        The leg's way points, metres.
    depart : float
        Departure time, s.
    t : numpy.ndarray, shape (N,)
        Times, s.

    Returns
    -------
    numpy.ndarray, shape (N, 2)
        Positions, metres.
    """
    path = np.asarray(path, float)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    s = np.clip((np.asarray(t, float) - depart) * SPEED, 0.0, arc[-1])
    return np.column_stack([np.interp(s, arc, path[:, d]) for d in range(path.shape[1])])


def gap(points: np.ndarray, t: np.ndarray, obstacles: Sequence[MovingObstacle]) -> float:
    """The smallest distance (metres, by the largest separation along a dimension; ``inf``
    when none is present) of a point ``points[k]`` ((K, 2)) from an obstacle's hull over
    ``[t[k] - SLACK, t[k] + SLACK]`` (seconds); negative inside.

    Parameters
    ----------
    points : numpy.ndarray, shape (K, 2)
        Positions, metres.
    t : numpy.ndarray, shape (K,)
        Their times, s.
    obstacles : sequence of MovingObstacle
        The spec's moving obstacles.

    Returns
    -------
    float
        The smallest gap, metres (``inf`` when no obstacle is present near any ``t[k]``).
    """
    out = np.inf
    for ob in obstacles:
        lo, hi, present = ob.hull(t - SLACK, t + SLACK)
        p = points[:, list(ob.dims)]
        sep = np.maximum(lo - p, p - hi).max(axis=1)
        if np.any(present):
            out = min(out, float(sep[present].min()))
    return out


def departure(path: np.ndarray, begin: float, deadline: float,
              obstacles: Sequence[MovingObstacle]) -> tuple[float, bool]:
    """The earliest clear departure of a leg (module notes).

    Parameters
    ----------
    path : numpy.ndarray, shape (K, 2)
        The leg, metres.
    begin : float
        When the leg may start (s): the previous leg's deadline, or 0.
    deadline : float
        When it must have arrived (s), ``> begin``.
    obstacles : sequence of MovingObstacle
        The spec's moving obstacles.

    Returns
    -------
    (float, bool)
        The departure time (s) and whether it keeps more than :data:`~.planning.MARGIN`
        (:func:`gap`); when none does, the one with the largest gap and ``False``
        (``begin`` when no departure on the grid arrives by ``deadline``).
    """
    if not obstacles:
        return begin, True
    path = np.asarray(path, float)
    travel = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))) / SPEED
    t = np.arange(begin, deadline + 0.5 * CHECK_STEP, CHECK_STEP)
    latest = deadline - travel
    best, best_gap = begin, -np.inf
    k = 0
    while begin + k * DEPARTURE_STEP <= latest + 1e-9:
        depart = begin + k * DEPARTURE_STEP
        g = gap(positions(path, depart, t), t, obstacles)
        if g > MARGIN:
            return depart, True
        if g > best_gap:
            best, best_gap = depart, g
        k += 1
    return best, False


__all__ = ["CHECK_STEP", "DEPARTURE_STEP", "SLACK", "departure", "gap", "positions"]
