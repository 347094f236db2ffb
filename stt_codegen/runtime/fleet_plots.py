"""A fleet in space and time: time slices of every robot's certified tube (docs/fleets.md).

Each panel is the shared floor at one instant: the state space, the static obstacles, and
per robot its target and the box of its certified enclosure on the interval (at most
:data:`SLICE_SPAN` long) holding that instant, grown by the robot's reach (a set its body
stays in), in the robot's colour;
with a run, each robot's body at the sample nearest that instant. Two robots' grown boxes
may overlap in a panel: the fleet certificate proves the bodies apart on a finer partition
and along one dimension at a time, not the panel's boxes.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.patches import Circle

from ..design.fleet import FleetDesign, enclosed
from ..errors import SpecError
from ..spec.loader import Box
from .dims import DEFAULT_DIMS, check_dims
from .fleet import FleetRun
from .plots import agg_figure, draw_box, draw_unsafe_sets, save

__all__ = ["MAX_SLICES", "SLICE_SPAN", "fleet_figure", "plot_fleet"]

#: The most time slices a figure draws.
MAX_SLICES = 12
#: The longest interval of the certified enclosure a slice draws, seconds.
SLICE_SPAN = 0.1


def _slice_times(designed: FleetDesign, slices: int) -> np.ndarray:
    """``slices`` instants from 0 to the longest ``prescribed_time``, evenly spaced."""
    end = max(d.spec.prescribed_time for d in designed.designs.values())
    return np.linspace(0.0, end, slices)


def _checked_slices(slices: int) -> int:
    if isinstance(slices, bool) or not isinstance(slices, (int, np.integer)) \
            or not 1 <= slices <= MAX_SLICES:
        raise SpecError("slices", f"must be an integer from 1 to {MAX_SLICES}, got {slices!r}")
    return int(slices)


def fleet_figure(designed: FleetDesign, run: FleetRun | None = None, *, slices: int = 6,
                 dims: tuple[int, int] = DEFAULT_DIMS):
    """The figure of :func:`plot_fleet`.

    Parameters
    ----------
    designed, run, slices, dims
        As :func:`plot_fleet`.

    Returns
    -------
    matplotlib.figure.Figure
        On its own Agg canvas.
    """
    if not isinstance(designed, FleetDesign):
        raise TypeError("plot_fleet(): parameter 'designed' must be a FleetDesign (call "
                        f"stt_codegen.design_fleet first), not {type(designed).__name__}")
    slices = _checked_slices(slices)
    robots = designed.fleet.robots
    first = robots[0].spec
    dims = check_dims(dims, first.dimension)
    times = _slice_times(designed, slices)
    cols = min(3, slices)
    rows = math.ceil(slices / cols)
    fig = agg_figure(figsize=(4.2 * cols + 1.8, 3.4 * rows + 0.6), layout="constrained")
    colours = [f"C{k % 10}" for k in range(len(robots))]
    # each robot's certified enclosure cut to intervals of at most SLICE_SPAN seconds
    tubes = {r.name: enclosed(designed.designs[r.name], SLICE_SPAN) for r in robots}
    i, j = dims
    space = first.state_space
    for s, t in enumerate(times):
        ax = fig.add_subplot(rows, cols, s + 1)
        draw_box(ax, space, dims, fill=False, lw=1.5, ec="black")
        draw_unsafe_sets(ax, first, dims)
        for k, robot in enumerate(robots):
            draw_box(ax, robot.spec.target_set, dims, fc=colours[k], alpha=0.15,
                     ec=colours[k], lw=0.5)
            t_start, _, lower, upper = tubes[robot.name].boxes(robot.dims)
            m = int(np.searchsorted(t_start, t, side="right") - 1)
            reach = robot.reach
            box_lower, box_upper = list(space.lower), list(space.upper)
            for d, lo, hi in zip(robot.dims, lower[m], upper[m]):
                box_lower[d], box_upper[d] = float(lo) - reach, float(hi) + reach
            draw_box(ax, Box(tuple(box_lower), tuple(box_upper)), dims, fill=False,
                     ec=colours[k], lw=1.2, label=robot.name if s == 0 else None)
            if run is not None and robot.name in run.results:
                traj = run.results[robot.name].trajectory
                n = int(np.argmin(np.abs(traj.t - t)))
                ax.add_patch(Circle((traj.x[n, i], traj.x[n, j]), reach, fc=colours[k],
                                    ec="black", lw=0.5, alpha=0.8))
        pad = [0.02 * (space.upper[d] - space.lower[d]) for d in dims]
        ax.set_xlim(space.lower[i] - pad[0], space.upper[i] + pad[0])
        ax.set_ylim(space.lower[j] - pad[1], space.upper[j] + pad[1])
        ax.set_aspect("equal")
        ax.set_title(f"t = {t:.2f} s", fontsize=9)
        ax.tick_params(labelsize=7)
    fig.legend(*fig.axes[0].get_legend_handles_labels(), loc="outside right upper",
               fontsize=7)
    verdict = "certified" if designed.certified else "NOT certified"
    closest = None if run is None else run.closest
    fig.suptitle(f"Fleet {designed.fleet.name}: {len(robots)} robots, {verdict}"
                 + ("" if designed.narrowest is None else
                    f", narrowest certified pair {designed.narrowest.margin:.3g}")
                 + ("" if closest is None else
                    f"; closest approach in the run {closest.clearance:.3g}")
                 + "\nbox: the certified tube grown by the robot's reach; shaded: its target"
                 + ("" if run is None else "; disc: its body in the run"), fontsize=10)
    return fig


def plot_fleet(designed: FleetDesign, path: str | Path, run: FleetRun | None = None, *,
               slices: int = 6, dims: tuple[int, int] = DEFAULT_DIMS) -> Path:
    """Write a PNG of a fleet in time slices: every robot's certified tube at each instant.

    Parameters
    ----------
    designed : FleetDesign
        From :func:`stt_codegen.design_fleet`.
    path : str or path
        The PNG to write; its folder must exist.
    run : FleetRun, optional
        From :func:`stt_codegen.simulate_fleet`: each robot's body drawn at the sample
        nearest each instant.
    slices : int
        Panels, 1 to :data:`MAX_SLICES`: instants from 0 to the longest
        ``prescribed_time`` (eq. (10)'s ``t_c``), evenly spaced, seconds.
    dims : tuple of int, length 2
        The state dimensions drawn, zero-based.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``designed`` is not a :class:`~stt_codegen.design.fleet.FleetDesign`.
    SpecError
        ``slices`` out of range (field ``slices``); bad ``dims`` (field ``dims``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> stt.plot_fleet(fleet, "swap.png", slices=4).name
    'swap.png'
    """
    return save(fleet_figure(designed, run, slices=slices, dims=dims), path)
