"""Moving obstacles in the figures: time slices over the arena (docs/moving-obstacles.md).

A moving obstacle is drawn at :data:`SLICES` instants of its active interval (up to ``t_c``),
as hatched outlines coloured by time (one colour scale over ``[0, t_c]`` for every obstacle),
each labelled ``"j @ t s"``. In a run's figure the state at the same instants is marked in
the same colours, so that where the robot was when the obstacle was there can be read off.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.patches import Rectangle

from ..spec.loader import Spec
from ..spec.motion import MovingObstacle

__all__ = ["draw_moving_obstacles", "mark_states"]

#: Instants at which each moving obstacle is drawn.
SLICES = 4
#: Colour map of the slice times, over ``[0, t_c]``.
SLICE_COLOURS = "viridis"


def slice_times(obstacle: MovingObstacle, prescribed_time: float) -> list[float]:
    """The instants a moving obstacle is drawn at, seconds: :data:`SLICES` evenly over its
    active interval cut at ``t_c`` (one for a box that does not move)."""
    t_on = obstacle.active[0]
    t_off = min(obstacle.active[1], prescribed_time)
    if t_off < t_on:
        return [t_on]
    if obstacle.motion == "still" or t_off == t_on:
        return [t_on]
    return [float(t) for t in np.linspace(t_on, t_off, SLICES)]


def _colour(t: float, prescribed_time: float):
    return colormaps[SLICE_COLOURS](min(max(t / prescribed_time, 0.0), 1.0))


def draw_moving_obstacles(ax: Axes, spec: Spec, dims: tuple[int, int]) -> None:
    """Draw each moving obstacle of ``spec`` at its :func:`slice_times`, projected on ``dims``.

    Patches have the gid ``"moving obstacle j"``; labels ``"j @ t s"``. With ``[robot]``
    these are the inflated boxes, and the boxes as given are drawn inside them, filled (gid
    ``"moving obstacle j as given"``).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The arena's axes.
    spec : Spec
        The spec whose ``moving_obstacles`` are drawn.
    dims : tuple of int, length 2
        The state dimensions of the axes, zero-based; a dimension the obstacle does not move
        in spans the state space.
    """
    t_c = spec.prescribed_time
    real = () if spec.robot is None else spec.robot.moving_obstacles

    def corners(ob: MovingObstacle, t: float) -> tuple[list[float], list[float]]:
        centre = ob.centre([t])[0]
        lower, upper = [], []
        for d in dims:
            if d in ob.dims:
                k = ob.dims.index(d)
                lower.append(centre[k] - ob.half_size[k])
                upper.append(centre[k] + ob.half_size[k])
            else:
                lower.append(spec.state_space.lower[d])
                upper.append(spec.state_space.upper[d])
        return lower, upper
    for m, ob in enumerate(spec.moving_obstacles):
        for q, t in enumerate(slice_times(ob, t_c)):
            lower, upper = corners(ob, t)
            colour = _colour(t, t_c)
            ax.add_patch(Rectangle((lower[0], lower[1]), upper[0] - lower[0], upper[1] - lower[1],
                                   fill=False, ec=colour, lw=1.2, hatch="//",
                                   gid=f"moving obstacle {ob.source}",
                                   label=("moving obstacle (at the times shown)"
                                          if m == 0 and q == 0 else None)))
            if real:        # [robot]: the box above is inflated; the real one inside it
                lo, hi = corners(real[m], t)
                ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1],
                                       fc=colour, alpha=0.5, ec=colour,
                                       gid=f"moving obstacle {ob.source} as given"))
            ax.annotate(f"{ob.source} @ {t:.3g} s", ((lower[0] + upper[0]) / 2,
                                                      (lower[1] + upper[1]) / 2),
                        ha="center", va="center", fontsize=6, color="black",
                        gid="moving obstacle label", zorder=5,
                        bbox={"boxstyle": "round,pad=0.1", "fc": colour, "alpha": 0.6,
                              "ec": "none"})


def mark_states(ax: Axes, spec: Spec, t: np.ndarray, x: np.ndarray,
                dims: tuple[int, int]) -> None:
    """Mark the state of a run (times ``t`` (N,), states ``x`` (N, n)) at every slice time of
    the moving obstacles, in the slice's colour.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The arena's axes.
    spec : Spec
        The spec whose moving obstacles give the slice times.
    t : ndarray, shape (N,)
        Times of the run, s.
    x : ndarray, shape (N, n)
        States of the run, state units.
    dims : tuple of int, length 2
        The state dimensions of the axes, zero-based.
    """
    times = sorted({s for ob in spec.moving_obstacles
                    for s in slice_times(ob, spec.prescribed_time)})
    for q, s in enumerate(times):
        k = int(np.argmin(np.abs(t - s)))
        if not math.isclose(float(t[k]), s, abs_tol=1.0):
            continue
        ax.plot(x[k, dims[0]], x[k, dims[1]], "s", ms=5, mec="black", mew=0.5,
                color=_colour(s, spec.prescribed_time), zorder=6,
                label="state at those times" if q == 0 else None)
