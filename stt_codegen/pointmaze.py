"""Specs from gymnasium-robotics' PointMaze mazes (``stt-codegen import pointmaze NAME``).

gymnasium-robotics (the optional extra ``pip install ".[mujoco]"``) encodes a maze as rows
of cells, ``1`` a wall block, ``0`` free, ``"r"``/``"g"``/``"c"`` a free cell where the ball
may be reset, the goal may be, or both (``gymnasium_robotics/envs/maze/maps.py``). Its
``Maze.make_maze`` (``maze_v4.py``) puts cell ``(row i, column j)`` of a map of ``H`` rows
and ``W`` columns at the centre ``x = (j + 1/2) s - W s / 2``, ``y = H s / 2 - (i + 1/2) s``
(``s`` the ``maze_size_scaling``, 1 for PointMaze), each wall a box of side ``s``. The
PointMaze ball is the sphere ``particle_geom`` of ``assets/point/point.xml`` (radius 0.1 m).

:func:`import_pointmaze` reads the map from the installed package (nothing is downloaded)
and writes a spec: the walls merged into few boxes (:func:`wall_boxes`), the state space
the maze's bounding box, ``[robot] radius`` the ball's radius plus a contact margin, the
start and goal cells as the initial and target sets.
"""

from __future__ import annotations

import os
import shutil
import contextlib
import io
from collections import deque
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

from .errors import SpecError
from .spec.plants import SECOND_ORDER_PLANTS, plant_entry
from .system import atomic_write

__all__ = ["DEFAULT_CONTACT_MARGIN", "DEFAULT_RATE_HZ", "JOINTS", "SECONDS_PER_CELL", "SERVOS",
           "SERVO_ASSUMPTIONS", "SERVO_DISTURBANCE", "SERVO_KV", "SERVO_TIMESTEP",
           "import_pointmaze", "pointmaze_names", "wall_boxes"]

#: gymnasium-robotics' PointMaze map names (its environment ids ``PointMaze_<name>-v3``)
#: -> the constant of ``gymnasium_robotics.envs.maze.maps``.
MAPS: dict[str, str] = {
    "UMaze": "U_MAZE", "Open": "OPEN", "Open_Diverse_G": "OPEN_DIVERSE_G",
    "Open_Diverse_GR": "OPEN_DIVERSE_GR", "Medium": "MEDIUM_MAZE",
    "Medium_Diverse_G": "MEDIUM_MAZE_DIVERSE_G", "Medium_Diverse_GR": "MEDIUM_MAZE_DIVERSE_GR",
    "Large": "LARGE_MAZE", "Large_Diverse_G": "LARGE_MAZE_DIVERSE_G",
    "Large_Diverse_GR": "LARGE_MAZE_DIVERSE_GR"}
#: PointMaze's ``maze_size_scaling`` and ``maze_height`` (``point_maze.py``), metres.
SCALING = 1.0
MAZE_HEIGHT = 0.4
#: Added to the ball's radius in ``[robot] radius``, metres: room for the ball's contact
#: (MuJoCo's soft contacts let it press slightly into a wall) and the sampled controller.
DEFAULT_CONTACT_MARGIN = 0.01
#: Default sampling rate of the controller, Hz (PointMaze steps its simulation at 100 Hz).
DEFAULT_RATE_HZ = 100.0
#: Default prescribed time per cell of the shortest path from start to goal, seconds.
SECONDS_PER_CELL = 2.0
#: PointMaze's ball joints (the states x, y).
JOINTS = ("ball_x", "ball_y")
#: With ``plant.model = "mujoco"``: the velocity servos that replace PointMaze's motors,
#: their gain (N s/m) and MuJoCo's timestep (s).
SERVOS = ("vel_x", "vel_y")
SERVO_KV = 200.0
SERVO_TIMESTEP = 0.001
#: The bounds declared for the ball through its servos: the servo's velocity over its
#: command is kv / (kv + damping) = 0.995 in steady state (PointMaze's joint damping 1), its
#: lag and the walls' friction are the drift and the disturbance.
SERVO_ASSUMPTIONS = {"input_gain": [0.9, 1.05], "drift_bound": 0.1}
SERVO_DISTURBANCE = 0.05
#: Half side of the initial and target boxes, in cells (a quarter cell: inside the cell
#: with the ball's radius to spare).
CELL_BOX_HALF = 0.25
_MISSING = ('gymnasium-robotics is not installed: install the optional extra with '
            'pip install ".[mujoco]"')


def pointmaze_names() -> list[str]:
    """The PointMaze map names :func:`import_pointmaze` knows, as gymnasium-robotics spells
    them (``PointMaze_<name>-v3``).

    Returns
    -------
    list of str
    """
    return list(MAPS)


