"""Figures of a design, of a rejected design and of a closed-loop run (the paper's Fig. 3).

Every figure has the arena on the left, drawn on two chosen state dimensions ``dims``
(default ``(0, 1)``): the state space, every obstacle as its projection on those two
dimensions (a box as a rectangle, a ball as a disc, a polytope as the hull of its
projected vertices; an obstacle not given on a plotted dimension spans that dimension's
whole range), numbered ``j`` as the messages number them (``obstacle j``, the spec's
``obstacles[j]``), the target and what the figure is about. On the right are the time
plots: the tube per dimension and, for a run, the inputs ``u(t)``. Legends sit outside
the axes, one entry per thing drawn.

A figure is a :class:`matplotlib.figure.Figure` on an explicit Agg canvas
(:func:`agg_figure`): this module neither selects matplotlib's global backend nor uses
``pyplot``, so importing it (also into a notebook) changes no global state.
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.gridspec import GridSpec
from matplotlib.patches import Circle, Patch, Polygon, Rectangle
from matplotlib.transforms import offset_copy
from scipy.spatial import ConvexHull

from ..errors import SpecError
from ..spec.loader import Box, Spec, UnsafeSet
from ..spec.plants import PLANTS
from ..tube import reference
from ..design.result import Design, require_design
from ..tube.parameters import TANH, TubeDesign
from .dims import DEFAULT_DIMS, check_dims, parse_dims
from .motion_plots import draw_moving_obstacles, mark_states
from .simulate import SimulationResult
from .task_plots import draw_task_windows, draw_tasks

if TYPE_CHECKING:
    from ..design.certificate import Certificate
    from ..errors import DesignError

__all__ = ["OBSTACLE_LABEL", "agg_figure", "arena_figure", "design_figure", "draw_arena",
           "draw_box", "draw_unsafe_sets",
           "plot_design", "plot_rejected", "plot_run", "rejected_figure",
           "run_figure", "save"]

#: Tube boxes (at most) drawn over the arena of a design.
BOXES_DRAWN = 24
#: Characters per line of a rejected design's reason in its figure's title.
TITLE_WIDTH = 120
#: Lines of the reason shown in the title (the full reason is the error message).
TITLE_LINES = 4
#: Height of one time plot, inches.
ROW_HEIGHT = 2.3
#: Style of an obstacle (filled grey, partly transparent so that a trajectory drawn over
#: its projection stays visible).
OBSTACLE_STYLE: dict[str, Any] = {"fc": "0.55", "ec": "0.3", "alpha": 0.8}
#: Height of an axes' x tick labels and x label, points: a legend below the axes starts
#: this far under it.
BELOW_AXIS_POINTS = 40.0
#: Legend entry of the obstacles.
OBSTACLE_LABEL = "obstacle j (obstacles[j] of the spec)"
#: An obstacle inflated by the robot's radius (``[robot]``): the set the reference point
#: avoids, drawn under the real obstacle.
MARGIN_STYLE: dict[str, Any] = {"fc": "none", "ec": "0.45", "hatch": "////", "lw": 0.6}
MARGIN_LABEL = "obstacle inflated by the robot's radius"


def agg_figure(**kwargs) -> Figure:
    """A :class:`~matplotlib.figure.Figure` on its own Agg canvas (``kwargs`` go to
    ``Figure``): it can be saved as PNG without pyplot and without touching matplotlib's
    global backend.

    Parameters
    ----------
    **kwargs
        Passed to :class:`matplotlib.figure.Figure` (``figsize``, ``layout``...).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, with its canvas.
    """
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def _state_label(i: int) -> str:
    return f"$x_{{{i + 1}}}$"


# --------------------------------------------------------------------------- the arena


def draw_box(ax: Axes, box: Box, dims: tuple[int, int], **style) -> None:
    """Draw the projection of ``box`` (length ``n``) on the state dimensions ``dims``.

    ``style`` goes to :class:`matplotlib.patches.Rectangle` (``fc``, ``ec``, ``label``...).
    """
    i, j = dims
    ax.add_patch(Rectangle((box.lower[i], box.lower[j]), box.upper[i] - box.lower[i],
                           box.upper[j] - box.lower[j], **style))


def obstacle_projection(unsafe: UnsafeSet, state_space: Box, dims: tuple[int, int],
                        **style) -> tuple[Patch, tuple[float, float]]:
    """The projection of an ``[[obstacles]]`` entry on the state dimensions ``dims``.

    On a plotted dimension the entry is not given on, it spans the state space: the
    projection is then the product of intervals (the shape's bounds, the state space's
    range). Given on both, a box is a rectangle, a ball of radius ``r`` a disc of radius
    ``r`` and a polytope the convex hull of its vertices' projections.

    Parameters
    ----------
    unsafe : UnsafeSet
    state_space : Box
        Length ``n``, state units.
    dims : tuple of int, length 2
    style
        Passed to the patch.

    Returns
    -------
    patch : matplotlib.patches.Patch
    anchor : tuple of float, length 2
        A point inside the projection, for its label, state units.
    """
    k = [unsafe.dims.index(d) if d in unsafe.dims else None for d in dims]
    if None not in k and unsafe.kind == "ball":
        center = (unsafe.shape.center[k[0]], unsafe.shape.center[k[1]])
        return Circle(center, unsafe.shape.radius, **style), center
    if None not in k and unsafe.kind == "polytope":
        points = np.array(unsafe.shape.vertices)[:, k]
        ring = points[ConvexHull(points).vertices]
        return Polygon(ring, **style), tuple(ring.mean(axis=0))
    lower = [state_space.lower[d] if m is None else unsafe.shape.lower[m]
             for d, m in zip(dims, k)]
    upper = [state_space.upper[d] if m is None else unsafe.shape.upper[m]
             for d, m in zip(dims, k)]
    anchor = ((lower[0] + upper[0]) / 2, (lower[1] + upper[1]) / 2)
    return Rectangle(lower, upper[0] - lower[0], upper[1] - lower[1], **style), anchor


def draw_unsafe_sets(ax: Axes, spec: Spec, dims: tuple[int, int]) -> None:
    """Draw every obstacle of the spec projected on ``dims``, numbered as in messages.

    Each ``[[obstacles]]`` entry ``j`` is one patch (:func:`obstacle_projection`) labelled
    ``j``; entries whose projections share a label point get one label (``"0, 2"``).
    Balls and polytopes also get their covering boxes (dashed), the boxes the design
    avoids. With ``[robot]`` the entries are drawn as given, over their inflated sets
    (hatched, the margin the reference point keeps).
    """
    anchors: dict[tuple[float, float], list[int]] = {}
    real, space = spec.unsafe_sets, spec.state_space
    if spec.robot is not None:      # the inflated sets hatched, the real ones over them
        real, space = spec.robot.unsafe_sets, spec.robot.state_space
        for k, unsafe in enumerate(spec.unsafe_sets):
            patch, _ = obstacle_projection(unsafe, spec.state_space, dims, **MARGIN_STYLE,
                                           label=MARGIN_LABEL if k == 0 else None,
                                           gid="robot margin")
            ax.add_patch(patch)
    for k, unsafe in enumerate(real):
        j = k if unsafe.source is None else unsafe.source
        patch, anchor = obstacle_projection(unsafe, space, dims, **OBSTACLE_STYLE,
                                            label=OBSTACLE_LABEL if k == 0 else None,
                                            gid=f"obstacle {j}")
        ax.add_patch(patch)
        anchors.setdefault((round(anchor[0], 9), round(anchor[1], 9)), []).append(j)
    for anchor, numbers in anchors.items():
        ax.annotate(", ".join(map(str, numbers)), anchor, ha="center", va="center",
                    color="white", fontweight="bold", gid="obstacle label", zorder=5,
                    bbox={"boxstyle": "round,pad=0.15", "fc": "0.3", "ec": "none"})
    kinds = {(k if u.source is None else u.source): u.kind
             for k, u in enumerate(spec.unsafe_sets)}
    covered = [o for o in spec.obstacles if kinds[o.source] != "box"]
    for m, obstacle in enumerate(covered):
        draw_box(ax, obstacle.box(spec.state_space), dims, fill=False, ec="tab:red", lw=0.5,
                 ls="--", label="covering boxes" if m == 0 else None)


def _equal_aspect(spec: Spec, dims: tuple[int, int]) -> bool:
    """Equal axis scales, unless one plotted range is over 3 times the other (the state
    dimensions then likely have different units, as a position and a heading)."""
    i, j = dims
    width = spec.state_space.upper[i] - spec.state_space.lower[i]
    height = spec.state_space.upper[j] - spec.state_space.lower[j]
    return 1 / 3 <= width / height <= 3


def draw_arena(ax: Axes, spec: Spec, dims: tuple[int, int]) -> None:
    """The state space, the obstacles and the target on ``ax``, projected on ``dims``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    spec : Spec
        The spec whose sets are drawn.
    dims : tuple of int, length 2
        The state dimensions of the axes, zero-based.
    """
    space = spec.state_space if spec.robot is None else spec.robot.state_space
    draw_box(ax, space, dims, fill=False, lw=1.5, ec="black")
    if spec.robot is not None:
        draw_box(ax, spec.state_space, dims, fill=False, lw=0.8, ec="0.4", ls=":",
                 label=f"state space shrunk by the robot's radius {spec.robot.radius:g}")
    draw_unsafe_sets(ax, spec, dims)
    draw_moving_obstacles(ax, spec, dims)      # time slices (motion_plots.py); none: nothing
    draw_box(ax, spec.target_set, dims, fc="tab:green", alpha=0.35, label="target")
    draw_tasks(ax, spec, dims)          # [[tasks]], if any
    i, j = dims
    ax.set_xlabel(_state_label(i))
    ax.set_ylabel(_state_label(j))
    pad = [0.02 * (space.upper[d] - space.lower[d]) for d in dims]
    ax.set_xlim(space.lower[i] - pad[0], space.upper[i] + pad[0])
    ax.set_ylim(space.lower[j] - pad[1], space.upper[j] + pad[1])
    ax.set_aspect("equal" if _equal_aspect(spec, dims) else "auto")


def arena_title(spec: Spec, dims: tuple[int, int], headline: str) -> str:
    """``headline``, and for ``n > 2`` a line saying the arena is a projection."""
    if spec.dimension <= 2:
        return headline
    i, j = dims
    return (f"{headline}\nprojection on ({_state_label(i)}, {_state_label(j)}) of the "
            f"{spec.dimension}-D state space")


def legend_below(ax: Axes) -> None:
    """The legend of ``ax`` under it and under its x tick labels and label, outside the
    data (offset by :data:`BELOW_AXIS_POINTS`, a length independent of the axes' size)."""
    anchor = offset_copy(ax.transAxes, fig=ax.figure, y=-BELOW_AXIS_POINTS, units="points")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=anchor, ncols=2,
              fontsize=7)


