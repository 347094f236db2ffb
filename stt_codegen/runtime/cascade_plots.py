"""Figure of a second-order closed loop (docs/second-order.md): the arena from above with
the path of ``x1``, each position against its tube, and ``|u|``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..design.result import Design
from ..tube import reference
from .cascade_simulate import CascadeResult
from .plots import agg_figure, draw_arena, save

__all__ = ["plot_cascade_run"]


def plot_cascade_run(design: Design, result: CascadeResult, path: str | Path,
                     dims: tuple[int, int] = (0, 1)) -> Path:
    """Write a PNG of a cascade run.

    Parameters
    ----------
    design : Design
        The design the run used (its spec and tube).
    result : CascadeResult
        With its trajectory.
    path : str or path
        The PNG to write (its folder must exist).
    dims : (int, int)
        The two positions of the arena view.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    spec, tube, traj = design.spec, design.tube, result.trajectory
    n = spec.dimension
    with reference.numpy_math():
        g_l, g_u, _, _ = reference.adaptive_tube(tube, traj.t, traj.alpha)
    fig = agg_figure(figsize=(11, 3.2 * max(2, n)), layout="constrained")
    grid = fig.add_gridspec(n + 1, 2)
    ax = fig.add_subplot(grid[:, 0])
    draw_arena(ax, spec, dims)
    ax.plot(traj.x1[:, dims[0]], traj.x1[:, dims[1]], color="C0", lw=1.5, label="x1(t)")
    ax.set_title(f"{spec.name}: {result.model}, backend {result.backend}, "
                 f"{'satisfied' if result.satisfied else 'NOT satisfied'}")
    ax.legend(loc="lower right", fontsize=8)
    for i in range(n):
        axi = fig.add_subplot(grid[i, 1])
        axi.fill_between(traj.t, g_l[:, i], g_u[:, i], color="C2", alpha=0.25, label="tube")
        axi.plot(traj.t, traj.x1[:, i], color="C0", lw=1.0, label=f"x1_{i + 1}")
        axi.axvline(spec.prescribed_time, color="k", ls=":", lw=0.8)
        axi.set_ylabel(f"position {i + 1}")
        axi.legend(loc="upper left", fontsize=7)
    axu = fig.add_subplot(grid[n, 1])
    for i in range(n):
        axu.plot(traj.t, np.abs(traj.u[:, i]), lw=0.8, label=f"|u_{i + 1}|")
    axu.set_xlabel("t [s]")
    axu.set_ylabel("|u|")
    axu.legend(loc="upper right", fontsize=7)
    return save(fig, path)