def _gymnasium_robotics() -> tuple[Any, Path]:
    """gymnasium-robotics' ``maps`` module and its package folder."""
    try:
        # importing it prints a notice about its Adroit hand environments on stderr
        with contextlib.redirect_stderr(io.StringIO()):
            from gymnasium_robotics.envs.maze import maps
    except ImportError:
        raise SpecError("name", _MISSING) from None
    return maps, Path(maps.__file__).resolve().parents[2]


def _ball_radius(package: Path) -> float:
    """The radius of PointMaze's ball, ``particle_geom`` of ``assets/point/point.xml``."""
    import xml.etree.ElementTree as ET
    geom = ET.parse(package / "envs" / "assets" / "point" / "point.xml").find(
        ".//geom[@name='particle_geom']")
    return float(geom.get("size").split()[0])


def wall_boxes(maze_map: list[list[Any]]) -> list[tuple[int, int, int, int]]:
    """The wall cells merged into rectangles of cells: runs of walls along each row, a run
    merged with the same run of the rows below.

    Parameters
    ----------
    maze_map : list of list
        Rows of cells, ``1`` a wall.

    Returns
    -------
    list of (row0, row1, col0, col1)
        Inclusive cell ranges, in the order of their first row and column; together they
        are the wall cells, each once.
    """
    rows = [[c == 1 for c in row] for row in maze_map]
    runs = []
    for i, row in enumerate(rows):
        j = 0
        while j < len(row):
            if row[j]:
                k = j
                while k + 1 < len(row) and row[k + 1]:
                    k += 1
                runs.append((i, j, k))
                j = k + 1
            else:
                j += 1
    boxes: list[list[int]] = []
    open_boxes: dict[tuple[int, int], list[int]] = {}   # (col0, col1) -> box ending above
    for i, j, k in runs:
        box = open_boxes.get((j, k))
        if box is not None and box[1] == i - 1:
            box[1] = i
        else:
            box = [i, i, j, k]
            boxes.append(box)
            open_boxes[(j, k)] = box
    return [tuple(b) for b in boxes]


def _free_cells(maze_map: list[list[Any]]) -> list[tuple[int, int]]:
    return [(i, j) for i, row in enumerate(maze_map) for j, c in enumerate(row) if c != 1]


def _path_lengths(maze_map: list[list[Any]], start: tuple[int, int]) -> dict:
    """Steps from ``start`` to each free cell reachable through free cells (4-neighbours)."""
    free = set(_free_cells(maze_map))
    steps = {start: 0}
    queue = deque([start])
    while queue:
        i, j = queue.popleft()
        for cell in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)):
            if cell in free and cell not in steps:
                steps[cell] = steps[(i, j)] + 1
                queue.append(cell)
    return steps


def _cell(value: Any, name: str, maze_map: list[list[Any]]) -> tuple[int, int]:
    """A ``(row, col)`` given as a pair or ``"ROW,COL"``, checked to be a free cell."""
    try:
        if isinstance(value, str):
            row, col = (int(v) for v in value.split(","))
        else:
            row, col = (int(v) for v in value)
    except (TypeError, ValueError):
        raise SpecError(name, f"must be a cell ROW,COL (two integers), got {value!r}") from None
    if not (0 <= row < len(maze_map) and 0 <= col < len(maze_map[0])):
        raise SpecError(name, f"cell ({row}, {col}) is outside the {len(maze_map)} x "
                              f"{len(maze_map[0])} map")
    if maze_map[row][col] == 1:
        raise SpecError(name, f"cell ({row}, {col}) is a wall")
    return row, col


def _default_cells(maze_map: list[list[Any]]) -> tuple[list, list]:
    """The map's reset and goal cells as ``Maze.make_maze`` reads them: ``r`` and ``c``
    cells for the reset, ``g`` and ``c`` for the goal, every free cell where the map marks
    none."""
    marked = {m: [(i, j) for i, row in enumerate(maze_map) for j, c in enumerate(row) if c == m]
              for m in ("r", "g", "c")}
    free = _free_cells(maze_map)
    resets = marked["r"] + marked["c"] or free
    goals = marked["g"] + marked["c"] or free
    return resets, goals


def _number(value: float) -> str:
    return repr(float(round(value, 12)) + 0.0)


def _toml(doc: dict[str, Any], header: list[str]) -> str:
    """The spec document as TOML: top-level keys, then tables, then ``[[obstacles]]``."""
    def value(v: Any) -> str:
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return _number(v)
    lines = [f"# {h}" if h else "#" for h in header]
    tables = []
    for key, v in doc.items():
        if isinstance(v, dict):
            tables.append(f"\n[{key}]")
            tables += [f"{k} = {value(x)}" for k, x in v.items()]
        elif key == "obstacles":
            for entry in v:
                tables.append("\n[[obstacles]]")
                tables += [f"{k} = {value(x)}" for k, x in entry.items()]
        else:
            lines.append(f"{key} = {value(v)}")
    return "\n".join(lines + tables) + "\n"