def legend_right(ax: Axes) -> None:
    """The legend of ``ax`` right of it, outside the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)


def arena_figure(spec: Spec, rows: int, dims: tuple[int, int]) -> tuple[Figure, GridSpec,
                                                                            Axes | None]:
    """The two-column figure: the arena on the left, ``rows`` time plots on the right.

    Parameters
    ----------
    spec : Spec
        The spec whose arena is drawn.
    rows : int
        Time plots in the right column.
    dims : tuple of int, length 2
        Checked by :func:`check_dims` when ``n >= 2``.

    Returns
    -------
    fig : matplotlib.figure.Figure
        The figure, on its Agg canvas.
    grid : matplotlib.gridspec.GridSpec
        ``rows`` rows, 2 columns.
    ax : matplotlib.axes.Axes or None
        The arena (:func:`draw_arena`, spanning the left column); ``None`` when ``n < 2``.
    """
    n = spec.dimension
    if n >= 2:
        dims = check_dims(dims, n)
    fig = agg_figure(figsize=(12, ROW_HEIGHT * max(rows, 3)), layout="constrained")
    grid = fig.add_gridspec(rows, 2, width_ratios=[1.1, 1.4])
    if n < 2:
        return fig, grid, None
    ax = fig.add_subplot(grid[:, 0])
    draw_arena(ax, spec, dims)
    return fig, grid, ax


# --------------------------------------------------------------------------- a run


def input_names(spec: Spec, m: int) -> list[str]:
    """Names of the ``m`` inputs of the spec's plant (``u1``... when it names none)."""
    named = PLANTS[spec.plant_model].inputs
    return list(named) if named else [f"u{k + 1}" for k in range(m)]


