"""A fleet spec: several robots sharing one state space and its obstacles (docs/fleets.md).

A fleet file has a shared ``name``, ``[state_space]`` and ``[[obstacles]]``, and one
``[[robots]]`` entry per robot: its ``name``, ``radius`` (and optional ``dims``), and the
tables a single spec has for one robot (``prescribed_time``, ``[initial]``, ``[target]``,
``[tube]``, ``[plant]``, ``[controller]``, ``[assumptions]``, ``[actuator]``,
``[[tasks]]``, ``[task_order]``). Each robot becomes one single spec
(:meth:`~.loader.Spec.from_dict`, the one validation path): the shared tables, the robot's
own, and ``[robot] radius``; the single spec's errors come back with the robot's field
(``robots[2].target.lower: ...``).

This module is plain Python; it reads TOML with :mod:`tomllib`.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from ..cases import bundled_fleet_bytes, bundled_fleets
from ..errors import SpecError
from .loader import Spec, file_or_bundled, toml_document
from .mujoco import with_folder

__all__ = ["FleetRobot", "FleetSpec", "fleet_json_schema", "is_fleet", "load_fleet",
           "parse_fleet"]

#: The top-level keys of a fleet file.
FLEET_KEYS = ("name", "state_space", "obstacles", "robots")
#: The keys of a ``[[robots]]`` entry that are the fleet's, not the single spec's.
ROBOT_KEYS = ("name", "radius", "dims")
#: The single spec's tables a robot entry may give (the rest are the fleet's).
ROBOT_TABLES = ("prescribed_time", "initial", "target", "tube", "plant", "controller",
                "assumptions", "actuator", "tasks", "task_order")
#: The most robots a fleet may have.
MAX_ROBOTS = 1024


@dataclass(frozen=True)
class FleetRobot:
    """One robot of a fleet.

    Attributes
    ----------
    index : int
        Its position in ``[[robots]]`` (as in messages: ``robots[2]``).
    name : str
        Its name, unique in the fleet (an identifier: it names its generated folder).
    radius : float
        Its body's radius around its reference point as given (``robots[i].radius``), state
        units; ``spec.robot.radius`` adds a differential drive's axle offset.
    spec : Spec
        Its single spec: the fleet's state space and obstacles, its own tables, its radius.
    """

    index: int
    name: str
    radius: float
    spec: Spec

    @property
    def reach(self) -> float:
        """The radius of the disc around the reference point that holds the body (the
        radius plus a differential drive's axle offset), state units."""
        return self.spec.robot.radius

    @property
    def dims(self) -> tuple[int, ...]:
        """The state dimensions its body extends in (the planar position by default)."""
        return self.spec.robot.dims


@dataclass(frozen=True)
class FleetSpec:
    """A validated fleet: robots that share a state space and its obstacles.

    Attributes
    ----------
    name : str
        The fleet's name.
    robots : tuple of FleetRobot
        In the file's order.
    source_hash : str
        SHA-256 of the fleet file's bytes (of the canonical JSON for a dict).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.load_fleet("warehouse-fleet")
    >>> len(fleet.robots), fleet.robots[0].spec.plant_model
    (8, 'single-integrator')
    """

    name: str
    robots: tuple[FleetRobot, ...]
    source_hash: str = ""

    def robot(self, name: str) -> FleetRobot:
        """The robot named ``name`` (``KeyError`` if none)."""
        for r in self.robots:
            if r.name == name:
                return r
        raise KeyError(name)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "FleetSpec":
        """Validate a fleet given as a dictionary, the same document as a fleet file.

        Parameters
        ----------
        data : mapping
            ``{"name", "state_space", "obstacles", "robots": [{"name", "radius", ...}]}``
            as :mod:`tomllib` reads a fleet file (docs/fleets.md).

        Returns
        -------
        FleetSpec

        Raises
        ------
        SpecError
            The field (``robots[2].target.lower``) and the reason.

        Examples
        --------
        >>> import stt_codegen as stt
        >>> robot = {"prescribed_time": 5.0, "radius": 0.1,
        ...          "initial": {"lower": [0.2, 0.2], "upper": [0.7, 0.7]},
        ...          "target": {"lower": [3.3, 0.2], "upper": [3.8, 0.7]}}
        >>> doc = {"name": "two", "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 2.0]},
        ...        "robots": [{**robot, "name": "a"},
        ...                   {**robot, "name": "b", "initial": {"lower": [3.3, 1.3],
        ...                                                      "upper": [3.8, 1.8]}}]}
        >>> [r.name for r in stt.FleetSpec.from_dict(doc).robots]
        ['a', 'b']
        >>> doc["robots"][1]["target"] = {"lower": [3.5, 1.0], "upper": [3.0, 1.5]}
        >>> stt.FleetSpec.from_dict(doc)
        Traceback (most recent call last):
        ...
        stt_codegen.errors.SpecError: robots[1].target.lower: lower[0] = 3.5 exceeds upper[0] = 3.0
        """
        if not isinstance(data, Mapping):
            raise SpecError("", "a fleet is a table (dict)")
        canonical = json.dumps(data, sort_keys=True, default=repr).encode()
        return _validate(data, hashlib.sha256(canonical).hexdigest(), None)


def is_fleet(data: Mapping[str, Any]) -> bool:
    """Whether a spec document (a TOML file's tables) is a fleet: it has ``robots``.

    Parameters
    ----------
    data : mapping
        The document as :mod:`tomllib` reads it.

    Returns
    -------
    bool
    """
    return isinstance(data, Mapping) and "robots" in data


def parse_fleet(data: bytes | str, folder: Path | None = None) -> FleetSpec:
    """Validate the text of a fleet file (docs/fleets.md).

    Parameters
    ----------
    data : bytes or str
        The TOML text (``bytes`` must be UTF-8).
    folder : pathlib.Path, optional
        The file's folder (files a robot's spec names are found there).

    Returns
    -------
    FleetSpec

    Raises
    ------
    SpecError
        Not UTF-8, not TOML or nested too deeply (field ``""``), or a field that fails
        validation.
    """
    raw = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    return _validate(toml_document(raw), hashlib.sha256(raw).hexdigest(), folder)


def load_fleet(fleet: str | os.PathLike) -> FleetSpec:
    """Load and validate a fleet, by bundled name or by file path.

    Parameters
    ----------
    fleet : str or path
        A bundled case name (``"warehouse-fleet"``) or a fleet TOML file.

    Returns
    -------
    FleetSpec

    Raises
    ------
    SpecError
        The file cannot be read, is not a fleet (no ``[[robots]]``), or a field fails
        validation (``robots[i].<field>`` for a robot's).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> [r.name for r in stt.load_fleet("warehouse-fleet").robots][:3]
    ['amr1', 'amr2', 'amr3']
    """
    data, folder = file_or_bundled(os.fspath(fleet), bundled_fleets(), bundled_fleet_bytes,
                                   "fleet")
    return parse_fleet(data, folder)


def _validate(doc: Mapping[str, Any], digest: str, folder: Path | None) -> FleetSpec:
    """The fleet of a document: each robot's single spec, errors named by robot."""
    unknown = sorted(set(doc) - set(FLEET_KEYS))
    if unknown:
        raise SpecError(unknown[0], "unknown key of a fleet (a fleet has name, state_space, "
                                    "obstacles and [[robots]]; a robot's own tables go in "
                                    "its [[robots]] entry)")
    for key in ("name", "state_space", "robots"):
        if key not in doc:
            raise SpecError(key, "missing (a fleet has name, [state_space] and [[robots]])")
    robots = doc["robots"]
    if not isinstance(robots, list) or not robots:
        raise SpecError("robots", "must be a non-empty array of tables ([[robots]])")
    if len(robots) > MAX_ROBOTS:
        raise SpecError("robots", f"at most {MAX_ROBOTS} robots, got {len(robots)}")
    out, names = [], {}
    for i, entry in enumerate(robots):
        field = f"robots[{i}]"
        if not isinstance(entry, Mapping):
            raise SpecError(field, "must be a table")
        for key in ("name", "radius"):
            if key not in entry:
                raise SpecError(f"{field}.{key}", "missing (every robot has a name and a "
                                                  "radius)")
        extra = sorted(set(entry) - set(ROBOT_KEYS) - set(ROBOT_TABLES) - {"state_space"})
        if extra:
            raise SpecError(f"{field}.{extra[0]}",
                            "unknown key of a robot" + (" (the fleet's obstacles are shared: "
                                                        "give them at the top)"
                                                        if extra[0] == "obstacles" else ""))
        spec = _robot_spec(doc, entry, field)
        if folder is not None:
            spec = with_folder(spec, folder)
        if spec.name in names:
            raise SpecError(f"{field}.name", f"{spec.name!r} is robots[{names[spec.name]}]'s "
                                             "name too (names are unique: they name the "
                                             "generated folders)")
        names[spec.name] = i
        out.append(FleetRobot(i, spec.name, float(entry["radius"]), spec))
    dims = {r.dims for r in out}
    if len(dims) > 1:
        raise SpecError("robots", "every robot's body must extend in the same state "
                                  f"dimensions (dims), got {sorted(dims)}")
    return FleetSpec(str(doc["name"]), tuple(out), digest)


def _robot_spec(doc: Mapping[str, Any], entry: Mapping[str, Any], field: str) -> Spec:
    """The single spec of one ``[[robots]]`` entry, its errors prefixed by ``field``."""
    state_space = entry.get("state_space", {})
    if not isinstance(state_space, Mapping):
        raise SpecError(f"{field}.state_space", "must be a table")
    shared = sorted(set(state_space) & {"lower", "upper"})
    if shared:
        raise SpecError(f"{field}.state_space.{shared[0]}",
                        "the state space is the fleet's: give lower and upper once, in the "
                        "top-level [state_space] (a robot's own state_space takes only the "
                        "keys of its plant, such as velocity_bound)")
    single = {k: v for k, v in entry.items() if k in ROBOT_TABLES}
    single["name"] = entry["name"]
    base = doc["state_space"]
    single["state_space"] = ({**base, **state_space} if isinstance(base, Mapping) else base)
    single["obstacles"] = doc.get("obstacles", [])
    single["robot"] = {"radius": entry["radius"],
                       **({"dims": entry["dims"]} if "dims" in entry else {})}
    try:
        return Spec.from_dict(single)
    except SpecError as exc:
        raise SpecError(_robot_field(exc.field, field), exc.reason) from None


def _robot_field(name: str, field: str) -> str:
    """A single spec's field as the fleet file names it."""
    if name.startswith(("state_space.lower", "state_space.upper", "obstacles")) \
            or name in ("state_space", "obstacles"):
        return f"{name} (robot {field})"
    if name.startswith("robot."):
        return f"{field}.{name[len('robot.'):]}"
    return f"{field}.{name}" if name else field



def fleet_json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 7) of a fleet file, built from the single spec's.

    The shared ``name``, ``state_space`` and ``obstacles`` are the single spec's; a
    ``[[robots]]`` entry has ``name``, ``radius`` and ``dims`` (``[robot]``'s) and the
    single spec's tables of :data:`ROBOT_TABLES`, its ``state_space`` only the keys other
    than ``lower`` and ``upper``. The rules between fields are the loader's, per robot.

    Returns
    -------
    dict
        The schema, with the single spec's ``$defs``.

    Examples
    --------
    >>> from stt_codegen.spec.fleet import fleet_json_schema
    >>> schema = fleet_json_schema()
    >>> sorted(schema["properties"]), schema["required"]
    (['name', 'obstacles', 'robots', 'state_space'], ['name', 'state_space', 'robots'])
    """
    from .schema import json_schema
    single = json_schema()
    props = single["properties"]
    robot_table = single["$defs"]["RobotTable"]["properties"]
    space = dict(single["$defs"]["StateSpaceTable"])
    space_props = {k: v for k, v in space["properties"].items() if k not in ("lower", "upper")}
    robot = {
        "type": "object", "additionalProperties": False,
        "description": "one robot: its name, radius, and a single spec's tables for it "
                       "(docs/fleets.md)",
        "properties": {
            "name": props["name"], "radius": robot_table["radius"], "dims": robot_table["dims"],
            "state_space": {"type": "object", "additionalProperties": False,
                            "properties": space_props,
                            "description": "the keys of the robot's plant only (the box "
                                           "is the fleet's)"},
            **{k: props[k] for k in ROBOT_TABLES}},
        "required": ["name", "radius", "prescribed_time", "initial", "target"]}
    return {
        "$schema": single["$schema"], "$defs": single["$defs"], "type": "object",
        "title": "stt-codegen fleet", "additionalProperties": False,
        "description": "robots sharing a state space and its obstacles (docs/fleets.md)",
        "properties": {
            "name": props["name"], "state_space": props["state_space"],
            "obstacles": props["obstacles"],
            "robots": {"type": "array", "items": robot, "minItems": 1,
                       "maxItems": MAX_ROBOTS, "description": "the robots, one table each"}},
        "required": ["name", "state_space", "robots"]}