def import_pointmaze(name: str, path: str | os.PathLike | None = None, *,
                     start: Any = None, goal: Any = None,
                     prescribed_time: float | None = None, rate_hz: float = DEFAULT_RATE_HZ,
                     contact_margin: float = DEFAULT_CONTACT_MARGIN,
                     model: str = "single-integrator",
                     mjcf: str | os.PathLike | None = None) -> dict[str, Any]:
    """A spec of one of gymnasium-robotics' PointMaze mazes: go from a start cell to a goal
    cell, the ball clear of the walls.

    Parameters
    ----------
    name : str
        The map, as gymnasium-robotics spells it (:func:`pointmaze_names`: ``"UMaze"``,
        ``"Medium"``, ``"Large_Diverse_G"``...).
    path : path, optional
        Write the spec there as TOML (atomically; nothing is written on an error).
    start, goal : (int, int) or str, optional
        The cells ``(row, col)`` (or ``"ROW,COL"``) of the initial state and of the
        target, counted from the map's top-left. Default: the start is the map's first
        reset cell (``r``, else ``c``, else free) in reading order; the goal is, among its
        goal cells (``g`` or ``c``, else the free cells), the one farthest from the start
        along the maze (the first in reading order on a tie).
    prescribed_time : float, optional
        ``t_c``, seconds; default :data:`SECONDS_PER_CELL` per step of the shortest path
        between the cells (at least two steps' worth).
    rate_hz : float
        The controller's rate, Hz (default :data:`DEFAULT_RATE_HZ`).
    contact_margin : float
        Added to the ball's radius in ``[robot] radius``, metres (default
        :data:`DEFAULT_CONTACT_MARGIN`).
    model : str
        ``plant.model`` (default ``"single-integrator"``, the first-order point). With
        ``"mujoco"`` the spec's plant is the written MJCF (``mjcf`` required): the ball
        through velocity servos, with the bounds :data:`SERVO_ASSUMPTIONS` declared.
    mjcf : path, optional
        Also write the maze's MuJoCo model there, built by gymnasium-robotics'
        ``Maze.make_maze`` with the PointMaze ball; the spec's header names it relative to
        ``path``.

    Returns
    -------
    dict
        The spec document (:meth:`stt_codegen.Spec.from_dict` takes it), state units
        metres, in MuJoCo's world frame.

    Raises
    ------
    SpecError
        gymnasium-robotics not installed, an unknown map (the message lists the names), a
        bad or walled ``start``/``goal``, cells not connected, a value the spec refuses,
        or an output folder that does not exist (the field names the argument).

    Examples
    --------
    The bundled case ``pointmaze-umaze`` is the spec this function writes for ``"UMaze"``
    (with the ``mujoco`` extra installed: ``stt.import_pointmaze("UMaze", "umaze.toml")``).
    The map's name is checked first:

    >>> import stt_codegen as stt
    >>> stt.load_spec("pointmaze-umaze").dimension
    2
    >>> try:
    ...     stt.import_pointmaze("NoSuchMaze")
    ... except stt.SpecError as error:
    ...     print(error.field)
    name
    """
    from .spec.loader import Spec
    if name not in MAPS:
        raise SpecError("name", f"no PointMaze map named {name!r} (maps: "
                                f"{', '.join(MAPS)})")
    maps, package = _gymnasium_robotics()
    maze_map = getattr(maps, MAPS[name])
    resets, goals = _default_cells(maze_map)
    first = _cell(start, "start", maze_map) if start is not None else resets[0]
    steps = _path_lengths(maze_map, first)
    if goal is not None:
        last = _cell(goal, "goal", maze_map)
    else:
        reachable = [c for c in goals if c in steps and c != first]
        if not reachable:
            raise SpecError("goal", f"no goal cell of {name} is reachable from the start "
                                    f"{first}")
        last = max(reachable, key=lambda c: steps[c])
    if last == first:
        raise SpecError("goal", f"the goal cell {last} is the start cell")
    if last not in steps:
        raise SpecError("goal", f"cell {last} is not reachable from the start cell {first}")
    if prescribed_time is None:
        prescribed_time = SECONDS_PER_CELL * max(steps[last], 2)
    s, rows, cols = SCALING, len(maze_map), len(maze_map[0])
    x0, y0 = cols * s / 2, rows * s / 2

    def centre(cell: tuple[int, int]) -> tuple[float, float]:
        return (cell[1] + 0.5) * s - x0, y0 - (cell[0] + 0.5) * s

    def cell_box(cell: tuple[int, int]) -> dict[str, list[float]]:
        cx, cy = centre(cell)
        h = CELL_BOX_HALF * s
        return {"lower": [cx - h, cy - h], "upper": [cx + h, cy + h]}

    radius = _ball_radius(package) + contact_margin
    doc: dict[str, Any] = {
        "name": f"pointmaze-{name.lower().replace('_', '-')}",
        "prescribed_time": float(prescribed_time),
        "state_space": {"lower": [-x0, -y0], "upper": [x0, y0]},
        "initial": {**cell_box(first), "state": list(centre(first))},
        "target": cell_box(last),
        "obstacles": [{"lower": [j0 * s - x0, y0 - (i1 + 1) * s],
                       "upper": [(j1 + 1) * s - x0, y0 - i0 * s]}
                      for i0, i1, j0, j1 in wall_boxes(maze_map)],
        "robot": {"radius": radius},
        "controller": {"rate_hz": float(rate_hz)},
        "plant": {"model": model},
    }
    if path is None and mjcf is not None:
        raise SpecError("mjcf", "needs the spec's path too (the spec names the model "
                                "relative to itself)")
    on_mujoco = plant_entry(model).declared_bounds     # model = "mujoco": the MJCF is the plant
    if on_mujoco:
        if model in SECOND_ORDER_PLANTS:
            raise SpecError("model", f"{model!r} is not written by the importer: it drives the "
                                     "ball through velocity servos (model = \"mujoco\"); for "
                                     "PointMaze's force motors write the second-order spec "
                                     "by hand (docs/mujoco.md)")
        if mjcf is None:
            raise SpecError("mjcf", f"plant.model = {model!r} simulates the maze's MuJoCo "
                                    "model: give the file to write it to (--mjcf)")
        rel = os.path.relpath(Path(mjcf).resolve(), Path(path).resolve().parent)
        doc["plant"] = {"model": model, "mjcf": Path(rel).as_posix(),
                        "joints": list(JOINTS), "actuators": list(SERVOS),
                        "disturbance_amplitude": SERVO_DISTURBANCE}
        doc["assumptions"] = dict(SERVO_ASSUMPTIONS)
    Spec.from_dict(doc)                 # refuse what the loader refuses, before writing
    if path is not None:
        header = [f"gymnasium-robotics PointMaze {name!r} (PointMaze_{name}-v3), imported by "
                  "stt-codegen:",
                  f"start cell {first}, goal cell {last} (row, col from the map's top-left); "
                  f"cell side {s:g} m;",
                  f"walls merged into {len(doc['obstacles'])} boxes; robot radius = ball "
                  f"{radius - contact_margin:g} m + contact margin {contact_margin:g} m."]
        if mjcf is not None:
            rel = os.path.relpath(Path(mjcf).resolve(), Path(path).resolve().parent)
            header.append(f"MuJoCo model (gymnasium-robotics' Maze.make_maze): "
                          f"{Path(rel).as_posix()} (relative to this file)")
        text = _toml(doc, header)
        for field, target in (("path", path), ("mjcf", mjcf)):   # both, before writing
            if target is not None and not Path(target).resolve().parent.is_dir():
                raise SpecError(field, f"folder {str(Path(target).parent)!r} does not exist")
        if mjcf is not None:
            _write_mjcf(maze_map, package, mjcf, servos=on_mujoco)
        atomic_write(path, text.encode(), field="path")
    return doc