def draw_inputs(ax: Axes, spec: Spec, result: SimulationResult) -> None:
    """Each input ``u_k(t)`` against time (held between samples), one line each."""
    traj = result.trajectory
    for k, name in enumerate(input_names(spec, traj.u.shape[1])):
        ax.step(traj.t, traj.u[:, k], where="post", lw=0.9, label=name)
    ax.axvline(spec.prescribed_time, color="tab:red", lw=0.8, ls=":", label="$t_c$")
    ax.set_ylabel("u (plant units)")
    ax.set_xlabel("t [s]")
    legend_right(ax)


def draw_sensed(ax: Axes, spec: Spec, traj, dims: tuple[int, int]) -> None:
    """The obstacles a run sensed (:func:`~.sensed.simulate_sensed`), when the arena's two
    dimensions are among ``[sensing] dims``: each one's path, dotted, and its disc (a
    ball's section through its centre) every 2 s with the robot's place then."""
    if traj.sensed_positions is None or spec.sensing is None \
            or not set(dims) <= set(spec.sensing.dims):
        return
    columns = [list(spec.sensing.dims).index(d) for d in dims]
    every = max(1, int(round(2.0 * spec.rate_hz)))
    for j, radius in enumerate(traj.sensed_radii):
        path = traj.sensed_positions[:, j][:, columns]
        ax.plot(path[:, 0], path[:, 1], ":", color="tab:purple", lw=1.0,
                label="sensed obstacle's path" if j == 0 else None)
        for k in range(0, len(traj.t), every):
            ax.add_patch(Circle(path[k], radius, fc="tab:purple", alpha=0.15, ec="none"))
            ax.annotate(f"{traj.t[k]:.0f}", path[k], fontsize=6, ha="center", va="center")
    for k in range(0, len(traj.t), every):
        ax.annotate(f"{traj.t[k]:.0f}", traj.x[k, list(dims)], fontsize=6, color="k",
                    xytext=(0, 4), textcoords="offset points", ha="center")


