"""Timed tasks on the figures: each task's boxes on the arena, its window on the time plots.

Reach boxes are dashed pink outlines, stay boxes dotted cyan ones, captioned with the
task's label and window (``"T1 [7, 8] s"``; docs/tasks.md).
"""

from __future__ import annotations

from matplotlib.axes import Axes
from matplotlib.patches import Rectangle

from ..spec.loader import Box, Spec
from ..spec.tasks import STAY, Task

__all__ = ["draw_task_windows", "draw_tasks"]


def task_caption(task: Task) -> str:
    """The label drawn beside a task's box: ``"T1 [7, 8] s"`` (``"T2 stay [2, 4] s"``)."""
    kind = " stay" if task.kind == STAY else ""
    return f"{task.label}{kind} [{task.window[0]:g}, {task.window[1]:g}] s"


def draw_tasks(ax: Axes, spec: Spec, dims: tuple[int, int]) -> None:
    """Draw every task's boxes projected on ``dims``, captioned (:func:`task_caption`).

    Reach boxes are dashed pink outlines, stay boxes dotted cyan ones; every ``any_of``
    box carries the caption.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The arena's axes.
    spec : Spec
        The spec whose ``tasks`` are drawn.
    dims : tuple of int, length 2
        The state dimensions of the axes, zero-based.
    """
    i, j = dims
    for task in spec.tasks:
        color = "tab:cyan" if task.kind == STAY else "tab:pink"
        for q, box in enumerate(task.boxes):
            b = Box(box.lower, box.upper)
            ax.add_patch(Rectangle((b.lower[i], b.lower[j]), b.upper[i] - b.lower[i],
                                   b.upper[j] - b.lower[j], fill=False, ec=color, lw=1.3,
                                   ls=":" if task.kind == STAY else "--",
                                   gid=f"task {task.label}",
                                   label="task box" if (task.index, q) == (0, 0) else None))
            ax.text(b.lower[i], b.upper[j], task_caption(task), fontsize=7, color=color,
                    va="bottom", ha="left", gid="task label", zorder=5)


def draw_task_windows(ax: Axes, spec: Spec, i: int) -> None:
    """On a time plot of state ``x_i``: each task's box over its window (``[t0, t1]`` by
    the box's range in dimension ``i``), captioned.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The time plot of ``x_i`` (time in s on the horizontal axis).
    spec : Spec
        The spec whose ``tasks`` are drawn.
    i : int
        The state dimension of the plot, zero-based.
    """
    for task in spec.tasks:
        color = "tab:cyan" if task.kind == STAY else "tab:pink"
        t0, t1 = task.window
        for box in task.boxes:
            ax.add_patch(Rectangle((t0, box.lower[i]), t1 - t0, box.upper[i] - box.lower[i],
                                   fill=False, ec=color, lw=1.0,
                                   ls=":" if task.kind == STAY else "--",
                                   gid=f"task {task.label}"))
        ax.text(t0, max(b.upper[i] for b in task.boxes), task.label, fontsize=7,
                color=color, va="bottom", ha="left", gid="task label")
