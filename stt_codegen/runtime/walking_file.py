"""Obstacles a closed loop senses at run time, read from a TOML file.

``stt-codegen simulate SPEC --sensed FILE`` runs a spec with ``[sensing]`` among the
obstacles ``FILE`` lists (docs/sensing.md, "The closed loop"): one
``[[walking_obstacles]]`` table per obstacle, the fields of
:class:`~.sensed.WalkingObstacle`::

    [[walking_obstacles]]            # a person walking straight
    start = [5.0, 0.5]               # centre at t = 0, on the spec's [sensing] dims
    radius = 0.3
    velocity = [0.0, 0.5]

    [[walking_obstacles]]            # another along a path of rows [t, centre...]
    start = [7.0, 5.5]
    radius = 0.35
    path = [[2.0, 7.0, 5.5], [10.0, 7.0, 0.5]]

    [[walking_obstacles]]            # an adversary heading for the robot
    start = [8.0, 3.0]
    radius = 0.3
    pursuit_speed = 0.8
    pursuit_acceleration = 1.0       # optional

Nothing in the file is known to the design: the controller sees each obstacle only once
it is within the envelope's range, after its latency.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import SpecError
from ..spec.loader import toml_document
from .sensed import WalkingObstacle

__all__ = ["MAX_WALKING_OBSTACLES", "WALKING_KEYS", "load_walking_obstacles",
           "walking_obstacles"]

#: The table of the file: one entry per obstacle.
TABLE = "walking_obstacles"
#: The keys of an entry (:class:`~.sensed.WalkingObstacle`'s fields).
WALKING_KEYS = ("start", "radius", "velocity", "path", "pursuit_speed",
                "pursuit_acceleration")
#: The most obstacles a file may list.
MAX_WALKING_OBSTACLES = 4096


def load_walking_obstacles(path: str | os.PathLike) -> tuple[WalkingObstacle, ...]:
    """The obstacles a TOML file lists for a closed loop with ``[sensing]``.

    Parameters
    ----------
    path : str or path
        A TOML file of ``[[walking_obstacles]]`` tables (this module's docstring), each
        with ``start`` and ``radius`` (state units) and at most one of ``velocity``
        (state units per second), ``path`` (rows ``[t, centre...]``, seconds and state
        units) and ``pursuit_speed`` (state units per second, with an optional
        ``pursuit_acceleration``, per second squared).

    Returns
    -------
    tuple of WalkingObstacle
        In the file's order; empty for a file with no entry.

    Raises
    ------
    SpecError
        The file cannot be read or is not TOML (field ``sensed``); an unknown key, a
        missing ``start`` or ``radius``, a value of the wrong type or one
        :class:`~.sensed.WalkingObstacle` refuses (field ``walking_obstacles[i].<key>``).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from stt_codegen.runtime.walking_file import load_walking_obstacles
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "people.toml").write_text(
    ...     "[[walking_obstacles]]\\nstart = [5.0, 0.5]\\nradius = 0.3\\n"
    ...     "velocity = [0.0, 0.5]\\n")
    >>> load_walking_obstacles(folder / "people.toml")[0].velocity
    (0.0, 0.5)
    """
    name = os.fspath(path)
    try:
        raw = Path(name).read_bytes()
    except FileNotFoundError:
        raise SpecError("sensed", f"no file named {name!r}") from None
    except OSError as exc:
        raise SpecError("sensed", f"cannot read {name!r}: {exc.strerror or exc}") from None
    try:
        document = toml_document(raw)
    except SpecError as exc:
        raise SpecError("sensed", f"{name!r}: {exc.reason}") from None
    return walking_obstacles(document)


def walking_obstacles(document: Mapping[str, Any]) -> tuple[WalkingObstacle, ...]:
    """The obstacles of a document as :func:`load_walking_obstacles` reads it.

    Parameters
    ----------
    document : mapping
        ``{"walking_obstacles": [{"start": [...], "radius": ..., ...}, ...]}``, as
        :mod:`tomllib` reads the file.

    Returns
    -------
    tuple of WalkingObstacle

    Raises
    ------
    SpecError
        As :func:`load_walking_obstacles`, for the entries.

    Examples
    --------
    >>> from stt_codegen.runtime.walking_file import walking_obstacles
    >>> doc = {"walking_obstacles": [{"start": [8.0, 3.0], "radius": 0.3,
    ...                               "pursuit_speed": 0.8}]}
    >>> walking_obstacles(doc)[0].pursuit_speed
    0.8
    """
    unknown = sorted(set(document) - {TABLE})
    if unknown:
        raise SpecError(unknown[0], f"unknown key (the file lists [[{TABLE}]] tables only)")
    entries = document.get(TABLE, [])
    if not isinstance(entries, list) or not all(isinstance(e, Mapping) for e in entries):
        raise SpecError(TABLE, f"must be an array of tables ([[{TABLE}]])")
    if len(entries) > MAX_WALKING_OBSTACLES:
        raise SpecError(TABLE, f"at most {MAX_WALKING_OBSTACLES} obstacles, got "
                               f"{len(entries)}")
    return tuple(_obstacle(entry, f"{TABLE}[{i}]") for i, entry in enumerate(entries))


def _obstacle(entry: Mapping[str, Any], field: str) -> WalkingObstacle:
    """One entry, each value's type checked before :class:`WalkingObstacle` checks the
    rest; its errors named by the entry."""
    extra = sorted(set(entry) - set(WALKING_KEYS))
    if extra:
        raise SpecError(f"{field}.{extra[0]}", f"unknown key (an obstacle has "
                                               f"{', '.join(WALKING_KEYS)})")
    for key in ("start", "radius"):
        if key not in entry:
            raise SpecError(f"{field}.{key}", "missing (every obstacle has a start and a "
                                              "radius)")
    values: dict[str, Any] = {"start": _numbers(entry["start"], f"{field}.start"),
                              "radius": _number(entry["radius"], f"{field}.radius")}
    if "velocity" in entry:
        values["velocity"] = _numbers(entry["velocity"], f"{field}.velocity")
    if "path" in entry:
        rows = entry["path"]
        if not isinstance(rows, list) or not rows:
            raise SpecError(f"{field}.path", "must be a non-empty array of rows "
                                             "[t, centre...]")
        values["path"] = tuple(_numbers(row, f"{field}.path[{k}]")
                               for k, row in enumerate(rows))
    for key in ("pursuit_speed", "pursuit_acceleration"):
        if key in entry:
            values[key] = _number(entry[key], f"{field}.{key}")
    try:
        return WalkingObstacle(**values)
    except SpecError as exc:
        raise SpecError(exc.field.replace("WalkingObstacle", field, 1), exc.reason) from None


def _number(value: Any, field: str) -> float:
    """A finite number (not a boolean)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value):
        raise SpecError(field, f"must be a finite number, got {value!r}")
    return float(value)


def _numbers(value: Any, field: str) -> tuple[float, ...]:
    """A non-empty array of finite numbers."""
    if not isinstance(value, Sequence) or isinstance(value, str) or not value:
        raise SpecError(field, f"must be a non-empty array of numbers, got {value!r}")
    return tuple(_number(v, f"{field}[{k}]") for k, v in enumerate(value))