def run_figure(design: Design, result: SimulationResult,
               dims: tuple[int, int] = DEFAULT_DIMS) -> Figure:
    """The figure of a closed-loop run: arena with the trajectory, the tube and the state
    per dimension against time, and the inputs against time.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`: the run's tube and (``design.spec``) its task.
    result : SimulationResult
        With its trajectory: ``x`` (N, n), ``u`` (N, m), ``alpha`` (N, 2n) at ``t`` (N,) s.
    dims : tuple of int, length 2
        State dimensions of the arena (:func:`check_dims`).

    Returns
    -------
    matplotlib.figure.Figure
        ``n + 1`` time plots: ``x_1``...``x_n`` in their tube, then ``u(t)``.
    """
    design = require_design(design, "run_figure")
    spec = design.spec
    traj = result.trajectory
    n = spec.dimension
    if traj.gamma_L is not None:        # a run whose tube changed: the active tube's
        g_l, g_u = traj.gamma_L, traj.gamma_U
    else:
        g_l, g_u, _, _ = reference.adaptive_tube(design.tube, traj.t, traj.alpha)
    fig, grid, ax = arena_figure(spec, n + 1, dims)
    if ax is not None:
        i, j = dims
        draw_box(ax, spec.initial_set, dims, fc="tab:blue", alpha=0.3, label="initial set")
        ax.plot(traj.x[:, i], traj.x[:, j], "k--", lw=1.2, label="trajectory")
        ax.plot(traj.x[0, i], traj.x[0, j], "o", color="tab:blue", label="x(0)")
        mark_states(ax, spec, traj.t, traj.x, dims)    # at the moving obstacles' slice times
        draw_sensed(ax, spec, traj, dims)
        verdict = "satisfied" if result.satisfied else "NOT satisfied"
        reach = "-" if result.reach_time is None else f"{result.reach_time:.3f}"
        ax.set_title(arena_title(spec, dims, f"{spec.name}: {verdict}, reach {reach} s"),
                     fontsize=10)
        legend_below(ax)
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        ax.fill_between(traj.t, g_l[:, i], g_u[:, i], color="tab:orange", alpha=0.25,
                        label=r"tube $[\gamma_L, \gamma_U]$")
        ax.plot(traj.t, g_l[:, i], color="tab:orange", lw=0.8)
        ax.plot(traj.t, g_u[:, i], color="tab:orange", lw=0.8)
        ax.plot(traj.t, traj.x[:, i], "k", lw=1.0, label="state")
        draw_task_windows(ax, spec, i)
        ax.axvline(spec.prescribed_time, color="tab:red", lw=0.8, ls=":", label="$t_c$")
        ax.set_ylabel(_state_label(i))
        if i == 0:
            legend_right(ax)
    draw_inputs(fig.add_subplot(grid[n, 1]), spec, result)
    return fig


