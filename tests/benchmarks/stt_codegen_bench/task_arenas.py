"""Seeded random timed-task problems for ``stt-codegen bench tasks`` (docs/tasks.md).

Problem ``k`` of seed ``S`` is random arena ``k`` of seed ``S`` of :mod:`.arenas` (the
case study's 5 m x 5 m arena, four random 1 m x 1 m obstacles, a random start set, the
target ``[4.5, 5] x [4.5, 5]``, the single integrator with ``|w_i| <= 0.1``) with timed
reach tasks drawn from ``numpy.random.default_rng([S, k, 1])``:

* ``m`` = 2 or 3 tasks (equally likely), ``t_c = 4 (m + 1)`` seconds;
* task ``j`` (from 0) has the window ``[4 (j + 1) - 0.5, 4 (j + 1) + 0.5]`` s;
* each task box is :data:`TASK_SIZE` m square, its lower corner uniform in
  ``[0, 5 - TASK_SIZE]^2``; the first task is an ``any_of`` of two such boxes;
* a box that meets an obstacle (touching allowed, as the spec's rule), the target or the
  start set is drawn again;
* then 0-4 moving obstacles (:func:`~.moving.random_moving_obstacles`, the count drawn
  uniformly), from the same generator after the task boxes, each never meeting the start
  set, the target or a task box (every ``any_of`` alternative) while active; they are
  appended to ``[[obstacles]]`` after the four static boxes.
"""

from __future__ import annotations

import numpy as np

from stt_codegen.spec.loader import Box, Spec, parse_spec
from .arenas import generate_arena
from .moving import random_moving_obstacles

__all__ = ["task_problem", "task_problem_toml"]

#: Side of a task box, metres.
TASK_SIZE = 0.6
#: Seconds between consecutive window centres (and before the first).
WINDOW_SPACING = 4.0
#: Half the length of a window, seconds.
WINDOW_HALF = 0.5
#: Draws allowed for one box before giving up (never reached in practice).
MAX_DRAWS = 10_000


def _strictly_meets(a: Box, b: Box) -> bool:
    return all(c < bb and aa < d for aa, bb, c, d in zip(a.lower, a.upper, b.lower, b.upper))


def _draw_box(rng: np.random.Generator, avoid: list[Box]) -> Box:
    for _ in range(MAX_DRAWS):
        corner = rng.uniform(0.0, 5.0 - TASK_SIZE, 2)
        box = Box(tuple(float(v) for v in corner), tuple(float(v + TASK_SIZE) for v in corner))
        if not any(_strictly_meets(box, o) for o in avoid):
            return box
    raise AssertionError("unreachable: no free task box in MAX_DRAWS draws")  # pragma: no cover


def _box_toml(box: Box) -> str:
    return (f"lower = [{box.lower[0]!r}, {box.lower[1]!r}]\n"
            f"upper = [{box.upper[0]!r}, {box.upper[1]!r}]\n")


def task_problem_toml(seed: int, index: int) -> str:
    """Problem ``index`` of ``seed`` as a spec file (module notes).

    Parameters
    ----------
    seed, index : int
        Non-negative.

    Returns
    -------
    str
        TOML text, loadable by :func:`stt_codegen.spec.loader.parse_spec`.

    Raises
    ------
    SpecError
        A negative seed or index (fields ``seed``, ``index``).
    """
    arena = generate_arena(seed, index)
    rng = np.random.default_rng([seed, index, 1])
    m = int(rng.integers(2, 4))
    t_c = WINDOW_SPACING * (m + 1)
    avoid = list(arena.obstacles) + [Box((4.5, 4.5), (5.0, 5.0)), arena.start]
    text = arena.to_toml().replace("prescribed_time = 9.0", f"prescribed_time = {t_c!r}", 1)
    text = text.replace(f'name = "{arena.name}"', f'name = "tasks-{seed}-{index}"', 1)
    text = text.replace("# Random arena", "# Random timed tasks (stt_codegen_bench.task_arenas) "
                        "in random arena", 1)
    for j in range(m):
        centre = WINDOW_SPACING * (j + 1)
        window = f"window = [{centre - WINDOW_HALF!r}, {centre + WINDOW_HALF!r}]\n"
        text += f'\n[[tasks]]\nkind = "reach"\n{window}'
        if j == 0:
            first, second = _draw_box(rng, avoid), _draw_box(rng, avoid)
            text += "any_of = [ { " + _box_toml(first).replace("\n", ", ").rstrip(", ") + \
                " },\n           { " + _box_toml(second).replace("\n", ", ").rstrip(", ") + \
                " } ]\n"
        else:
            text += _box_toml(_draw_box(rng, avoid))
    with_tasks = parse_spec(text)
    boxes = [box for task in with_tasks.tasks for box in task.boxes]
    for entry in random_moving_obstacles(rng, with_tasks, keep_clear=boxes):
        text += _moving_toml(entry)
    return text


def _moving_toml(entry: dict) -> str:
    """A moving obstacle's spec-dict entry (:func:`~.moving.random_moving_obstacles`) as an
    ``[[obstacles]]`` table, numbers written exactly (``repr``)."""
    def value(v) -> str:
        return "[" + ", ".join(value(x) for x in v) + "]" if isinstance(v, list) else repr(v)
    return "\n[[obstacles]]\n" + "".join(f"{key} = {value(entry[key])}\n"
                                         for key in ("lower", "upper", "velocity", "active",
                                                     "path") if key in entry)


def task_problem(seed: int, index: int) -> Spec:
    """Problem ``index`` of ``seed`` (:func:`task_problem_toml`), validated.

    Parameters
    ----------
    seed : int
        Problem seed, >= 0.
    index : int
        Problem index, >= 0.

    Returns
    -------
    Spec
        The validated spec ``tasks-<seed>-<index>``.

    Raises
    ------
    SpecError
        A negative seed or index.
    """
    return parse_spec(task_problem_toml(seed, index))
