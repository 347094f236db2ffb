"""The spec file's schema, with pydantic v2: types, known keys, finite numbers.

:class:`SpecDocument` describes the TOML document (docs/spec-format.md) as it is
written: every table and key, its type, its sign, its default. Validation is strict (no
coercion: ``"9"`` is not a number, ``true`` is not a number), extra keys are forbidden, and
numbers must be finite and at most 1e12 in magnitude. :func:`check_document` turns the
first violation into a :class:`~stt_codegen.errors.SpecError` naming the field, in the
loader's words (``prescribed_time: must be positive, got -1``). The rules that relate
fields to each other (lengths equal to the state dimension, sets inside the state space,
``x(0)`` in the interior of ``X_0``, obstacles missing the start and the target) are the
loader's (:mod:`stt_codegen.spec.loader`).

:func:`json_schema` is the JSON Schema of the document (``stt-codegen schema``): editors
with a TOML language server validate and complete spec files with it.
"""

from __future__ import annotations

import difflib
import re
from typing import Annotated, Any, Literal

from pydantic import (AllowInfNan, BaseModel, ConfigDict, Discriminator, Field, Strict, Tag,
                      ValidationError)

from ..errors import SpecError
from .plants import ALL_PLANT_MODELS, PLANTS, SECOND_ORDER_PLANTS

__all__ = ["ActuatorTable", "AssumptionsTable", "BallObstacle", "BoxObstacle", "BoxTable", "ControllerTable",
           "NAME_REGEX", "PlantTable", "PolytopeObstacle", "RobotTable", "SensingTable",
           "check_document",
           "json_schema", "value_kind"]

#: Largest magnitude of any number in a spec.
MAX_MAGNITUDE = 1e12
#: Default covering tolerance of balls and polytopes (Remark 3.1), state units.
DEFAULT_TOLERANCE = 0.05
#: A spec name: a C identifier once ``-`` becomes ``_``, at most 64 characters.
NAME_REGEX = r"^[A-Za-z][A-Za-z0-9_-]{0,63}$"
#: Largest state dimension (the generated code unrolls per dimension).
MAX_DIMENSION = 64
#: At most this many ``[[obstacles]]`` entries.
MAX_OBSTACLES = 4096
#: ``tube.method``: the paper's single reach tube, via-point reach tubes, or paper first.
TUBE_METHODS = ("paper", "via", "auto")
#: At most this many vertices per polytope.
MAX_VERTICES = 1024
#: ``[[tasks]]`` kinds (docs/tasks.md).
TASK_KINDS = ("reach", "stay")
#: ``[task_order] order`` values (docs/tasks.md).
TASK_ORDERS = ("listed", "any")
#: At most this many ``[[tasks]]`` entries, and boxes in one ``any_of``.
MAX_TASKS = 32
MAX_ALTERNATIVES = 8
#: At most this many rows in a moving obstacle's ``path``.
MAX_PATH_ROWS = 1024
#: The keys that make an obstacle move (box obstacles only: spec/motion.py).
MOTION_KEYS = ("active", "velocity", "path")