def plot_run(design: Design, result: SimulationResult, path: str | Path, *,
             dims: tuple[int, int] = DEFAULT_DIMS) -> Path:
    """Write a PNG of a closed-loop run, in the manner of the paper's Fig. 3
    (:func:`run_figure`).

    On the left, the arena on the dimensions ``dims``: the state space, every obstacle
    (projected), the initial and target sets and the trajectory; on the right, for each
    dimension, the tube ``[gamma_L, gamma_U]`` of eq. (10) (with the run's ``alpha``)
    against time with the state inside it and ``t_c``, then the inputs ``u(t)``.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`: the run's tube and (``design.spec``) its task.
    result : SimulationResult
        From :func:`stt_codegen.simulate` on ``design``, with its trajectory.
    path : str or path
        Output file (PNG); its folder must exist.
    dims : tuple of int, length 2
        State dimensions of the arena, zero-based (:func:`check_dims`).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`, or ``result`` is
        not a :class:`~stt_codegen.runtime.simulate.SimulationResult`.
    SpecError
        ``dims`` is not two distinct dimensions of the state space (field ``dims``).

    See Also
    --------
    stt_codegen.simulate : the run.
    stt_codegen.plot_design : the certified tube, before any run.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> result = stt.simulate(design, backend="casadi", horizon=1.0)   # the first second
    >>> stt.plot_run(design, result, "s1-run.png").name
    's1-run.png'
    """
    design = require_design(design, "plot_run")
    if not isinstance(result, SimulationResult):
        raise TypeError(f"plot_run(): parameter 'result' must be a SimulationResult, not "
                        f"{type(result).__name__}")
    return save(run_figure(design, result, dims), path)


# --------------------------------------------------------------------------- a design


