"""Seeded random arenas, one generator for every benchmark: :func:`make_arena`.

``make_arena(kind, seed, index)`` returns the text of a spec file (TOML); arena ``index`` of
``seed`` draws every number from ``numpy.random.default_rng([seed, index])`` (and streams
derived from it, below), so it does not depend on how many arenas are drawn, or in which
order or process. The kinds (:data:`ARENA_KINDS`):

``"paper"`` (``bench arenas``), in the spirit of the paper's Table I (section V), which
compares planners on 500 arenas with "obstacles placed at random" and gives no further
protocol; this one is fixed:

* the state space is the case study's 5 m x 5 m arena ``[0, 5] x [0, 5]``;
* four obstacles of the case study's size, 1 m x 1 m, whose lower-left corners are drawn
  uniformly in ``[0, 4] x [0, 4]`` (they may overlap each other and touch the walls);
* a 0.5 m x 0.5 m start set whose lower-left corner is drawn uniformly in
  ``[0, 4.5] x [0, 4.5]``; ``x(0)`` is its centre;
* the case study's target ``[4.5, 5] x [4.5, 5]``;
* an arena in which the start set or the target meets an obstacle (touching counts), or
  the start set meets the target (a trivial task), is drawn again;
* the single integrator ``x_dot = u + w`` in 2-D with the bundled specs' disturbance bound
  ``|w_i| <= 0.1`` m/s and tube parameters (``delta_b = 0.2``, ``circumvent_sharpness =
  0.1``, ``theta0 = 0.01``, ``kappa = 5``, ``mu = 1``, half-widths ``d_0 = d_T = 0.2``,
  1 kHz), and ``t_c = 9`` s.

``"moving"`` (``python -m stt_codegen_bench.moving_study``): the ``"paper"`` arena and 0-4
moving obstacles (:func:`~.moving.random_moving_obstacles`) from a second generator
``default_rng([seed, index])``, appended to ``[[obstacles]]``.

``"tasks"`` (``bench tasks``, docs/tasks.md): the ``"paper"`` arena with timed reach tasks
drawn from ``default_rng([seed, index, 1])``:

* ``m`` = 2 or 3 tasks (equally likely), ``t_c = 4 (m + 1)`` seconds;
* task ``j`` (from 0) has the window ``[4 (j + 1) - 0.5, 4 (j + 1) + 0.5]`` s;
* each task box is :data:`TASK_SIZE` m square, its lower corner uniform in
  ``[0, 5 - TASK_SIZE]^2``; the first task is an ``any_of`` of two such boxes;
* a box that meets an obstacle (touching allowed, as the spec's rule), the target or the
  start set is drawn again;
* then 0-4 moving obstacles (the count drawn uniformly), from the same generator after the
  task boxes, each never meeting the start set, the target or a task box (every
  ``any_of`` alternative) while active; they follow the four static boxes.

``"office-drive"`` and ``"office-holonomic"`` (``bench drive``, docs/differential-drive.md):
a 10 m x 8 m room, six desks and cabinets (boxes of sides drawn in [0.6, 1.6] m, anywhere in
the room), the start box ``[0.5, 1.5]^2`` with a heading drawn in ``[-pi, pi)``, the target
box by the door ``[8.6, 9.6] x [6.6, 7.6]``, ``t_c = 20`` s, 200 Hz (:data:`OFFICE_RATE_HZ`);
an office is redrawn while a box, grown by :data:`OFFICE_CLEARANCE`, meets the start or the
target box. The same office for two bases:

* ``drive``: ``plant.model = "differential-drive"`` (axle offset 0.1 m, track 0.16 m, wheel
  errors ``+-5 %``, slip ``[0.02, 0.01, 0.05]``, body radius 0.12 m);
* ``holonomic``: ``plant.model = "single-integrator"`` with the same body radius and the
  same disturbance bound (a base that moves in every direction, law (13) on its centre).

``"polygons"`` (``bench covering``): ``polygons`` random convex polygons (3-7 vertices,
radius 0.05-0.2 m, centres in ``[0.9, 4.1]^2``) from ``default_rng(seed)`` (one arena a
seed: ``index`` is 0), each covered at ``tolerance``, in the 5 m x 5 m arena with the start
``[0, 0.5]^2`` and the target ``[4.5, 5]^2``.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import Box, Spec, parse_spec

from .moving import random_moving_obstacles

__all__ = ["ARENA", "ARENA_KINDS", "OBSTACLE_SIZE", "OFFICE_CLEARANCE", "OFFICE_RATE_HZ",
           "OFFICE_START", "OFFICE_TARGET", "START_SIZE", "TARGET", "arena_spec", "make_arena"]

#: Every kind :func:`make_arena` draws (module notes).
ARENA_KINDS = ("paper", "moving", "tasks", "office-drive", "office-holonomic", "polygons")

#: The case study's arena, target, obstacle size and start-set size, metres.
ARENA = Box((0.0, 0.0), (5.0, 5.0))
TARGET = Box((4.5, 4.5), (5.0, 5.0))
OBSTACLE_SIZE = 1.0
START_SIZE = 0.5
OBSTACLE_COUNT = 4
PRESCRIBED_TIME = 9.0
#: Draws allowed for one arena or box before giving up (never reached in practice: about
#: one draw in three is accepted).
MAX_DRAWS = 10_000

#: ``"tasks"``: side of a task box (m), seconds between consecutive window centres (and
#: before the first), half the length of a window (s).
TASK_SIZE = 0.6
WINDOW_SPACING = 4.0
WINDOW_HALF = 0.5

#: The offices: the room, the start and target boxes (m); obstacles, their side range (m)
#: and the clearance they keep from start and target (m).
OFFICE_ROOM = ((0.0, 0.0), (10.0, 8.0))
OFFICE_START = ((0.5, 0.5), (1.5, 1.5))
OFFICE_TARGET = ((8.6, 6.6), (9.6, 7.6))
OFFICE_OBSTACLES, OFFICE_SIDES, OFFICE_CLEARANCE = 6, (0.6, 1.6), 0.3
#: The offices' sampling rate, Hz: the drive's sampled-data check counts the heading's turn
#: while (v, omega) is held (docs/differential-drive.md); it certifies none of offices 0-9 of
#: seed 0 at 50 or 100 Hz, all ten at 200 Hz.
OFFICE_RATE_HZ = 200.0
#: The bases: body radius (m), the drive's axle offset and track width (m), wheel errors,
#: slip (m/s, m/s, rad/s).
RADIUS, AXLE_OFFSET, TRACK_WIDTH = 0.12, 0.1, 0.16
WHEEL_ERRORS, SLIP = (0.05, -0.05), (0.02, 0.01, 0.05)

#: ``"polygons"``: the default count and covering tolerance (docs/performance.md).
DEFAULT_POLYGONS = 80
DEFAULT_TOLERANCE = 0.02

_PAPER = """\
# Random arena {index} of seed {seed} (stt_codegen_bench.arenas): the paper's 5 m x 5 m
# arena, four 1 m x 1 m obstacles at random, a random 0.5 m x 0.5 m start set, the case
# study's target; single integrator x_dot = u + w, |w_i| <= 0.1.
name = "{name}"
prescribed_time = {t_c!r}