# strict: an integer is a number, a boolean or a string is not; no NaN, no infinity
Number = Annotated[float, Strict(), AllowInfNan(False), Field(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
Positive = Annotated[float, Strict(), AllowInfNan(False), Field(gt=0, le=MAX_MAGNITUDE)]
NonNegative = Annotated[float, Strict(), AllowInfNan(False), Field(ge=0, le=MAX_MAGNITUDE)]
Vector = Annotated[list[Number], Field(min_length=1, max_length=MAX_DIMENSION)]
Index = Annotated[int, Strict(), Field(ge=0)]
Matrix = Annotated[list[Vector], Field(min_length=1)]


def _omitted(description: str) -> Any:
    """A key that may be left out (the loader then derives its value), but not null: TOML
    has no null, and the JSON Schema shows no default."""
    return Field(None, description=description,
                 json_schema_extra=lambda schema: schema.pop("default", None))


class _Table(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


class BoxTable(_Table):
    """A box ``prod_i [lower_i, upper_i]``, one entry per state dimension."""

    lower: Vector = Field(description="lower corner, state units")
    upper: Vector = Field(description="upper corner, state units; upper >= lower")


class StateSpaceTable(BoxTable):
    """The state space ``X`` (positions, for a second-order plant)."""

    velocity_bound: Annotated[list[Positive], Field(min_length=1, max_length=MAX_DIMENSION)] \
        = _omitted("second-order models only: bound on |x2_i| the run must keep, one per "
                   "position; default none")


class InitialTable(BoxTable):
    """The initial set ``X_0`` (a box inside ``X``) and the initial state ``x(0)``."""

    state: Vector = _omitted("x(0), in the interior of X_0; default its centre")
    half_width: Vector = _omitted("d_0 of eq. (2), positive; default 0.8 x the room around "
                                  "x(0) in X_0")
    velocity: Vector = _omitted("second-order models only: the initial velocity x2(0), one "
                                "per position; default 0")
    heading: Number = _omitted("differential-drive only: the heading theta(0), rad, in "
                               "[-pi, pi]; default 0 (state and the box are the look-ahead "
                               "point's)")


class TargetTable(BoxTable):
    """The target set ``T`` (a box inside ``X``), or several (``any_of``)."""

    lower: Vector = _omitted("lower corner, state units (or any_of)")
    upper: Vector = _omitted("upper corner, state units; upper >= lower")
    any_of: Annotated[list["TaskBoxTable"], Field(min_length=1,
                                                  max_length=MAX_ALTERNATIVES)] = _omitted(
        "target boxes of which the tube ends in one (instead of lower/upper); the design "
        "picks the first that it certifies, in this order, and drops one that meets an "
        "obstacle")
    center: Vector = _omitted("eta of eq. (3), in the interior of T; default its centre")
    half_width: Vector = _omitted("d_T of eq. (3), positive; default 0.8 x the room around "
                                  "eta in T")


class BoxObstacle(_Table):
    """A box obstacle; given on the dimensions ``dims`` (default the first ones)."""

    lower: Vector = Field(description="lower corner on dims, state units")
    upper: Vector = Field(description="upper corner on dims, state units; upper >= lower")
    dims: list[Index] = _omitted("state dimensions of lower/upper (default the first ones); "
                                 "the box spans the others")
    # moving obstacles (docs/moving-obstacles.md; cross-field rules: spec/motion.py)
    active: Annotated[list[NonNegative], Field(min_length=2, max_length=2)] = _omitted(
        "[t_on, t_off], seconds, t_on < t_off: when the obstacle exists; default always")
    active_until: Annotated[str, Strict(), Field(pattern=r"^T[1-9][0-9]*$")] = _omitted(
        "a reach task's label (\"T1\"...): the obstacle exists from 0 until that task is "
        "met; the design keeps clear of it until the task's window ends (instead of active)")
    velocity: Vector = _omitted("state units/s on dims: the box translates from lower/upper "
                                "at t_on; without active, from 0 until it has left the "
                                "state space")
    path: Annotated[list[Vector], Field(min_length=1, max_length=MAX_PATH_ROWS)] = _omitted(
        "rows [t, centre...] (t in s, increasing), piecewise linear, held before the first "
        "and after the last row; lower/upper give the size and the box at the first row")


class BallObstacle(_Table):
    """A ball obstacle, covered by boxes (Remark 3.1)."""

    center: Vector = Field(description="centre on dims, state units")
    radius: Positive = Field(description="radius, state units")
    dims: list[Index] = _omitted("state dimensions of the coordinates (default the first "
                                 "ones)")
    tolerance: Positive = Field(DEFAULT_TOLERANCE, description="largest distance from the "
                                                               "covering boxes to the ball, "
                                                               "state units")


class PolytopeObstacle(_Table):
    """A convex polytope obstacle given by its vertices, covered by boxes (Remark 3.1)."""

    vertices: Annotated[list[Vector], Field(min_length=1, max_length=MAX_VERTICES)] = Field(
        description="the vertices on dims, state units; the obstacle is their convex hull")
    dims: list[Index] = _omitted("state dimensions of the coordinates (default the first "
                                 "ones)")
    tolerance: Positive = Field(DEFAULT_TOLERANCE, description="largest distance from the "
                                                               "covering boxes to the "
                                                               "polytope, state units")


def _obstacle_kind(value: Any) -> str | None:
    """The loader's rule: ``vertices`` makes a polytope, ``center`` or ``radius`` a ball."""
    if not isinstance(value, dict):
        return None
    if "vertices" in value:
        return "polytope"
    return "ball" if "center" in value or "radius" in value else "box"


Obstacle = Annotated[Annotated[BoxObstacle, Tag("box")] | Annotated[BallObstacle, Tag("ball")]
                     | Annotated[PolytopeObstacle, Tag("polytope")],
                     Discriminator(_obstacle_kind)]


class TubeTable(_Table):
    """Tube shaping, section III of the paper."""

    delta_b: Positive = Field(0.2, description="delta_B of eqs. (7)-(8): clearance kept "
                                               "from each obstacle, state units")
    circumvent_sharpness: Positive = _omitted("k^j of eqs. (7)-(8), the same for every "
                                              "obstacle; default chosen per circumvent by "
                                              "the design")
    theta0: Positive = Field(0.01, description="theta_0 of eq. (11)")
    kappa: Positive = Field(5.0, description="kappa of eq. (11)")
    mu: Positive = Field(1.0, description="mu of eq. (11), state units")
    smoothness: Positive = Field(50.0, description="nu of the smooth max/min of eqs. "
                                                   "(9)-(10), 1/state units")
    method: Literal[TUBE_METHODS] = Field("auto",  # type: ignore[valid-type]
                                          description="paper: one reach tube, eq. (4); via: "
                                                      "through via boxes; auto: paper first")


class ControllerTable(_Table):
    """The deployed controller, law (13)."""

    gain: Positive = _omitted("k of law (13); default derived from the designed tube")
    rate_hz: Positive = Field(1000.0, description="sampling rate, Hz")
    delay: NonNegative = Field(0.0, description="computation delay, s: the command computed "
                                                "from the state read at t_k is applied from "
                                                "t_k + delay on (delay + 2 jitter <= 1 / "
                                                "rate_hz)")
    jitter: NonNegative = Field(0.0, description="sampling jitter, s: the state is read at "
                                                 "t_k within jitter of k / rate_hz")
    compensate_delay: bool = Field(False, description="predict the state at t_k + delay from "
                                                      "the held command before law (13): a "
                                                      "delay up to one period (jitter 0)")


class PlantTable(_Table):
    """The plant used in simulation only; the controller never sees it."""

    model: Literal[ALL_PLANT_MODELS] = Field(  # type: ignore[valid-type]
        "single-integrator", description="; ".join(
            f"{p.name}: {p.summary}" for p in (*PLANTS.values(), *SECOND_ORDER_PLANTS.values())))
    disturbance_amplitude: NonNegative = Field(0.1, description="bound on |w_i|, state "
                                                                "units per second")
    a: Matrix = _omitted("linear model only: the n x n matrix a, as rows; default zero")
    g: Matrix = _omitted("linear model only: the n x n input matrix g, as rows; default "
                         "the identity")
    c: Vector = _omitted("linear model only: the constant drift c; default zero")
    parameters: Vector = _omitted("second-order models only: the simulated plant's "
                                  "parameters, in the model's order; default nominal")
    mjcf: Annotated[str, Strict(), Field(min_length=1)] = _omitted(
        "mujoco model only: the MJCF file, relative to the spec file's folder")
    joints: Annotated[list[Annotated[str, Strict()]], Field(min_length=1)] = _omitted(
        "mujoco model only: the slide or hinge joint of each state, in the spec's order")
    actuators: Annotated[list[Annotated[str, Strict()]], Field(min_length=1)] = _omitted(
        "mujoco model only: the actuator of each input, in the order of u")
    timestep: Positive = _omitted("mujoco model only: MuJoCo's timestep, s; default the "
                                  "model's own (1 / rate_hz must be a whole number of them)")
    axle_offset: Positive = _omitted(
        "differential-drive only (required): l, how far ahead of the axle's midpoint the "
        "look-ahead point the tube holds lies, m")
    track_width: Positive = _omitted("differential-drive only (required): b, the distance "
                                     "between the wheels, m")
    wheel_radius_error: Annotated[list[Annotated[float, Strict(), AllowInfNan(False),
                                                 Field(gt=-1, lt=1)]],
                                  Field(min_length=2, max_length=2)] = _omitted(
        "differential-drive only: [right, left] relative radius errors of the simulated "
        "base's wheels (a wheel of radius r (1 + e) where the controller assumes r); "
        "default [0, 0]")
    wheel_radius: Positive = _omitted(
        "differential-drive on MuJoCo only (required there): the wheels' nominal radius, m, "
        "to turn (v, omega) into the wheel actuators' speeds")
    slip: Annotated[list[NonNegative], Field(min_length=3, max_length=3)] = _omitted(
        "differential-drive only: amplitudes of the simulated slip [forward m/s, lateral "
        "m/s, turn rad/s]; default [0, 0, 0] (plant.disturbance_amplitude does not apply)")


class AssumptionsTable(_Table):
    """What the controller's designer knows about the unknown plant x_dot = f + g u + w."""

    input_gain: Annotated[list[Number], Field(min_length=2, max_length=2)] = _omitted(
        "[g_min, g_max]: bounds on the eigenvalues of the symmetric part of g(x); "
        "g_min > 0 (Assumption 2); default [1, 1]. For a second-order model: of the second "
        "stage's g; default the model's own (1 / mass; M(q)^-1 over the state space)")
    input_gain_skew: NonNegative = Field(0.0, description="bound on the norm of the skew "
                                                          "part of g(x)")
    input_gain_coupling: NonNegative = _omitted("bound on the off-diagonal part of each row "
                                                "of g(x); default implied by the two above")
    drift_bound: NonNegative | Annotated[list[NonNegative], Field(
        min_length=1, max_length=MAX_DIMENSION)] = Field(
        0.0, description="bound on |f(x)|, state units per second. For a second-order "
                         "model: on every |f_i| of the second stage, velocity units per "
                         "second, one number or one per position (a quadrotor's gravity "
                         "acts on its vertical axis only); default the model's own "
                         "(gravity; drag and Coriolis within state_space.velocity_bound)")
    disturbance_bound: NonNegative = _omitted("bound on |w(t)|, state units per second; "
                                              "default sqrt(n) x plant.disturbance_amplitude")
    input_gain_lipschitz: Annotated[list[NonNegative],
                                    Field(min_length=1, max_length=MAX_DIMENSION)] = _omitted(
        "one per state: L_j with |g(x) - g(y)|_2 <= sum_j L_j |x_j - y_j| (how fast g may "
        "change with each state); default the plant model's own (the omnidirectional robot "
        "[0, 0, 1]) while no bound on g is declared, else none: g may jump")
    drift_lipschitz: Annotated[list[NonNegative],
                               Field(min_length=1, max_length=MAX_DIMENSION)] = _omitted(
        "one per state: L_j with |f(x) - f(y)| <= sum_j L_j |x_j - y_j|, per second; default "
        "the plant model's own while drift_bound is not declared, else none: f may jump")


class ActuatorTable(_Table):
    """The actuators' limits: the controller must never ask an input for more than its bound."""

    input_bound: Annotated[list[Positive], Field(min_length=1, max_length=MAX_DIMENSION)] = \
        Field(description="largest |u_i| each input may be asked for, in input units (for "
                          "the omnidirectional robot v1, v2 in m/s, omega in rad/s; for the "
                          "other first-order plants one per state, state units per second; "
                          "for a second-order plant the physical input, one per position: "
                          "a force in N, the two-link arm's torques in N m); positive; "
                          "one entry per input")
    reverse_speed: NonNegative = _omitted(
        "differential-drive only: the largest speed the base may be asked to back up at, "
        "m/s (v >= -reverse_speed; 0: it never reverses); at most input_bound's v_max; "
        "default v_max (|v| <= v_max)")


class RobotTable(_Table):
    """The robot's size: the body lies within ``radius`` of the reference point the tube
    steers (docs/spec-format.md, ``[robot]``)."""

    radius: NonNegative = Field(description="the body's radius around the reference point, "
                                            "state units of dims (metres); obstacles are "
                                            "inflated and the state space shrunk by it")
    dims: Annotated[list[Index], Field(min_length=1, max_length=MAX_DIMENSION)] = _omitted(
        "state dimensions the body extends in; default the first two (the planar position)")


class SensingTable(_Table):
    """The sensing envelope within which obstacles sensed at run time are avoided
    (docs/sensing.md)."""

    range: Positive = Field(description="R: every obstacle with a point within this distance "
                                        "of the robot's reference point at a measurement is "
                                        "in it; state units of the robot's dims (metres)")
    latency: NonNegative = Field(description="L: a measurement taken at t_m is available at "
                                             "t_m + L, s")
    update_rate_hz: Positive = _omitted("measurements per second (or period)")
    period: Positive = _omitted("T_u: seconds between measurements (or update_rate_hz)")
    max_obstacle_radius: Positive = Field(description="r_max: every obstacle fits in a ball "
                                                      "of this radius, state units")
    max_obstacle_speed: NonNegative = Field(description="V: the largest speed of any point "
                                                        "of an obstacle, state units/s")
    replan_time: NonNegative = _omitted("tau: the replanner's time budget, s; a tube planned "
                                        "from the measurement at t_m switches in at t_m + L + "
                                        "tau; default one period")
    horizon: Positive = _omitted("H: how long after its switch a replanned tube is certified "
                                 "against the sensed obstacles, s, at least one period; "
                                 "default two periods")
    shortest_horizon: Positive = _omitted(
        "H_min: when no plan is certified over the horizon, one certified over this shorter "
        "one is taken, s, from one period to the horizon; default one period (equal to the "
        "horizon: no shorter plan)")
    max_obstacle_acceleration: NonNegative = _omitted(
        "A: the largest acceleration of any point of an obstacle, state units/s^2; with it a "
        "sensed obstacle's reachable set follows its velocity estimate; default none (the "
        "set grows at max_obstacle_speed in every direction)")
    velocity_error: NonNegative = _omitted(
        "E: every point of an obstacle moves, at the measurement, within this much of the "
        "velocity estimate, state units/s; only with max_obstacle_acceleration; default 0")


class TaskBoxTable(_Table):
    """One box of a reach task's ``any_of``."""

    lower: Vector = Field(description="lower corner, state units")
    upper: Vector = Field(description="upper corner, state units; upper > lower")


class TaskTable(_Table):
    """A timed task (docs/tasks.md): reach a box at some t of the window, or stay in a box
    for every t of it."""

    kind: Literal[TASK_KINDS] = Field(  # type: ignore[valid-type]
        description="reach: inside the box at some t in window (eventually); stay: inside "
                    "the box for every t in window (always)")
    window: Annotated[list[NonNegative], Field(min_length=2, max_length=2)] = Field(
        description="[t0, t1], seconds, 0 <= t0 < t1 <= prescribed_time")
    lower: Vector = _omitted("lower corner of the task's box, state units (or any_of)")
    upper: Vector = _omitted("upper corner of the task's box, state units")
    any_of: Annotated[list[TaskBoxTable], Field(min_length=1, max_length=MAX_ALTERNATIVES)] = \
        _omitted("reach only: the boxes of which one is to be reached (instead of "
                 "lower/upper); the design picks the first that certifies, in this order")
    duration: Positive = _omitted(
        "stay only: inside the box over some interval of this length (seconds) inside the "
        "window, the design choosing when; omitted: the whole window")


class TaskOrderTable(_Table):
    """Who orders the timed tasks' visits (docs/tasks.md, "Timing and order")."""

    order: Literal[TASK_ORDERS] = Field(  # type: ignore[valid-type]
        "listed", description="listed: the tasks are visited in the order they are listed; "
                              "any: the design chooses the order")


class SpecDocument(_Table):
    """One prescribed-time reach-avoid-stay task (Definition 2.1) and its design parameters.

    The document of a spec file, key for key; see docs/spec-format.md.
    """

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True,
                              title="stt-codegen spec")

    name: Annotated[str, Strict(), Field(pattern=NAME_REGEX)] = Field(
        description="identifier [A-Za-z][A-Za-z0-9_-]*, at most 64 characters")
    prescribed_time: Positive = Field(description="t_c of Definition 2.1, seconds")
    state_space: StateSpaceTable = Field(description="the state space X")
    initial: InitialTable
    target: TargetTable
    obstacles: list[Obstacle] = Field([], max_length=MAX_OBSTACLES,
                                      description="unsafe sets inside X: boxes, balls, "
                                                  "convex polytopes")
    tube: TubeTable = TubeTable()
    controller: ControllerTable = ControllerTable()
    plant: PlantTable = PlantTable()
    assumptions: AssumptionsTable = AssumptionsTable()
    actuator: ActuatorTable = _omitted("actuator limits; omitted: no limit (the design, the "
                                       "generated code and verify ignore actuators)")
    robot: RobotTable = _omitted("the robot's size; omitted: the robot is a point")
    tasks: Annotated[list[TaskTable], Field(max_length=MAX_TASKS)] = _omitted(
        "timed reach and stay tasks besides the target (docs/tasks.md), visited in the "
        "order listed unless [task_order] says otherwise; omitted: none")
    task_order: TaskOrderTable = _omitted("the order of the tasks' visits; omitted: as "
                                          "listed")
    sensing: SensingTable = _omitted("the sensing envelope of obstacles seen at run time "
                                     "(docs/sensing.md); omitted: none")


#: The JSON Schema dialect of :func:`json_schema`: draft 7, which TOML language servers
#: (Taplo, Even Better TOML, Tombi) read; references are JSON pointers into ``$defs``.
JSON_SCHEMA_DIALECT = "http://json-schema.org/draft-07/schema#"


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 7) of a spec document, from :class:`SpecDocument`.

    Returns
    -------
    dict
        The schema, with ``$schema`` naming draft 7; JSON-serialisable.
    """
    return {"$schema": JSON_SCHEMA_DIALECT, **SpecDocument.model_json_schema()}


_TABLES: dict[str, type[_Table]] = {
    "state_space": StateSpaceTable, "initial": InitialTable, "target": TargetTable,
    "tube": TubeTable, "controller": ControllerTable, "plant": PlantTable,
    "assumptions": AssumptionsTable, "actuator": ActuatorTable, "robot": RobotTable,
    "box": BoxObstacle, "ball": BallObstacle, "polytope": PolytopeObstacle,
    "tasks": TaskTable, "any_of": TaskBoxTable, "task_order": TaskOrderTable,
    "sensing": SensingTable}


def key_name(key: str) -> str:
    """A key as it appears in a field name: quoted when empty, long or odd (newlines...),
    so that the message names it on one line."""
    if re.fullmatch(r"[A-Za-z0-9_-]{1,64}", key):
        return key
    return repr(key) if len(key) <= 64 else repr(key[:64]) + "..."


def _is_number_tag(part: object) -> bool:
    """A tag pydantic puts in ``loc`` for a member of a number-or-list union."""
    return isinstance(part, str) and (part.startswith("constrained-")
                                      or part.startswith("list[constrained-"))


def _number_or_list(errors: list[dict]) -> list[dict]:
    """The errors of a number-or-list field (``drift_bound``) for the member the input
    meant: the list's when it was a list (its errors are then not ``list_type``), else
    the number's."""
    def tags(error: dict) -> list[str]:
        return [p for p in error["loc"] if _is_number_tag(p)]
    listed = [e for e in errors if any(t.startswith("list[") for t in tags(e))]
    meant_list = any(e["type"] != "list_type" for e in listed)
    return [e for e in errors if not tags(e)
            or any(t.startswith("list[") for t in tags(e)) == meant_list]


def _field(loc: tuple) -> str:
    """``("obstacles", 2, "ball", "radius")`` -> ``"obstacles[2].radius"`` (union tags dropped)."""
    text = ""
    for k, part in enumerate(loc):
        if isinstance(part, int):
            text += f"[{part}]"
        elif _is_number_tag(part):
            continue
        elif not (part in ("box", "ball", "polytope") and k and isinstance(loc[k - 1], int)):
            name = key_name(part) if k == len(loc) - 1 else part
            text += f".{name}" if text else name
    return text


def _allowed(loc: tuple) -> list[str]:
    """The keys of the table in which ``loc`` names a key."""
    tables = [_TABLES[p] for p in loc[:-1] if isinstance(p, str) and p in _TABLES]
    return sorted((tables[-1] if tables else SpecDocument).model_fields)


def _unknown_key(key: str, allowed: list[str]) -> str:
    """The reason for an unknown key: the allowed keys, with the closest (``difflib``) as a
    "did you mean" when one is close."""
    close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return f"unknown key ({hint}allowed: {', '.join(allowed)})"


def value_kind(value: Any) -> str:
    """What a value is, in TOML's words (``"an array"``, ``"a table"``...).

    Parameters
    ----------
    value : object
        A value parsed from TOML.

    Returns
    -------
    str
        ``"a boolean"``, ``"a string"``, ``"an array"``, ``"a table"``, ``"an integer"``,
        ``"a float"``, or the type's name for anything else (dates).
    """
    return {bool: "a boolean", str: "a string", list: "an array", dict: "a table",
            int: "an integer", float: "a float"}.get(type(value), type(value).__name__)


def short_repr(value: Any) -> str:
    """``repr(value)``, cut to one short line."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"


def _beyond(value: Any) -> str:
    return f"magnitude {short_repr(value)} is beyond {MAX_MAGNITUDE:.0e}".replace("e+", "e")


def _reason(error: dict) -> str:
    """One violation in the loader's words."""
    kind, value, ctx = error["type"], error.get("input"), error.get("ctx") or {}
    if kind in ("list_type", "too_short", "too_long") and error["loc"][-1] == "input_gain":
        return f"must be an array [g_min, g_max] of two numbers, got {short_repr(value)}"
    if kind in ("list_type", "too_short", "too_long") and error["loc"][-1] == "window":
        return f"must be an array [t0, t1] of two numbers, got {short_repr(value)}"
    if kind == "missing":
        return "missing"
    if kind == "extra_forbidden" and error["loc"][-1] in MOTION_KEYS and any(
            part in ("ball", "polytope") for part in error["loc"]):
        return ("motion (active, velocity, path) is for box obstacles only: give a box "
                "that covers the shape (docs/moving-obstacles.md)")
    if kind in ("list_type", "too_short", "too_long") and error["loc"][-1] == "active":
        return f"must be an array [t_on, t_off] of two numbers, got {short_repr(value)}"
    if kind == "extra_forbidden":
        return _unknown_key(str(error["loc"][-1]), _allowed(error["loc"]))
    if kind == "finite_number":
        return f"must be finite, got {value!r}"
    if kind in ("float_type", "float_parsing"):
        if isinstance(value, int) and not isinstance(value, bool):
            return _beyond(value)
        return f"must be a number, got {value_kind(value)}"
    if kind in ("int_type", "int_parsing", "int_from_float"):
        return f"must be an integer, got {value_kind(value)}"
    if kind == "string_type":
        return f"must be a string, got {value_kind(value)}"
    if kind == "string_pattern_mismatch":
        return (f"{short_repr(value)} is not an identifier: it must match [A-Za-z][A-Za-z0-9_-]* "
                "and be at most 64 characters")
    if kind == "literal_error":
        return f"must be one of {ctx.get('expected', '')}, got {short_repr(value)}".replace("'", "")
    if kind == "greater_than":
        return f"must be positive, got {value!r}"
    if kind == "greater_than_equal":
        return f"must be non-negative, got {value!r}"
    if kind == "less_than_equal":
        return _beyond(value)
    if kind == "too_short":
        return "must not be empty"
    if kind == "too_long":
        what = {"obstacles": "obstacles", "vertices": "vertices"}.get(
            error["loc"][-1], "dimensions" if ctx.get("max_length") == MAX_DIMENSION
            else "entries")
        return f"{len(value)} {what}; at most {ctx.get('max_length')}"
    if kind == "list_type":
        what = {"obstacles": "tables", "vertices": "points (arrays)",
                "path": "rows [t, centre...] (arrays of numbers)",
                "dims": "dimension indices", "a": "rows (arrays of numbers)",
                "g": "rows (arrays of numbers)"}.get(error["loc"][-1], "numbers")
        return f"must be an array of {what}, got {value_kind(value)}"
    if kind in ("model_type", "model_attributes_type", "dict_type", "union_tag_not_found",
                "union_tag_invalid"):
        return f"must be a table, got {value_kind(value)}"
    return error["msg"]


#: Arrays of arrays: a row that is not an array is reported as the whole array's fault.
_NESTED = ("vertices", "a", "g", "path")


def _row_as_array(error: dict) -> dict:
    loc = error["loc"]
    if (error["type"] == "list_type" and len(loc) >= 2 and isinstance(loc[-1], int)
            and loc[-2] in _NESTED):
        return {**error, "loc": loc[:-1], "input": [error["input"]]}
    return error


def _order(fields: tuple[str, ...]):
    """Sort key: unknown top-level keys first, then missing ones, then in field order."""
    def key(error: dict) -> tuple[int, int, int]:
        loc, kind = error["loc"], error["type"]
        if len(loc) == 1 and kind in ("extra_forbidden", "missing"):
            return (0 if kind == "extra_forbidden" else 1, 0, 0)
        top = fields.index(loc[0]) if loc and loc[0] in fields else len(fields)
        return (2, top, {"extra_forbidden": 0, "missing": 1}.get(kind, 2))
    return key


def check_document(doc: Any) -> SpecDocument:
    """Validate a spec document against :class:`SpecDocument`.

    Parameters
    ----------
    doc : dict
        The document as :mod:`tomllib` reads it.

    Returns
    -------
    SpecDocument
        With the defaults of the keys not given.

    Raises
    ------
    SpecError
        The first violation: the field (``"tube.kappa"``, ``"obstacles[2].radius"``) and
        the reason (``"must be positive, got 0.0"``).
    """
    try:
        return SpecDocument.model_validate(doc)
    except ValidationError as exc:
        first = _row_as_array(sorted(_number_or_list(exc.errors(include_url=False)),
                                     key=_order(tuple(SpecDocument.model_fields)))[0])
        raise SpecError(_field(first["loc"]), _reason(first)) from None
    except RecursionError:
        raise SpecError("", "nested too deeply") from None