def draw_tube_boxes(ax: Axes, tube: TubeDesign, certificate: Certificate,
                    dims: tuple[int, int]) -> None:
    """Over the arena: the certified enclosure's box at up to :data:`BOXES_DRAWN`
    instants of ``[0, t_c]``, and the via boxes of a via-point tube."""
    enc = certificate.enclosure
    times = np.linspace(0.0, tube.prescribed_time, BOXES_DRAWN)
    intervals = np.unique(np.searchsorted(enc.t_start, times, side="right") - 1)
    for m, k in enumerate(intervals):
        draw_box(ax, Box(tuple(enc.lower_min[k]), tuple(enc.upper_max[k])), dims, fill=False,
                 ec="tab:orange", lw=0.6,
                 label="tube box (certified enclosure)" if m == 0 else None)
    via = [s for s in tube.segments if s.profile != TANH]
    for m, seg in enumerate(via):
        draw_box(ax, Box(seg.lower_to, seg.upper_to), dims, fill=False, ec="tab:purple",
                 lw=1.2, label="via boxes" if m == 0 else None)


def draw_enclosure(ax: Axes, certificate: Certificate, i: int, end: float) -> None:
    """The certified ranges of ``gamma_L`` and ``gamma_U`` of dimension ``i`` on
    ``[0, end]`` s, one band per interval of the certificate."""
    enc = certificate.enclosure
    keep = enc.t_start < end
    t0 = enc.t_start[keep]
    t1 = np.minimum(enc.t_end[keep], end)
    for lo, hi, colour, name in ((enc.lower_min, enc.lower_max, "tab:blue", r"$\gamma_L$"),
                                 (enc.upper_min, enc.upper_max, "tab:orange", r"$\gamma_U$")):
        for k in range(t0.size):
            ax.fill_between([t0[k], t1[k]], [lo[keep][k, i]] * 2, [hi[keep][k, i]] * 2,
                            color=colour, alpha=0.35, lw=0.8, edgecolor=colour,
                            label=f"{name} enclosure" if k == 0 else None)


def tube_figure(spec: Spec, tube: TubeDesign, certificate: Certificate, headline: str,
                dims: tuple[int, int], reason: str = "",
                failure_time: float | None = None) -> Figure:
    """The figure of a tube and its certificate: tube and via boxes over the arena, the
    enclosure of ``gamma_L``, ``gamma_U`` per dimension against time.

    Parameters
    ----------
    spec : Spec
    tube : TubeDesign
    certificate : Certificate
        Of ``tube`` (its enclosure covers every ``t >= 0``).
    headline : str
        First line of the arena's title (of the figure's when ``n < 2``).
    dims : tuple of int, length 2
        State dimensions of the arena.
    reason : str, optional
        Why the tube was rejected: the figure's title, wrapped to :data:`TITLE_WIDTH`
        characters and cut at :data:`TITLE_LINES` lines.
    failure_time : float, optional
        Where the certificate's first failure is, seconds: marked on the time plots.

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = spec.dimension
    t_c = tube.prescribed_time
    fig, grid, ax = arena_figure(spec, n, dims)
    wrapped = textwrap.fill(reason, TITLE_WIDTH, max_lines=TITLE_LINES, placeholder=" [...]")
    title = "\n".join(part for part in (headline if ax is None else "", wrapped) if part)
    if title:
        fig.suptitle(title, fontsize=9)
    if ax is not None:
        draw_tube_boxes(ax, tube, certificate, dims)
        ax.set_title(arena_title(spec, dims, headline), fontsize=10)
        legend_below(ax)
    end = 1.2 * max(t_c, failure_time or 0.0)
    for i in range(n):
        ax = fig.add_subplot(grid[i, 1])
        draw_enclosure(ax, certificate, i, end)
        draw_task_windows(ax, spec, i)
        ax.axvline(t_c, color="tab:red", lw=0.8, ls=":", label="$t_c$")
        if failure_time is not None:
            ax.axvline(failure_time, color="black", lw=1.0, ls="-.",
                       label=f"first failure ({failure_time:.3g} s)")
        ax.set_ylabel(_state_label(i))
        if i == n - 1:
            ax.set_xlabel("t [s] (certified for every t >= 0; drawn up to "
                          f"{end:.3g} s)")
        if i == 0:
            legend_right(ax)
    return fig


def design_figure(design: Design, dims: tuple[int, int] = DEFAULT_DIMS) -> Figure:
    """The figure of a certified design (:func:`tube_figure`), its method and time in the
    title.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`.
    dims : tuple of int, length 2, optional
        State dimensions of the arena, zero-based (:func:`check_dims`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, on its Agg canvas (:func:`agg_figure`).

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.
    """
    design = require_design(design, "design_figure")
    spec = design.spec
    return tube_figure(spec, design.tube, design.certificate,
                       f"{spec.name}: {design.method} method, "
                       f"{design.design_time_s * 1e3:.1f} ms", dims)


def plot_design(design: Design, path: str | Path, *,
                dims: tuple[int, int] = DEFAULT_DIMS) -> Path:
    """Write a PNG of ``design``: tube boxes (the certificate's enclosure) and via boxes
    over the arena, and the certified enclosure of ``gamma_L``, ``gamma_U`` (eq. (10)) per
    dimension against time (:func:`design_figure`).

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube` (its spec gives the arena).
    path : str or path
        Output file (PNG); its folder must exist.
    dims : tuple of int, length 2
        State dimensions of the arena, zero-based (:func:`check_dims`).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.
    SpecError
        ``dims`` is not two distinct dimensions of the state space (field ``dims``).

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
    return save(design_figure(require_design(design, "plot_design"), dims), path)