[state_space]
lower = [0.0, 0.0]
upper = [5.0, 5.0]

[initial]
lower = [{s0!r}, {s1!r}]
upper = [{s2!r}, {s3!r}]
half_width = [0.2, 0.2]

[target]
lower = [4.5, 4.5]
upper = [5.0, 5.0]
half_width = [0.2, 0.2]
{obstacles}
[tube]
delta_b = 0.2
circumvent_sharpness = 0.1
theta0 = 0.01
kappa = 5.0
mu = 1.0

[controller]
rate_hz = 1000.0

[plant]
model = "single-integrator"
disturbance_amplitude = 0.1
"""


def _value(v: Any) -> str:
    """A TOML value: numbers exactly (``repr``), strings quoted, lists nested."""
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v)
    return repr(v)


def _toml(doc: dict[str, Any]) -> str:
    """A spec document of plain values, tables and arrays of tables as TOML text."""
    def is_table(v):
        return isinstance(v, dict)

    def is_tables(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    text = "".join(f"{k} = {_value(v)}\n" for k, v in doc.items()
                   if not is_table(v) and not is_tables(v))
    for key, v in doc.items():
        for table in [v] if is_table(v) else v if is_tables(v) else []:
            text += f"\n[{key}]\n" if is_table(v) else f"\n[[{key}]]\n"
            text += "".join(f"{k} = {_value(x)}\n" for k, x in table.items())
    return text


def _square(corner: np.ndarray, size: float) -> Box:
    return Box(tuple(float(v) for v in corner), tuple(float(v + size) for v in corner))


def _paper(seed: int, index: int) -> tuple[str, list[Box]]:
    """The ``"paper"`` arena's text, and its start box and obstacles."""
    rng = np.random.default_rng([seed, index])
    room_o = ARENA.upper[0] - OBSTACLE_SIZE
    room_s = ARENA.upper[0] - START_SIZE
    for _ in range(MAX_DRAWS):
        obstacles = tuple(_square(rng.uniform(0.0, room_o, 2), OBSTACLE_SIZE)
                          for _ in range(OBSTACLE_COUNT))
        start = _square(rng.uniform(0.0, room_s, 2), START_SIZE)
        if not (start.meets(TARGET) or any(o.meets(start) or o.meets(TARGET)
                                           for o in obstacles)):
            break
    else:   # pragma: no cover
        raise AssertionError("unreachable: no acceptable arena in MAX_DRAWS draws")
    boxes = "".join(f"\n[[obstacles]]\nlower = [{o.lower[0]!r}, {o.lower[1]!r}]\n"
                    f"upper = [{o.upper[0]!r}, {o.upper[1]!r}]\n" for o in obstacles)
    text = _PAPER.format(index=index, seed=seed, name=f"arena-{seed}-{index}",
                         t_c=PRESCRIBED_TIME, s0=start.lower[0], s1=start.lower[1],
                         s2=start.upper[0], s3=start.upper[1], obstacles=boxes)
    return text, [start, *obstacles]