def _write_mjcf(maze_map: list[list[Any]], package: Path, mjcf: str | os.PathLike,
                servos: bool = False) -> None:
    """The maze's MJCF from gymnasium-robotics' ``Maze.make_maze`` (PointMaze's ball,
    scaling and height), copied out of its temporary file; with ``servos``, PointMaze's
    force motors replaced by velocity servos (:data:`SERVOS`, gain :data:`SERVO_KV`) at a
    :data:`SERVO_TIMESTEP` timestep, for the first-order law (``plant.model = "mujoco"``)."""
    from gymnasium_robotics.envs.maze.maze_v4 import Maze
    agent = package / "envs" / "assets" / "point" / "point.xml"
    _, temporary = Maze.make_maze(str(agent), maze_map, SCALING, MAZE_HEIGHT)
    try:
        if servos:
            tree = ElementTree.parse(temporary)
            tree.getroot().find("option").set("timestep", repr(SERVO_TIMESTEP))
            actuators = tree.getroot().find("actuator")
            for child in list(actuators):
                actuators.remove(child)
            for name, joint in zip(SERVOS, JOINTS):
                ElementTree.SubElement(actuators, "velocity",
                                       {"name": name, "joint": joint, "kv": repr(SERVO_KV)})
            tree.write(temporary, encoding="unicode")
        atomic_write(mjcf, lambda target: shutil.copyfile(temporary, target), field="mjcf")
    finally:
        Path(temporary).unlink(missing_ok=True)
