"""The planning problem the baselines solve: free space with a safety margin.

A planner-plus-tracker baseline keeps its path away from obstacles and walls by a margin
that absorbs the tracking error, as a user would. Both baselines (A* on a grid,
:mod:`.astar`, and OMPL's RRT*, :mod:`.rrtstar`) plan in the same free space: the arena
shrunk by :data:`MARGIN` and every obstacle inflated by :data:`MARGIN` (the Minkowski sum
with a square, i.e. a bigger box). The margin equals the tube's ``delta_B = 0.2`` m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stt_codegen.spec.loader import Spec

__all__ = ["FreeSpace", "MARGIN", "Plan"]

#: Clearance kept from obstacles and walls by the planners, metres.
MARGIN = 0.2


@dataclass(frozen=True)
class FreeSpace:
    """Axis-aligned free space of a 2-D spec, with the planners' margin.

    Attributes
    ----------
    lower, upper : numpy.ndarray, shape (2,)
        The arena shrunk by the margin, metres.
    obstacles : numpy.ndarray, shape (m, 2, 2)
        ``[j, 0]`` lower and ``[j, 1]`` upper corner of obstacle ``j`` inflated by the
        margin, metres.
    start, goal : numpy.ndarray, shape (2,)
        ``x(0)`` and the centre of the target set, metres.
    """

    lower: np.ndarray
    upper: np.ndarray
    obstacles: np.ndarray
    start: np.ndarray
    goal: np.ndarray

    @classmethod
    def of(cls, spec: Spec, margin: float = MARGIN) -> "FreeSpace":
        """The free space of ``spec`` (2-D) with ``margin`` metres of clearance."""
        boxes = spec.obstacle_boxes()
        obstacles = np.array([[np.array(b.lower) - margin, np.array(b.upper) + margin]
                              for b in boxes]).reshape(len(boxes), 2, 2)
        return cls(np.array(spec.state_space.lower) + margin,
                   np.array(spec.state_space.upper) - margin, obstacles,
                   np.array(spec.initial_state, float), np.array(spec.target_set.center, float))

    def point_checker(self):
        """A fast scalar test ``free(x, y) -> bool``, same rule as :meth:`is_free` (for
        planners that call back from C++ once per state)."""
        (x0, y0), (x1, y1) = (float(v) for v in self.lower), (float(v) for v in self.upper)
        boxes = [tuple(float(v) for v in (o[0, 0], o[0, 1], o[1, 0], o[1, 1]))
                 for o in self.obstacles]

        def free(x: float, y: float) -> bool:
            if not (x0 < x < x1 and y0 < y < y1):
                return False
            for a, b, c, d in boxes:
                if a <= x <= c and b <= y <= d:
                    return False
            return True
        return free

    def is_free(self, points: np.ndarray) -> np.ndarray:
        """Whether each point (N, 2) is free (inside the shrunk arena, outside every
        inflated obstacle; boundaries count as occupied). Returns shape (N,)."""
        p = np.atleast_2d(points)
        inside = np.all((p > self.lower) & (p < self.upper), axis=1)
        if len(self.obstacles):
            lo, hi = self.obstacles[None, :, 0, :], self.obstacles[None, :, 1, :]
            hit = np.all((p[:, None, :] >= lo) & (p[:, None, :] <= hi), axis=2).any(axis=1)
            inside &= ~hit
        return inside


@dataclass(frozen=True)
class Plan:
    """Outcome of a planner.

    Attributes
    ----------
    path : numpy.ndarray or None
        Waypoints (K, 2) from ``x(0)`` to the goal, metres; ``None`` when no path was found.
    seconds : float
        Wall-clock planning time (including building the grid or the planner), seconds.
    reason : str
        Empty when a path was found, else why not.
    """

    path: np.ndarray | None
    seconds: float
    reason: str = ""