def _moving_toml(entries: list[dict[str, Any]]) -> str:
    """Moving obstacles (:func:`~.moving.random_moving_obstacles`) as ``[[obstacles]]``."""
    return "".join("\n[[obstacles]]\n" + "".join(f"{key} = {_value(entry[key])}\n"
                                                 for key in ("lower", "upper", "velocity",
                                                             "active", "path") if key in entry)
                   for entry in entries)


def _moving(seed: int, index: int) -> str:
    text, _ = _paper(seed, index)
    rng = np.random.default_rng([seed, index])
    return text + _moving_toml(random_moving_obstacles(rng, parse_spec(text)))


def _strictly_meets(a: Box, b: Box) -> bool:
    return all(c < bb and aa < d for aa, bb, c, d in zip(a.lower, a.upper, b.lower, b.upper))


def _task_box(rng: np.random.Generator, avoid: list[Box]) -> str:
    for _ in range(MAX_DRAWS):
        corner = rng.uniform(0.0, 5.0 - TASK_SIZE, 2)
        box = Box(tuple(float(v) for v in corner), tuple(float(v + TASK_SIZE) for v in corner))
        if not any(_strictly_meets(box, o) for o in avoid):
            return (f"lower = [{box.lower[0]!r}, {box.lower[1]!r}]\n"
                    f"upper = [{box.upper[0]!r}, {box.upper[1]!r}]\n")
    raise AssertionError("unreachable: no free task box in MAX_DRAWS draws")  # pragma: no cover


def _tasks(seed: int, index: int) -> str:
    text, (start, *obstacles) = _paper(seed, index)
    rng = np.random.default_rng([seed, index, 1])
    m = int(rng.integers(2, 4))
    t_c = WINDOW_SPACING * (m + 1)
    avoid = obstacles + [TARGET, start]
    text = text.replace("prescribed_time = 9.0", f"prescribed_time = {t_c!r}", 1)
    text = text.replace(f'name = "arena-{seed}-{index}"', f'name = "tasks-{seed}-{index}"', 1)
    text = text.replace("# Random arena", "# Random timed tasks (stt_codegen_bench.arenas, "
                        "kind tasks) in random arena", 1)
    for j in range(m):
        centre = WINDOW_SPACING * (j + 1)
        window = f"window = [{centre - WINDOW_HALF!r}, {centre + WINDOW_HALF!r}]\n"
        text += f'\n[[tasks]]\nkind = "reach"\n{window}'
        if j == 0:
            first, second = _task_box(rng, avoid), _task_box(rng, avoid)
            text += "any_of = [ { " + first.replace("\n", ", ").rstrip(", ") + \
                " },\n           { " + second.replace("\n", ", ").rstrip(", ") + " } ]\n"
        else:
            text += _task_box(rng, avoid)
    with_tasks = parse_spec(text)
    boxes = [box for task in with_tasks.tasks for box in task.boxes]
    return text + _moving_toml(random_moving_obstacles(rng, with_tasks, keep_clear=boxes))


def _meets(box, other, grow: float) -> bool:
    return all(box[0][i] - grow < other[1][i] and other[0][i] < box[1][i] + grow
               for i in range(2))


