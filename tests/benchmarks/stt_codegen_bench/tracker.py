"""The baselines' tracker: carrot (pure-pursuit) following of a planned path.

At each sampling instant the tracker projects ``x`` onto the path (searching forward from
its last progress, so it never jumps back), puts a carrot :data:`LOOKAHEAD` metres further
along the path and commands ``u = SPEED (carrot - x) / |carrot - x|``. Near the goal
(the carrot is the goal) it commands ``u = GOAL_GAIN (goal - x)``, saturated at
:data:`SPEED`. ``SPEED = 1.5`` m/s covers the longest paths met (about 10 m) well within
``t_c = 9`` s; the lookahead is small enough that cutting a right-angle corner stays
inside the planners' 0.2 m margin.

The closed loop is run by :func:`stt_codegen.runtime.simulate.run_closed_loop`, the loop of
``simulate`` itself, so that the baselines are judged by the very same code as the tube
controller: same plant and disturbance seed, same sampling rate (the spec's, 1 kHz) and
integration, same Definition 2.1 on ``[0, t_c]`` (target reached by ``t_c``, no collision
at any integration point, state space never left).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from stt_codegen.runtime.backends import STATUS_OK, backend_names, register_backend
from stt_codegen.design.search import base_design
from stt_codegen.runtime.simulate import SimulationResult, run_closed_loop
from stt_codegen.spec.loader import Spec
from stt_codegen.tube.parameters import TubeDesign

__all__ = ["GOAL_GAIN", "PathTracker", "SPEED", "track"]

#: Cruise speed, m/s.
SPEED = 1.5
#: Carrot distance ahead of the projection on the path, metres.
LOOKAHEAD = 0.15
#: Proportional gain towards the goal once the carrot reaches it, 1/s.
GOAL_GAIN = 4.0
#: Path length searched ahead of the last progress when projecting, metres.
SEARCH_AHEAD = 0.5
BACKEND = "bench-path-tracker"

_PATHS: dict[str, np.ndarray] = {}


class PathTracker:
    """Carrot following of a polyline (a :class:`~stt_codegen.runtime.backends.Controller`).

    Parameters
    ----------
    path : numpy.ndarray, shape (K, 2), K >= 2
        Waypoints, metres; the last one is the goal.
    """

    name = BACKEND

    def __init__(self, path: np.ndarray) -> None:
        path = np.asarray(path, dtype=float)
        keep = np.ones(len(path), bool)
        keep[1:] = np.any(np.diff(path, axis=0) != 0, axis=1)  # drop repeated points
        self.path = path[keep] if keep.sum() >= 2 else np.vstack([path[0], path[-1]])
        seg = np.diff(self.path, axis=0)
        length = np.linalg.norm(seg, axis=1)
        # plain floats: this runs at every sampling instant
        self._pts = [tuple(map(float, p)) for p in self.path]
        self._seg = [tuple(map(float, d)) for d in seg]
        self._len = [float(v) for v in length]
        self._arc = [0.0] + [float(v) for v in np.cumsum(length)]
        self.progress = 0.0

    def _point_at(self, s: float) -> tuple[float, float]:
        k = min(max(bisect.bisect_right(self._arc, s) - 1, 0), len(self._seg) - 1)
        (ax, ay), (dx, dy), length = self._pts[k], self._seg[k], self._len[k]
        frac = 0.0 if length == 0 else min(max((s - self._arc[k]) / length, 0.0), 1.0)
        return ax + frac * dx, ay + frac * dy

    def command(self, x: np.ndarray) -> np.ndarray:
        """The velocity command at position ``x`` (2,), m/s; updates the progress."""
        px, py = float(x[0]), float(x[1])
        last = len(self._seg) - 1
        lo = min(max(bisect.bisect_right(self._arc, self.progress) - 1, 0), last)
        hi = min(max(bisect.bisect_right(self._arc, self.progress + SEARCH_AHEAD), lo + 1),
                 last + 1)
        best, best_s = math.inf, self.progress
        for k in range(lo, hi):
            (ax, ay), (dx, dy), length = self._pts[k], self._seg[k], self._len[k]
            frac = 0.0 if length == 0 else ((px - ax) * dx + (py - ay) * dy) / length**2
            frac = min(max(frac, 0.0), 1.0)
            dist = math.hypot(ax + frac * dx - px, ay + frac * dy - py)
            if dist < best:
                best, best_s = dist, self._arc[k] + frac * length
        self.progress = max(self.progress, best_s)
        if self.progress + LOOKAHEAD >= self._arc[-1]:
            gx, gy = self._pts[-1]
            ux, uy = GOAL_GAIN * (gx - px), GOAL_GAIN * (gy - py)
            norm = math.hypot(ux, uy)
            scale = 1.0 if norm <= SPEED else SPEED / norm
            return np.array([ux * scale, uy * scale])
        cx, cy = self._point_at(self.progress + LOOKAHEAD)
        norm = math.hypot(cx - px, cy - py)
        if norm == 0:
            return np.zeros(2)
        return np.array([(cx - px) * SPEED / norm, (cy - py) * SPEED / norm])

    def step(self, x, t, dt, alpha):
        """The :class:`~stt_codegen.runtime.backends.Controller` step; ``alpha`` is passed through."""
        return self.command(np.asarray(x, float)), np.asarray(alpha, float), STATUS_OK


def _factory(design: TubeDesign) -> PathTracker:
    return PathTracker(_PATHS.pop(design.name))


def track(spec: Spec, path: np.ndarray, seed: int) -> SimulationResult:
    """Run the tracker on ``path`` in closed loop, judged by Definition 2.1.

    Parameters
    ----------
    spec : Spec
        A 2-D spec (its plant, disturbance bound, rate and ``t_c`` are used).
    path : numpy.ndarray, shape (K, 2)
        The planned way points, metres.
    seed : int
        Disturbance seed (the same as the tube controller's on this arena).

    Returns
    -------
    SimulationResult
        From :func:`stt_codegen.runtime.simulate.run_closed_loop`; ``backend`` is
        ``bench-path-tracker``.
    """
    if BACKEND not in backend_names():
        register_backend(BACKEND, _factory)
    design = base_design(spec)
    _PATHS[design.name] = np.asarray(path, float)
    try:
        return run_closed_loop(spec, design, backend=BACKEND, seed=seed)
    finally:
        _PATHS.pop(design.name, None)
