"""Figures of a closed-loop run, in the manner of the paper's Fig. 3.

The figure is a :class:`matplotlib.figure.Figure` drawn on an explicit Agg canvas: this
module neither selects matplotlib's global backend nor uses ``pyplot``, so importing it
(also into a notebook) changes no global state.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np
from matplotlib.patches import Circle, Polygon, Rectangle
from scipy.spatial import ConvexHull

from ..design.result import Design, require_design
from ..tube import reference
from .simulate import SimulationResult
from ..spec.loader import Box, Spec


def agg_figure(**kwargs) -> Figure:
    """A :class:`~matplotlib.figure.Figure` on its own Agg canvas (``kwargs`` go to
    ``Figure``): it can be saved as PNG without pyplot and without touching matplotlib's
    global backend."""
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def draw_box(ax, box: Box, dims: tuple[int, int], **style) -> None:
    """Draw the projection of ``box`` on the state dimensions ``dims`` as a rectangle.

    ``style`` goes to :class:`matplotlib.patches.Rectangle` (``fc``, ``ec``, ``label``...).
    """
    i, j = dims
    ax.add_patch(Rectangle((box.lower[i], box.lower[j]), box.upper[i] - box.lower[i],
                           box.upper[j] - box.lower[j], **style))


def draw_unsafe_sets(ax, spec: Spec, dims: tuple[int, int]) -> None:
    """Draw the spec's obstacles on the state dimensions ``dims``: as given (filled, labelled
    ``U1``, ``U2``...) and, for balls and polytopes, their covering boxes (dashed)."""
    for j, unsafe in enumerate(spec.unsafe_sets):
        label = "obstacles" if j == 0 else None
        if not set(dims) <= set(unsafe.dims):
            continue  # spans one of the plotted axes: drawn by its boxes below
        k = [unsafe.dims.index(d) for d in dims]
        if unsafe.kind == "box":
            box = unsafe.shape
            patch = Rectangle((box.lower[k[0]], box.lower[k[1]]), box.upper[k[0]] - box.lower[k[0]],
                              box.upper[k[1]] - box.lower[k[1]], fc="0.55", ec="0.3", label=label)
            center = ((box.lower[k[0]] + box.upper[k[0]]) / 2, (box.lower[k[1]] + box.upper[k[1]]) / 2)
        elif unsafe.kind == "ball":
            center = (unsafe.shape.center[k[0]], unsafe.shape.center[k[1]])
            patch = Circle(center, unsafe.shape.radius, fc="0.55", ec="0.3", label=label)
        else:
            points = [(v[k[0]], v[k[1]]) for v in unsafe.shape.vertices]
            hull = ConvexHull(points)
            patch = Polygon([points[i] for i in hull.vertices], fc="0.55", ec="0.3", label=label)
            center = tuple(sum(p[i] for p in points) / len(points) for i in (0, 1))
        ax.add_patch(patch)
        ax.annotate(f"U{j + 1}", center, ha="center", va="center", color="white")
    covered = [o for o in spec.obstacles if spec.unsafe_sets[o.source].kind != "box"]
    for m, obstacle in enumerate(covered):
        draw_box(ax, obstacle.box(spec.state_space), dims, fill=False, ec="tab:red", lw=0.5,
              ls="--", label="covering boxes" if m == 0 else None)


def arena_figure(spec: Spec):
    """The two-column figure of :func:`plot_run` and :func:`plot_design`.

    Returns
    -------
    fig : matplotlib.figure.Figure
    grid : matplotlib.gridspec.GridSpec
        ``n`` rows, 2 columns: the right column has one axes per dimension.
    ax : matplotlib.axes.Axes or None
        The arena (left column, dimensions 0 and 1) with the state space, the obstacles and
        the target drawn; ``None`` when ``n < 2``.
    """
    n = spec.dimension
    fig = agg_figure(figsize=(11, 2.6 * max(n, 2)), layout="constrained")
    grid = fig.add_gridspec(n, 2, width_ratios=[1.1, 1.4])
    if n < 2:
        return fig, grid, None
    ax = fig.add_subplot(grid[:, 0])
    dims = (0, 1)
    draw_box(ax, spec.state_space, dims, fill=False, lw=1.5, ec="black")
    draw_unsafe_sets(ax, spec, dims)
    draw_box(ax, spec.target_set, dims, fc="tab:green", alpha=0.35, label="target")
    ax.set_xlabel("$x_1$")
    ax.set_ylabel("$x_2$")
    ax.set_aspect("equal")
    return fig, grid, ax


def plot_run(design: Design, result: SimulationResult, path: str | Path) -> Path:
    """Write a PNG of a closed-loop run, in the manner of the paper's Fig. 3.

    On the left, the arena (dimensions ``x1``, ``x2``): the state space, the obstacles,
    the initial and target sets and the trajectory; on the right, for each dimension, the
    tube ``[gamma_L, gamma_U]`` of eq. (10) (with the run's ``alpha``) against time, the
    state inside it, and ``t_c``.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`: the run's tube and (``design.spec``) its task.
    result : SimulationResult
        From :func:`stt_codegen.simulate` on ``design``, with its trajectory.
    path : str or path
        Output file (PNG); its folder must exist.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.

    See Also
    --------
    stt_codegen.simulate : the run.
    stt_codegen.plot_design : the certified tube, before any run.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> result = stt.simulate(design, backend="casadi")
    >>> stt.plot_run(design, result, "s1-run.png").name
    's1-run.png'
    """
    design = require_design(design, "plot_run")
    spec, tube = design.spec, design.tube
    traj = result.trajectory
    n = spec.dimension
    g_l, g_u, _, _ = reference.adaptive_tube(tube, traj.t, traj.alpha)
    fig, grid, ax = arena_figure(spec)
    if ax is not None:
        draw_box(ax, spec.initial_set, (0, 1), fc="tab:blue", alpha=0.3, label="initial set")
        ax.plot(traj.x[:, 0], traj.x[:, 1], "k--", lw=1.2, label="trajectory")
        ax.plot(*traj.x[0, :2], "o", color="tab:blue")
        ax.legend(loc="lower right", fontsize=7)
        verdict = "satisfied" if result.satisfied else "NOT satisfied"
        ax.set_title(f"{spec.name}: {verdict}, reach {result.reach_time} s")
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        ax.fill_between(traj.t, g_l[:, i], g_u[:, i], color="tab:orange", alpha=0.25,
                        label=r"tube $[\gamma_L, \gamma_U]$")
        ax.plot(traj.t, g_l[:, i], color="tab:orange", lw=0.8)
        ax.plot(traj.t, g_u[:, i], color="tab:orange", lw=0.8)
        ax.plot(traj.t, traj.x[:, i], "k", lw=1.0, label=f"$x_{i + 1}$")
        ax.axvline(spec.prescribed_time, color="tab:red", lw=0.8, ls=":", label="$t_c$")
        ax.set_ylabel(f"$x_{i + 1}$")
        if i == n - 1:
            ax.set_xlabel("t [s]")
        if i == 0:
            ax.legend(loc="best", fontsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110, format="png")
    return out


#: Reach boxes drawn over the arena.
BOXES_DRAWN = 24


def plot_design(design: Design, path: str | Path) -> Path:
    """Write a PNG of ``design``: tube boxes (the certificate's enclosure) and via boxes in
    the first two dimensions, and the certified enclosure of ``gamma_L``, ``gamma_U`` (eq.
    (10)) per dimension against time.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube` (its spec gives the arena).
    path : str or path
        Output file (PNG); its folder must exist.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.

    See Also
    --------
    stt_codegen.design_tube : the design.
    stt_codegen.plot_run : a closed-loop run in its tube.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> stt.plot_design(design, "s1-tube.png").name
    's1-tube.png'
    """
    design = require_design(design, "plot_design")
    spec = design.spec
    tube, enc = design.tube, design.certificate.enclosure
    n = spec.dimension
    t_c = tube.prescribed_time
    fig, grid, ax = arena_figure(spec)
    if ax is not None:
        dims = (0, 1)
        times = np.linspace(0.0, t_c, BOXES_DRAWN)
        which = np.searchsorted(enc.t_start, times, side="right") - 1
        for k in which:
            draw_box(ax, Box(tuple(enc.lower_min[k]), tuple(enc.upper_max[k])), dims, fill=False,
                  ec="tab:orange", lw=0.6,
                  label="tube box (certified enclosure)" if k == which[0] else None)
        for k, seg in enumerate(tube.segments if design.method != "paper" else ()):
            draw_box(ax, Box(seg.lower_to, seg.upper_to), dims, fill=False, ec="tab:purple",
                  lw=1.2, label="via boxes" if k == 0 else None)
        ax.set_xlim(spec.state_space.lower[0], spec.state_space.upper[0])
        ax.set_ylim(spec.state_space.lower[1], spec.state_space.upper[1])
        ax.legend(loc="lower right", fontsize=7)
        ax.set_title(f"{spec.name}: {design.method} method, "
                     f"{design.design_time_s * 1e3:.1f} ms")
    end = 1.2 * t_c
    keep = enc.t_start < end
    t0 = enc.t_start[keep]
    t1 = np.minimum(enc.t_end[keep], end)
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        for lo, hi, colour, name in ((enc.lower_min, enc.lower_max, "tab:blue", r"$\gamma_L$"),
                                     (enc.upper_min, enc.upper_max, "tab:orange",
                                      r"$\gamma_U$")):
            for k in range(t0.size):
                ax.fill_between([t0[k], t1[k]], [lo[keep][k, i]] * 2, [hi[keep][k, i]] * 2,
                                color=colour, alpha=0.35, lw=0.8, edgecolor=colour,
                                label=f"{name} enclosure" if k == 0 else None)
        ax.axvline(t_c, color="tab:red", lw=0.8, ls=":", label="$t_c$")
        ax.set_ylabel(f"$x_{i + 1}$")
        if i == n - 1:
            ax.set_xlabel("t [s] (certified for every t >= 0; drawn up to 1.2 t_c)")
        if i == 0:
            ax.legend(loc="best", fontsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110)
    return out