def _office(seed: int, index: int, base: str) -> str:
    rng = np.random.default_rng([seed, index])
    while True:
        boxes = []
        for _ in range(OFFICE_OBSTACLES):
            side = rng.uniform(*OFFICE_SIDES, 2)
            corner = rng.uniform(OFFICE_ROOM[0], np.array(OFFICE_ROOM[1]) - side)
            boxes.append(((float(corner[0]), float(corner[1])),
                          (float(corner[0] + side[0]), float(corner[1] + side[1]))))
        if not any(_meets(b, s, OFFICE_CLEARANCE) for b in boxes
                   for s in (OFFICE_START, OFFICE_TARGET)):
            break
    heading = float(rng.uniform(-math.pi, math.pi))
    doc = {"name": f"office-{seed}-{index}-{base}", "prescribed_time": 20.0,
           "state_space": {"lower": list(OFFICE_ROOM[0]), "upper": list(OFFICE_ROOM[1])},
           "initial": {"lower": list(OFFICE_START[0]), "upper": list(OFFICE_START[1])},
           "target": {"lower": list(OFFICE_TARGET[0]), "upper": list(OFFICE_TARGET[1])},
           "obstacles": [{"lower": list(lo), "upper": list(hi)} for lo, hi in boxes],
           "controller": {"rate_hz": OFFICE_RATE_HZ}, "robot": {"radius": RADIUS}}
    if base == "drive":
        doc["initial"]["heading"] = heading
        doc["plant"] = {"model": "differential-drive", "axle_offset": AXLE_OFFSET,
                        "track_width": TRACK_WIDTH, "wheel_radius_error": list(WHEEL_ERRORS),
                        "slip": list(SLIP)}
    else:       # the same disturbance bound: sqrt(2) a = |w| of the drive's slip
        bound = math.hypot(SLIP[0], SLIP[1] + AXLE_OFFSET * SLIP[2])
        doc["plant"] = {"model": "single-integrator",
                        "disturbance_amplitude": bound / math.sqrt(2.0)}
    return (f"# Office {index} of seed {seed} (stt_codegen_bench.arenas, kind office-{base})\n"
            + _toml(doc))


def _polygons(seed: int, polygons: int, tolerance: float) -> str:
    rng = np.random.default_rng(seed)
    extra = ""
    for _ in range(polygons):
        centre, radius = rng.uniform(0.9, 4.1, 2), rng.uniform(0.05, 0.2)
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, int(rng.integers(3, 8))))
        points = centre + radius * np.c_[np.cos(angles), np.sin(angles)]
        extra += ("[[obstacles]]\nvertices = [" + ", ".join(
            f"[{float(x)!r}, {float(y)!r}]" for x, y in points) + f"]\ntolerance = {tolerance!r}\n")
    return (f'\nname = "polygons-{seed}-{polygons}"\nprescribed_time = 9.0\n'
            "[state_space]\nlower = [0.0, 0.0]\nupper = [5.0, 5.0]\n"
            "[initial]\nlower = [0.0, 0.0]\nupper = [0.5, 0.5]\n"
            "[target]\nlower = [4.5, 4.5]\nupper = [5.0, 5.0]\n" + extra)


def make_arena(kind: str, seed: int, index: int = 0, *, polygons: int = DEFAULT_POLYGONS,
               tolerance: float = DEFAULT_TOLERANCE) -> str:
    """Arena ``index`` of ``seed`` of one kind, as the text of a spec file (module notes).

    Parameters
    ----------
    kind : str
        One of :data:`ARENA_KINDS`.
    seed : int
        Non-negative.
    index : int, optional
        Non-negative; 0 for ``"polygons"`` (one arena a seed).
    polygons : int, optional
        ``"polygons"`` only: how many, >= 0.
    tolerance : float, optional
        ``"polygons"`` only: every polygon's covering tolerance, metres.

    Returns
    -------
    str
        TOML text, loadable by :func:`stt_codegen.spec.loader.parse_spec`; the same bytes
        for the same arguments.

    Raises
    ------
    SpecError
        An unknown ``kind`` (field ``kind``), a negative ``seed`` or ``index`` (fields
        ``seed``, ``index``), a non-zero ``index`` or negative ``polygons`` for
        ``"polygons"``.
    """
    if kind not in ARENA_KINDS:
        raise SpecError("kind", f"must be one of {', '.join(ARENA_KINDS)}, got {kind!r}")
    if seed < 0:
        raise SpecError("seed", f"must be non-negative, got {seed}")
    if index < 0:
        raise SpecError("index", f"must be non-negative, got {index}")
    if kind == "polygons":
        if index != 0:
            raise SpecError("index", f"the polygons have one arena a seed (0), got {index}")
        if polygons < 0:
            raise SpecError("count", f"must be non-negative, got {polygons}")
        return _polygons(seed, polygons, tolerance)
    if kind.startswith("office-"):
        return _office(seed, index, kind.removeprefix("office-"))
    return {"paper": lambda: _paper(seed, index)[0], "moving": lambda: _moving(seed, index),
            "tasks": lambda: _tasks(seed, index)}[kind]()


def arena_spec(kind: str, seed: int, index: int = 0, **options: Any) -> Spec:
    """The validated spec of :func:`make_arena`'s arena.

    Parameters
    ----------
    kind : str
        One of :data:`ARENA_KINDS`.
    seed : int
        Non-negative.
    index : int, optional
        Non-negative.
    **options
        ``polygons`` and ``tolerance``, as :func:`make_arena`'s.

    Returns
    -------
    Spec
        ``parse_spec(make_arena(kind, seed, index, **options))``.

    Raises
    ------
    SpecError
        As :func:`make_arena`, or an arena the loader refuses (``"polygons"`` with a bad
        ``tolerance``).
    """
    return parse_spec(make_arena(kind, seed, index, **options))