def rejected_figure(spec: Spec, error: DesignError,
                    dims: tuple[int, int] = DEFAULT_DIMS) -> Figure:
    """The figure of the best rejected tube of a failed design, the reason in its title.

    The tube ``error.tried`` is checked again (:func:`~stt_codegen.design.search.check_tube`)
    for its enclosure; its first failure is marked on the time plots.

    Parameters
    ----------
    spec : Spec
        The spec that has no design.
    error : DesignError
        From :func:`stt_codegen.design_tube` on ``spec``, with ``tried`` not ``None``.
    dims : tuple of int, length 2, optional
        State dimensions of the arena, zero-based (:func:`check_dims`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, on its Agg canvas (:func:`agg_figure`).

    Raises
    ------
    ValueError
        ``error.tried`` is ``None``: no tube was built.
    """
    from ..design.search import check_tube
    if error.tried is None:
        raise ValueError("the design error carries no tube tried")
    certificate = check_tube(error.tried, spec).certificate
    failure = certificate.first_failure()
    kind = "" if error.kind is None else f" ({error.kind.value})"
    # a tube that passes its check was refused at a later stage (a second stage)
    what = "the best rejected tube" if failure is not None else "the tube designed"
    return tube_figure(spec, error.tried, certificate,
                       f"{spec.name}: NO DESIGN{kind}, {what}", dims,
                       f"no design: {error}", None if failure is None else failure.time)


def plot_rejected(spec: Spec, error: DesignError, path: str | Path, *,
                  dims: tuple[int, int] = DEFAULT_DIMS) -> Path:
    """Write a PNG of the best rejected tube of a failed design (:func:`rejected_figure`).

    Parameters
    ----------
    spec : Spec
        The spec that has no design.
    error : DesignError
        With ``tried`` not ``None``.
    path : str or path
        Output file; its folder must exist.
    dims : tuple of int, length 2
        State dimensions of the arena.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    return save(rejected_figure(spec, error, dims), path)


def save(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` as PNG to ``path`` (its folder must exist).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or pathlib.Path
        The PNG file to write (110 dpi).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    out = Path(path)
    fig.savefig(out, dpi=110, format="png")
    return out
