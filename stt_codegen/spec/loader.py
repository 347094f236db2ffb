"""Problem specification: one prescribed-time reach-avoid-stay task (Definition 2.1).

A spec is a TOML file with a fixed schema (docs/spec-format.md). :func:`load_spec`
reads a bundled case by name or a file by path, validates it and returns a frozen
:class:`Spec`. Every rejection is a :class:`SpecError` naming the field and the reason.

One validation path: the schema (:mod:`.schema`, pydantic) checks every key, type, sign
and enum and fills in the defaults; this module builds the :class:`Spec` from the
validated :class:`~.schema.SpecDocument` and checks only the rules that relate fields to
each other (lengths equal to the state dimension, boxes inside boxes, points in
interiors, obstacles against the start and the target, a plant model's state count from
:mod:`.plants`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..cases import bundled_cases, bundled_folder, bundled_spec_bytes
from ..errors import SpecError, number_text
from .assumptions import Assumptions, combine_assumptions
from .model_bounds import declared_bounds, model_bounds
from .motion import MovingObstacle, check_moving, is_moving, moving_obstacle
from .mujoco import MujocoModel, mujoco_model, with_folder
from .differential_drive import DifferentialDrive
from .plants import (MODEL_KEYS, PARAMETER_KEYS, PLANTS, SECOND_ORDER_MODELS, SECOND_ORDER_PLANTS,
                     SIMULATOR_KEYS, dimension_mismatch, plant_entry)
from .robot import (Robot, inflate_ball, inflate_bounds, inflate_moving, inflate_polytope,
                    robot_dims, shrink_bounds)
from .tasks import Task, build_tasks
from .state_space import with_state_space
from .units import warn_units
from .second_order import SecondOrder, parse_second_order
from .sensing import Sensing, sensing_from_table
from .variants import variant_of
from .schema import (NAME_REGEX, ActuatorTable, AssumptionsTable, BallObstacle, BoxObstacle, BoxTable,
                     ControllerTable, PlantTable, PolytopeObstacle, check_document, value_kind)

__all__ = ["Assumptions", "Box", "DEFAULT_HALF_WIDTH_FRACTION", "LinearPlant",
           "law13_plant_terms", "look_ahead_plant_terms", "NAME_PATTERN", "Obstacle", "Spec",
           "UnsafeSet", "bundled_cases", "file_or_bundled", "load_spec", "parse_spec",
           "toml_document"]

NAME_PATTERN = re.compile(NAME_REGEX)
#: Fraction of the available room used by the default half-widths ``d_0`` and ``d_T``.
DEFAULT_HALF_WIDTH_FRACTION = 0.8


@dataclass(frozen=True)
class Box:
    """An axis-aligned box ``prod_i [lower_i, upper_i]``.

    Attributes
    ----------
    lower, upper : tuple of float, length n
        Corner coordinates, ``lower_i <= upper_i``.
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]

    @property
    def center(self) -> tuple[float, ...]:
        return tuple((a + b) / 2 for a, b in zip(self.lower, self.upper))

    def contains_box(self, other: "Box") -> bool:
        return all(a <= c and d <= b for a, b, c, d in
                   zip(self.lower, self.upper, other.lower, other.upper))

    def meets(self, other: "Box") -> bool:
        """Whether the closed boxes intersect (touching counts)."""
        return all(c <= b and a <= d for a, b, c, d in
                   zip(self.lower, self.upper, other.lower, other.upper))


@dataclass(frozen=True)
class Obstacle:
    """One box obstacle ``U^j`` the tube design avoids, given on some dimensions.

    A box from the spec is one obstacle; a ball or polytope from the spec becomes the
    several boxes of its covering (Remark 3.1), all with the same ``source``.

    Attributes
    ----------
    lower, upper : tuple of float, length len(dims)
        Bounds on the dimensions in ``dims``.
    dims : tuple of int
        The state dimensions the bounds apply to; in every other dimension the
        obstacle spans the whole state space.
    source : int
        Index of the spec's ``[[obstacles]]`` entry it comes from.
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    dims: tuple[int, ...]
    source: int = 0

    def box(self, state_space: Box) -> Box:
        """The obstacle as a full-dimensional box inside ``state_space``."""
        return _embed(self.lower, self.upper, self.dims, state_space)


def _embed(lower, upper, dims, state_space: Box) -> Box:
    lo, hi = list(state_space.lower), list(state_space.upper)
    for k, i in enumerate(dims):
        lo[i], hi[i] = float(lower[k]), float(upper[k])
    return Box(tuple(lo), tuple(hi))


@dataclass(frozen=True)
class UnsafeSet:
    """An ``[[obstacles]]`` entry as the user gave it: a box, a ball or a convex polytope.

    Attributes
    ----------
    kind : {"box", "ball", "polytope"}
    dims : tuple of int
    shape : Box, Ball or Polytope
        In the coordinates ``dims`` (a ``Box`` of length ``len(dims)`` for boxes).
    tolerance : float or None
        Covering tolerance (balls and polytopes), state units.
    source : int or None
        Index of the spec's ``[[obstacles]]`` entry (``None``: its place in
        ``Spec.unsafe_sets``, which holds the obstacles that do not move).
    """

    kind: str
    dims: tuple[int, ...]
    shape: Any
    tolerance: float | None = None
    source: int | None = None

    def signed_clearance(self, points) -> "Any":
        """Distance of each state (N, n) outside the set, minus its depth inside.

        Exact for boxes and balls; for polytopes the distance to the nearest facet's
        plane, a lower bound of the distance (exact off the edges).
        """
        import numpy as np
        y = np.atleast_2d(points)[:, list(self.dims)]
        if self.kind == "box":
            gaps = np.maximum(np.array(self.shape.lower) - y, y - np.array(self.shape.upper))
            outside = np.sqrt(np.sum(np.maximum(gaps, 0.0) ** 2, axis=1))
            return np.where(np.any(gaps > 0, axis=1), outside, gaps.max(axis=1))
        return self.shape.signed_clearance(y)


@dataclass(frozen=True)
class TubeParameters:
    """Tube shaping parameters of section III (all positive).

    Attributes
    ----------
    delta_b : float
        ``delta_B`` of eqs. (7)-(8): clearance kept from each obstacle, state units.
    circumvent_sharpness : float or None
        ``k^j`` of eqs. (7)-(8): smoothness of the circumvent bump, the same for every
        obstacle; ``None`` (the key omitted) lets the design choose one per circumvent.
    theta0 : float
        ``theta_0`` of eq. (11).
    kappa : float
        ``kappa`` of eq. (11): decay rate of ``alpha``, 1/s.
    mu : float
        ``mu`` of eq. (11): conflict tolerance, state units.
    smoothness : float
        ``nu`` of the smooth max/min in eqs. (9)-(10), 1/state units.
    method : {"paper", "via", "auto"}
        The reach tube: the paper's single tube (eq. (4)), via-point segments, or the
        paper's first and via points when it has no certified design (default).
    via_profile : {"smoothstep", "cruise", "scurve", "glide"}
        The via-point segments' profile (``tube/parameters.py``). Not a key of the file:
        ``"smoothstep"`` as loaded; the design within ``[actuator]`` tries ``"smoothstep"``
        and then ``"scurve"`` (a lower peak acceleration) with the ``"acceleration"``
        timing (which gives a move ``"glide"`` segments where its S-curve would pass the
        velocity bound), and ``"cruise"`` (a lower peak rate), when the other tubes exceed
        the bound.
    via_timing : {"length", "acceleration", "turn"}
        How the via-point segments (and the legs of ``[[tasks]]``) share the time
        (``design/via.py``): in proportion to each move's length, or to its square root
        (the same peak acceleration on every move), or to its length plus ``via_turn``
        times its turn from the move before (no tasks). Not a key of the file:
        ``"length"`` as loaded; the design of a second-order spec within ``[actuator]``
        tries ``"acceleration"`` (its input is a force), of a differential-drive spec
        ``"turn"``.
    via_corners : {"stop", "blend"}
        Whether the via-point tube stops at every via box (``"stop"``: one segment at a
        time) or passes it, each segment starting before the previous one ends
        (``"blend"``: blended corners, ``design/via.py``). Not a key of the file:
        ``"stop"`` as loaded; the design within ``[actuator]`` tries ``"blend"`` after
        the tubes that stop.
    via_turn : float
        With ``via_timing = "turn"``: state units a move's weight gains per radian of its
        turn from the move before (a base's ``v_max / omega_max``: the distance it drives
        in the time it turns one radian). Not a key of the file: 0 as loaded.
    """

    delta_b: float
    circumvent_sharpness: float | None
    theta0: float
    kappa: float
    mu: float
    smoothness: float
    method: str = "auto"
    via_profile: str = "smoothstep"
    via_timing: str = "length"
    via_corners: str = "stop"
    via_turn: float = 0.0


@dataclass(frozen=True)
class LinearPlant:
    """The ``linear`` plant of ``[plant]``: ``x_dot = a x + c + g u + w``.

    Attributes
    ----------
    a, g : tuple of tuple of float, shape (n, n)
        Rows of the matrices; defaults zero and the identity.
    c : tuple of float, length n
        Constant drift; default zero.
    """

    a: tuple[tuple[float, ...], ...]
    g: tuple[tuple[float, ...], ...]
    c: tuple[float, ...]


@dataclass(frozen=True)
class Spec:
    """A validated prescribed-time reach-avoid-stay task and its design parameters.

    Attributes
    ----------
    name : str
        Identifier, ``[A-Za-z][A-Za-z0-9_-]*`` (at most 64 characters).
    prescribed_time : float
        ``t_c`` of Definition 2.1 and eq. (4), seconds.
    state_space : Box
        ``X``.
    initial_set : Box
        ``X_0``.
    initial_state : tuple of float
        ``x(0)``, in the interior of ``X_0``.
    initial_half_width : tuple of float
        ``d_0`` of eq. (2); ``x(0) +- d_0`` lies inside ``X_0``.
    target_set : Box
        ``T``.
    target_center : tuple of float
        ``eta`` of eq. (3).
    target_half_width : tuple of float
        ``d_T`` of eq. (3); ``eta +- d_T`` lies inside ``T``.
    obstacles : tuple of Obstacle
        The box obstacles the tube avoids: the spec's boxes and the coverings of its
        balls and polytopes, in the spec's order.
    unsafe_sets : tuple of UnsafeSet
        The ``[[obstacles]]`` entries as given (for collision checks and plots).
    tube : TubeParameters
    gain : float or None
        ``k`` of law (13); ``None`` lets the design choose it.
    rate_hz : float
        Sampling rate of the deployed controller, Hz.
    delay : float
        ``[controller] delay``, s: the computation delay the sampled-data certificate
        covers; the command computed from the state read at ``t_k`` acts from
        ``t_k + delay`` until the next command acts (docs/sampled-data.md, "Computation
        delay and jitter"). 0: applied at once.
    jitter : float
        ``[controller] jitter``, s: the state is read within ``jitter`` of ``k / rate_hz``
        (the first sample at ``t = 0``); ``delay + 2 jitter <= 1 / rate_hz``.
    compensate_delay : bool
        ``[controller] compensate_delay``: law (13) is evaluated at the state predicted at
        ``t_k + delay`` from the held command (the variant's ``predictor`` role;
        docs/sampled-data.md, "Compensating a delay"); ``delay`` up to ``1 / rate_hz``,
        ``jitter`` 0.
    plant_model : str
        ``"omnidirectional"`` (eq. (14)), ``"single-integrator"`` or ``"linear"``: the
        plant ``simulate`` runs, and the source of the bounds in :attr:`assumptions`. For a
        spec whose ``plant.model`` is second order, ``"single-integrator"``: the position
        stage ``x1_dot = x2`` that the tube and law (13) see (the plant itself is
        :attr:`second_order`).
    disturbance_amplitude : float
        Bound on ``|w_i|`` of the simulated disturbance.
    linear_plant : LinearPlant or None
        The matrices of the ``linear`` model (``None`` for the other models).
    assumptions : Assumptions
        The plant bounds: the model's over the state space, with the ``[assumptions]``
        section (:func:`~.assumptions.combine_assumptions`).
    input_bound : tuple of float or None
        ``[actuator] input_bound``: the largest ``|u_i|`` the controller may ask of each
        input, in input units, one per input of the plant model (:attr:`input_names`):
        law (13)'s ``u`` for a first-order model; for a second-order model the physical
        input (force or torque, :attr:`input_unit`) of the cascade's second stage, not the
        virtual velocity ``r``. ``None``: no ``[actuator]``, no limit.
    reverse_speed : float or None
        ``[actuator] reverse_speed`` of a differential-drive base: the largest speed it may
        be asked to back up at, m/s (``v >= -reverse_speed``), at most ``v_max``; ``None``:
        ``|v| <= v_max`` (docs/differential-drive.md, "Backing up").
    second_order : SecondOrder or None
        The second-order plant (``plant.model`` a second-order model, with
        ``plant.parameters``, ``initial.velocity``, ``state_space.velocity_bound`` and the
        ``[assumptions]`` of its second stage; docs/second-order.md); ``None`` for a
        first-order spec.
    drive : DifferentialDrive or None
        The differential-drive base (``plant.model = "differential-drive"``: the
        ``[plant]`` parameters and ``initial.heading``; docs/differential-drive.md), whose
        look-ahead point the tube holds (the state space, the sets and ``initial.state``
        are the point's); ``None`` for any other model.
    source_hash : str
        SHA-256 of the spec file's bytes.
    target_half_width_given : bool
        ``target.half_width`` was set in the spec (else the design may shrink the
        default ``d_T`` to keep an obstacle beside the target out of the target box).
    tasks : tuple of Task
        The ``[[tasks]]`` entries (:mod:`~.tasks`, docs/tasks.md); empty without them.
    target_any_of : tuple of (int, Spec)
        ``[target] any_of``: per target box kept, its ``any_of`` index and the spec with
        that box as the target (whose own ``target_any_of`` is empty); this spec is the
        first of them. Empty for a single target.
    target_dropped : tuple of (int, str)
        ``[target] any_of`` boxes dropped because an obstacle meets them: the index and
        the obstacle's field.
    task_order : {"listed", "any"}
        ``[task_order] order``: the tasks are visited in the listed order, or in the order
        the design chooses.
    moving_obstacles : tuple of MovingObstacle
        The ``[[obstacles]]`` boxes with ``active``, ``velocity`` or ``path``
        (:mod:`~.motion`); they are in neither :attr:`obstacles` nor :attr:`unsafe_sets`.
    mujoco : MujocoModel or None
        ``[plant] model = "mujoco"``: the MJCF file, joints and actuators the plant is
        simulated on (:mod:`.mujoco`).
    robot : Robot or None
        ``[robot]``: the robot's size and the sets as given (:mod:`~.robot`). With it,
        :attr:`state_space` is the given one shrunk by the radius and :attr:`obstacles`,
        :attr:`unsafe_sets`, :attr:`moving_obstacles` are the given ones inflated by it:
        the sets of the reference point the tube steers. ``None``: a point robot.
    sensing : Sensing or None
        ``[sensing]``: the envelope within which obstacles sensed at run time are avoided
        by replanning (:mod:`~.sensing`, docs/sensing.md); ``None`` without the table. It
        plays no part in the design of the spec itself.

    Examples
    --------
    From a dictionary (a TOML spec file's tables, :func:`load_spec` for a file or a bundled
    case); defaults fill in what is not given:

    >>> import stt_codegen as stt
    >>> spec = stt.Spec.from_dict({
    ...     "name": "corridor", "prescribed_time": 5.0,
    ...     "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 1.0]},
    ...     "initial": {"lower": [0.0, 0.0], "upper": [0.5, 1.0]},
    ...     "target": {"lower": [3.5, 0.0], "upper": [4.0, 1.0]}})
    >>> spec.dimension, spec.initial_state, spec.target_center, spec.plant_model
    (2, (0.25, 0.5), (3.75, 0.5), 'single-integrator')
    """

    name: str
    prescribed_time: float
    state_space: Box
    initial_set: Box
    initial_state: tuple[float, ...]
    initial_half_width: tuple[float, ...]
    target_set: Box
    target_center: tuple[float, ...]
    target_half_width: tuple[float, ...]
    obstacles: tuple[Obstacle, ...]
    unsafe_sets: tuple[UnsafeSet, ...]
    tube: TubeParameters
    gain: float | None
    rate_hz: float
    plant_model: str
    disturbance_amplitude: float
    linear_plant: LinearPlant | None = None
    assumptions: Assumptions = Assumptions()
    input_bound: tuple[float, ...] | None = None
    reverse_speed: float | None = None
    second_order: SecondOrder | None = None
    source_hash: str = field(default="", compare=False)
    target_half_width_given: bool = True
    tasks: tuple[Task, ...] = ()
    task_order: str = "listed"
    target_any_of: tuple[tuple[int, "Spec"], ...] = field(default=(), compare=False,
                                                          repr=False)
    target_dropped: tuple[tuple[int, str], ...] = ()
    moving_obstacles: tuple[MovingObstacle, ...] = ()
    robot: Robot | None = None
    mujoco: MujocoModel | None = None
    drive: DifferentialDrive | None = None
    delay: float = 0.0
    jitter: float = 0.0
    compensate_delay: bool = False
    sensing: Sensing | None = None

    @property
    def dimension(self) -> int:
        """State dimension ``n``."""
        return len(self.state_space.lower)

    @property
    def order(self) -> int:
        """The plant's order (what the variant does with it: :attr:`variant`,
        :mod:`~.variants`).

        Returns
        -------
        int
            1: system (1), ``x_dot = f(x) + g(x) u + w``, driven by law (13); 2: a
            second-order ``plant.model`` (:attr:`second_order`), ``x1_dot = x2``, ``x2_dot
            = f + g u + w``, driven by the cascade law (docs/second-order.md) on the same
            tube of the positions ``x1``.
        """
        return 1 if self.second_order is None else 2

    @property
    def velocity_bound(self) -> tuple[float, ...] | None:
        """``state_space.velocity_bound``: the bound of ``|x2_i|`` of a second-order plant
        (:attr:`second_order`), velocity units (state units per second) per position; None
        for a first-order plant or where it is not declared."""
        return None if self.second_order is None else self.second_order.velocity_bound

    @property
    def variant(self) -> str:
        """The controller variant (:data:`~.plants.VARIANTS`) that runs the plant.

        Returns
        -------
        str
            ``"first-order"`` (law (13) on the plant's state), ``"cascade"`` (a
            second-order plant, docs/second-order.md) or ``"look-ahead"`` (law (13) on the
            look-ahead point of a differential-drive base, docs/differential-drive.md).
        """
        return "cascade" if self.second_order is not None else \
            plant_entry(self.plant_model).variant

    def plant_data(self, model: str | None = None) -> Any:
        """The ``[plant]`` data a model's equations take: the ``linear`` model's matrices,
        the differential drive's base; ``None`` for a model without any.

        Parameters
        ----------
        model : str, optional
            A first-order ``plant.model`` (default the spec's): the spec's data only if
            that model takes them.

        Returns
        -------
        LinearPlant, DifferentialDrive or None
        """
        entry = plant_entry(model or self.plant_model)
        if entry.keys:
            return self.linear_plant
        return self.drive if entry.parameter_keys else None

    @property
    def input_names(self) -> tuple[str, ...]:
        """Names of the inputs ``u`` that ``[actuator] input_bound`` bounds, in its order:
        the second-order model's physical inputs (``F1``, ``F2``, ..., the quadrotor's
        thrust, the arm's torques) for order 2, else the first-order model's; a MuJoCo
        plant's actuators, except a differential-drive base's (its wheels), whose bound is
        on ``(v, omega)``."""
        if self.mujoco is not None and variant_of(self).actuator_inputs:
            return self.mujoco.actuators
        if self.second_order is not None:
            return SECOND_ORDER_PLANTS[self.second_order.model].input_names(self.dimension)
        return PLANTS[self.plant_model].input_names(self.dimension)

    @property
    def input_unit(self) -> str:
        """The SI unit of the inputs for a second-order model (``"N"``, ``"N m"``); ``""``
        for a first-order model (its inputs are velocities, in state units per second)."""
        if self.second_order is not None:
            return SECOND_ORDER_PLANTS[self.second_order.model].input_unit
        return ""

    @property
    def c_name(self) -> str:
        """The name as a C identifier (``-`` replaced by ``_``)."""
        return self.name.replace("-", "_")

    def obstacle_boxes(self) -> list[Box]:
        """Every obstacle as a full-dimensional box."""
        return [o.box(self.state_space) for o in self.obstacles]

    def with_plant_model(self, model: str) -> "Spec":
        """This spec with another ``plant.model``, its :attr:`assumptions` derived again.

        The declared ``[assumptions]`` keys keep their values; the others come from
        ``model`` (a ``linear`` model without this spec's matrices is ``a = 0``,
        ``g = I``, ``c = 0``).

        Raises
        ------
        SpecError
            A declared bound that ``model`` violates (the field names the key), or a
            model whose state count differs (field ``plant``).
        """
        if model == self.plant_model:
            return self
        mismatch = dimension_mismatch(model, self.dimension)
        if mismatch:
            raise SpecError("plant", mismatch)
        a = self.assumptions
        declared = {key: getattr(a, key) for key in a.declared}
        # only a model that takes [plant] matrices or parameters keeps this spec's
        bounds = model_bounds(model, self.state_space.lower, self.state_space.upper,
                              self.plant_data(model))
        return replace(self, plant_model=model, assumptions=combine_assumptions(
            bounds, declared, self.dimension, self.disturbance_amplitude))

    def without_actuator(self) -> "Spec":
        """This spec without ``[actuator]``: no ``input_bound`` and no ``reverse_speed``
        (the design of a tube whose proof against the limits comes after).

        Returns
        -------
        Spec

        Examples
        --------
        >>> import stt_codegen as stt
        >>> spec = stt.load_spec("office-base")
        >>> spec.input_bound, spec.without_actuator().input_bound
        ((1.6, 16.0), None)
        """
        return replace(self, input_bound=None, reverse_speed=None)

    def with_axle_offset(self, axle_offset: float) -> "Spec":
        """This differential-drive spec with another ``plant.axle_offset``: the obstacles
        inflated and the state space shrunk by ``robot.radius`` plus the new offset, and
        the :attr:`assumptions` the base implies derived again (the declared
        ``[assumptions]`` keys keep their values), as :func:`load_spec` would load it.

        Parameters
        ----------
        axle_offset : float
            ``l``, m, positive.

        Returns
        -------
        Spec
            ``initial.state`` and the sets as given (they are the look-ahead point's);
            each ``[target] any_of`` box's spec with the same offset.

        Raises
        ------
        SpecError
            Not a differential drive (field ``plant.model``); ``axle_offset`` not positive
            or the robot no longer fitting (field ``plant.axle_offset``, or the set's).

        Examples
        --------
        >>> import stt_codegen as stt
        >>> spec = stt.load_spec("office-base")
        >>> longer = spec.with_axle_offset(0.2)
        >>> longer.drive.axle_offset, round(longer.state_space.lower[0], 6)
        (0.2, 0.32)
        """
        if self.robot is None or not self.robot.offset:     # the offset is the base's only
            raise SpecError("plant.model", "only a differential-drive spec has an axle_offset")
        if not axle_offset > 0.0:
            raise SpecError("plant.axle_offset", f"must be positive, got {axle_offset!r}")
        given = self.robot
        robot = replace(given, radius=given.radius - given.offset + axle_offset,
                        offset=float(axle_offset))
        state_space, unsafe_sets, moving = _robot_problem(
            robot, given.state_space, self.initial_set, self.target_set,
            self.prescribed_time, (self.initial_state, self.target_center))
        obstacles = _clipped(_cover_all(unsafe_sets, state_space, self.initial_set,
                                        self.target_set), state_space)
        drive = replace(self.drive, axle_offset=float(axle_offset))
        a = self.assumptions
        declared = {key: getattr(a, key) for key in a.declared}
        bounds = model_bounds(self.plant_model, state_space.lower, state_space.upper, drive)
        return replace(self, state_space=state_space, unsafe_sets=unsafe_sets,
                       moving_obstacles=moving, obstacles=obstacles, robot=robot, drive=drive,
                       assumptions=combine_assumptions(bounds, declared, self.dimension,
                                                       self.disturbance_amplitude),
                       target_any_of=tuple((k, one.with_axle_offset(axle_offset))
                                           for k, one in self.target_any_of))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Spec":
        """Validate a spec given as a dictionary, the same document as a TOML file.

        Parameters
        ----------
        data : mapping
            The spec's tables as nested dicts and lists, exactly as :mod:`tomllib` would
            read the file: ``{"name": ..., "prescribed_time": ..., "state_space":
            {"lower": [...], "upper": [...]}, ...}`` (see docs/spec-format.md).
            Tuples and numpy arrays are accepted wherever a list is, numpy scalars
            wherever a number is. A ``linear`` plant may be given as a continuous-time
            python-control system, ``"plant": {"model": "linear", "system": ct.ss(A, B,
            np.eye(n), 0)}`` (``A`` and ``B`` become ``a`` and ``g``; field
            ``plant.system`` in errors).

        Returns
        -------
        Spec
            ``source_hash`` is the SHA-256 of the validated document as canonical JSON
            (sorted keys), since there are no file bytes.

        Raises
        ------
        SpecError
            As :func:`load_spec`: the field and the reason.

        See Also
        --------
        load_spec : the same from a bundled case name or a TOML file.
        stt_codegen.design_tube : the next step, the tube of the spec.

        Examples
        --------
        >>> import numpy as np
        >>> import stt_codegen as stt
        >>> task = {
        ...     "name": "corridor", "prescribed_time": 8.0,
        ...     "state_space": {"lower": [0.0, 0.0], "upper": [5.0, 5.0]},
        ...     "initial": {"lower": [0.0, 0.0], "upper": [0.5, 0.5]},
        ...     "target": {"lower": np.array([4.5, 4.5]), "upper": np.array([5.0, 5.0])},
        ...     "obstacles": [{"lower": [2.0, 2.0], "upper": [3.0, 3.0]}]}
        >>> spec = stt.Spec.from_dict(task)
        >>> spec.dimension, spec.target_set.lower
        (2, (4.5, 4.5))
        >>> stt.Spec.from_dict({**task, "prescribed_time": -8.0})
        Traceback (most recent call last):
        ...
        stt_codegen.errors.SpecError: prescribed_time: must be positive, got -8.0
        """
        if not isinstance(data, Mapping):
            raise SpecError("", f"a spec is a table (dict), got {value_kind(data)}")
        try:
            doc = _as_document(with_state_space(data))
        except RecursionError:
            raise SpecError("", "nested too deeply") from None
        spec = _validate(doc)
        warn_units(spec)
        canonical = json.dumps(doc, sort_keys=True, default=repr).encode()
        return _replace_hash(spec, hashlib.sha256(canonical).hexdigest())


# --------------------------------------------------------------------------- loading


def load_spec(spec: str | Path) -> Spec:
    """Load and validate a spec, by bundled name or by file path.

    A spec is one prescribed-time reach-avoid-stay task (Definition 2.1): the state space
    ``X``, the initial set ``X_0`` and state ``x(0)``, the target ``T``, the unsafe sets
    and the prescribed time ``t_c`` (seconds), with the tube's parameters (eqs. (2)-(11)),
    the controller's gain and rate (law (13)) and the plant used in simulation. The format
    is docs/spec-format.md's; :meth:`Spec.from_dict` takes the same as a dict.

    Parameters
    ----------
    spec : str or path
        A bundled case name (see :func:`bundled_cases`) or a path to a TOML file.

    Returns
    -------
    Spec
        Frozen; vectors are tuples of length ``n``, the state dimension.

    Raises
    ------
    TypeError
        ``spec`` is neither a string nor a path (a dict: use :meth:`Spec.from_dict`).
    SpecError
        The file does not exist or cannot be read, is not valid TOML, or a field
        is missing, unknown, of the wrong type or fails a rule of the schema.

    See Also
    --------
    Spec.from_dict : the same from a dictionary.
    stt_codegen.bundled_cases : the bundled case names.
    stt_codegen.design_tube : the next step, the tube of the spec.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> spec = stt.load_spec("omnirobot-s1")         # or a path: stt.load_spec("task.toml")
    >>> spec.name, spec.dimension, spec.prescribed_time
    ('omnirobot-s1', 3, 9.0)
    >>> stt.load_spec("no-such-case")                          # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stt_codegen.errors.SpecError: no bundled case and no file named 'no-such-case' (bundled: ...)
    """
    if not isinstance(spec, (str, os.PathLike)):
        hint = "; for a dict use Spec.from_dict" if isinstance(spec, Mapping) else ""
        raise TypeError(f"load_spec(): parameter 'spec' must be a bundled case name or a "
                        f"path, not {type(spec).__name__}{hint}")
    data, folder = file_or_bundled(str(spec), bundled_cases(), bundled_spec_bytes, "case")
    return with_folder(parse_spec(data), folder)


def file_or_bundled(text: str, bundled: list[str], read: Callable[[str], bytes],
                    kind: str) -> tuple[bytes, Path]:
    """The bytes a bundled name or a file path names, and the folder its files are in.

    Parameters
    ----------
    text : str
        A name of ``bundled`` (when no such file exists) or a path.
    bundled : list of str
        The bundled names.
    read : callable
        The bytes of a bundled name.
    kind : str
        What is bundled, in the message (``"case"``, ``"fleet"``).

    Returns
    -------
    data : bytes
    folder : pathlib.Path
        The bundled folder, or the file's.

    Raises
    ------
    SpecError
        Field ``""``: no such name or file, or it cannot be read.
    """
    if text in bundled and not Path(text).exists():
        return read(text), bundled_folder()
    path = Path(text)
    try:
        return path.read_bytes(), path.resolve().parent
    except FileNotFoundError:
        raise SpecError("", f"no bundled {kind} and no file named {text!r} "
                            f"(bundled: {', '.join(bundled)})") from None
    except OSError as exc:
        raise SpecError("", f"cannot read {text!r}: {exc.strerror or exc}") from None


def parse_spec(data: bytes | str) -> Spec:
    """Validate the text of a spec file; see :func:`load_spec`.

    Parameters
    ----------
    data : bytes or str
        The TOML text of a spec file (``bytes`` must be UTF-8).

    Returns
    -------
    Spec
        The validated spec; its hash is the SHA-256 of the UTF-8 text.

    Raises
    ------
    SpecError
        Text that is not UTF-8 or not TOML (field ``""``), or a field that fails validation
        (the error names the field and the reason).
    """
    raw = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    spec = _validate(toml_document(raw))
    warn_units(spec)
    return _replace_hash(spec, hashlib.sha256(raw).hexdigest())


def toml_document(raw: bytes) -> dict[str, Any]:
    """The tables of a TOML file's bytes, as :mod:`tomllib` reads them.

    Parameters
    ----------
    raw : bytes
        The file's bytes (UTF-8).

    Returns
    -------
    dict

    Raises
    ------
    SpecError
        Field ``""``: not UTF-8, not TOML, or nested too deeply.
    """
    try:
        return tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SpecError("", f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError("", f"malformed TOML: {exc}") from None
    except RecursionError:
        raise SpecError("", "malformed TOML: nested too deeply") from None


def _as_document(value: Any) -> Any:
    """A Python value as TOML would read it: mappings as dicts, tuples and numpy arrays as
    lists, numpy scalars as Python numbers."""
    if isinstance(value, Mapping):
        return {k: _as_document(v) for k, v in value.items()}
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        value = value.tolist()      # an array to nested lists, a scalar to int/float/bool
    if isinstance(value, (list, tuple)):
        return [_as_document(v) for v in value]
    return value


def _replace_hash(spec: Spec, digest: str) -> Spec:
    from dataclasses import replace
    return replace(spec, source_hash=digest)


# --------------------------------------------------------------------------- validation
# Only rules that relate fields to each other: the schema has checked every key, type,
# sign and enum (spec/schema.py), and given the defaults.


def _any_target(raw: dict, doc: Any) -> Spec:
    """A spec with ``[target] any_of``: one spec per target box (an obstacle meeting a box
    drops it), the first kept one carrying them all (``Spec.target_any_of``)."""
    given = [k for k in ("lower", "upper", "center", "half_width")
             if getattr(doc.target, k) is not None]
    if given:
        raise SpecError("target.any_of", f"give either any_of or {'/'.join(given)}, not "
                        "both (each target box takes its own default centre and half-width)")
    kept, dropped = [], []
    for q, box in enumerate(doc.target.any_of):
        variant = {**raw, "target": {"lower": box.lower, "upper": box.upper}}
        try:
            kept.append((q, _validate(variant)))
        except SpecError as exc:
            if exc.reason.startswith("meets the target set"):
                dropped.append((q, exc.field))
                continue
            field_name = exc.field.replace("target", f"target.any_of[{q}]", 1) \
                if exc.field.startswith("target") else exc.field
            raise SpecError(field_name, exc.reason) from None
    if not kept:
        raise SpecError("target.any_of", "every box meets an obstacle (" + ", ".join(
            f"any_of[{q}]: {name}" for q, name in dropped) + ")")
    return replace(kept[0][1], target_any_of=tuple(kept), target_dropped=tuple(dropped))


def _until_tasks(doc: Any) -> Any:
    """``doc`` with each obstacle's ``active_until = "Tk"`` given ``active = [0, t1]``, ``t1``
    the end of task ``Tk``'s window: a run that meets the task has met it by then, so the box
    exists at most that long; the moving obstacle keeps ``Tk`` (``MovingObstacle.until``),
    and the certificate and the run judge end it when the task is met (docs/tasks.md,
    "Obstacles until a task")."""
    if not any(getattr(o, "active_until", None) is not None for o in doc.obstacles):
        return doc
    tasks = doc.tasks or []
    obstacles = []
    for j, table in enumerate(doc.obstacles):
        label = getattr(table, "active_until", None)
        if label is None:
            obstacles.append(table)
            continue
        name = f"obstacles[{j}].active_until"
        if table.active is not None:
            raise SpecError(name, "give either active or active_until, not both")
        k = int(label[1:]) - 1
        if k >= len(tasks):
            raise SpecError(name, f"no task {label} (the spec has {len(tasks)} task(s))")
        if tasks[k].kind != "reach":
            raise SpecError(name, f"task {label} is a {tasks[k].kind} task; an obstacle "
                            "lasts until a reach task is met")
        obstacles.append(table.model_copy(update={"active": [0.0, float(tasks[k].window[1])]}))
    return doc.model_copy(update={"obstacles": obstacles})


def _validate(raw: dict) -> Spec:
    doc = check_document(raw)
    if doc.target.any_of is not None:
        return _any_target(raw, doc)
    for key in ("lower", "upper"):
        if getattr(doc.target, key) is None:
            raise SpecError(f"target.{key}", "missing (give lower and upper, or any_of)")
    state_space = _box(doc.state_space, "state_space", None)
    n = len(state_space.lower)

    initial_set = _box(doc.initial, "initial", n)
    if not state_space.contains_box(initial_set):
        raise SpecError("initial", "the initial set is not inside the state space")
    x0 = (_vector(doc.initial.state, "initial.state", n) if doc.initial.state is not None
          else initial_set.center)
    _interior(x0, initial_set, "initial.state", "initial set")
    d0 = _half_width(doc.initial.half_width, "initial", x0, initial_set, "initial set")

    target_set = _box(doc.target, "target", n)
    if not state_space.contains_box(target_set):
        raise SpecError("target", "the target set is not inside the state space")
    eta = (_vector(doc.target.center, "target.center", n) if doc.target.center is not None
           else target_set.center)
    _interior(eta, target_set, "target.center", "target set")
    d_t = _half_width(doc.target.half_width, "target", eta, target_set, "target set")

    doc = _until_tasks(doc)
    if doc.sensing is not None and doc.tasks:
        raise SpecError("sensing", "replanning around sensed obstacles does not take "
                                   "[[tasks]]: a replanned tube heads for the target only "
                                   "(docs/sensing.md)")
    unsafe_sets = tuple(_unsafe_set(table, f"obstacles[{j}]", state_space, j)
                        for j, table in enumerate(doc.obstacles) if not is_moving(table))
    moving = tuple(_moving(table, f"obstacles[{j}]", j, state_space, initial_set, target_set,
                           doc.prescribed_time)
                   for j, table in enumerate(doc.obstacles) if is_moving(table))
    linear = _linear_plant(doc.plant, n)      # also refuses another model's [plant] keys
    drive = _differential_drive(doc)
    # the variant's terms: the point the robot's radius is about, the disturbance, the
    # [plant] data the assumptions are checked on
    offset, amplitude, plant_data = variant_of(plant_entry(doc.plant.model)).entry(
        "plant_terms")(doc, linear, drive)
    robot = _robot(doc, state_space, initial_set, target_set, unsafe_sets, moving, offset)
    if robot is not None:        # the problem of the reference point: sets inflated, X shrunk
        state_space, unsafe_sets, moving = _robot_problem(robot, state_space, initial_set,
                                                          target_set, doc.prescribed_time,
                                                          (x0, eta))
    obstacles = _cover_all(unsafe_sets, state_space, initial_set, target_set)
    if robot is not None:
        obstacles = _clipped(obstacles, state_space)

    model = doc.plant.model
    mismatch = dimension_mismatch(model, n)
    if mismatch:
        raise SpecError("plant.model", mismatch)
    second_order = _second_order(doc, n)
    if second_order is not None:
        model = "single-integrator"     # the position stage x1_dot = x2 (Spec.plant_model)
    tube = TubeParameters(**doc.tube.model_dump())
    return Spec(name=doc.name, prescribed_time=doc.prescribed_time, state_space=state_space,
                initial_set=initial_set, initial_state=x0, initial_half_width=d0,
                target_set=target_set, target_center=eta, target_half_width=d_t,
                obstacles=obstacles, unsafe_sets=unsafe_sets, tube=tube,
                gain=doc.controller.gain, rate_hz=doc.controller.rate_hz,
                plant_model=model, disturbance_amplitude=amplitude,
                linear_plant=linear,
                assumptions=_assumptions(doc.assumptions if second_order is None
                                         else AssumptionsTable(), n, amplitude, model,
                                         state_space, plant_data),
                input_bound=_input_bound(doc.actuator, doc.plant.model, n,
                                         doc.plant.actuators),
                reverse_speed=_reverse_speed(doc.actuator, doc.plant.model,
                                             doc.sensing is not None),
                second_order=second_order,
                target_half_width_given=doc.target.half_width is not None,
                tasks=build_tasks(doc.tasks or (), n, doc.prescribed_time,
                                  (state_space.lower, state_space.upper),
                                  [(b.lower, b.upper, o.source) for o, b in
                                   zip(obstacles, (o.box(state_space) for o in obstacles))],
                                  doc.tube.method),
                task_order=doc.task_order.order if doc.task_order is not None else "listed",
                moving_obstacles=moving, robot=robot,
                mujoco=_mujoco(doc.plant, n),
                sensing=sensing_from_table(
                    doc.sensing, robot.dims if robot is not None else robot_dims(None, n),
                    variant_of(plant_entry(doc.plant.model)),
                    robot.radius if robot is not None else 0.0),
                drive=drive, **_timing(doc.controller, doc.plant.model))


def _timing(table: ControllerTable, model: str) -> dict[str, float | bool]:
    """``[controller] delay``, ``jitter`` and ``compensate_delay``, checked against the period
    and the variant (docs/sampled-data.md, "Computation delay and jitter", "Compensating a
    delay")."""
    delay, jitter = table.delay, table.jitter
    period = 1.0 / table.rate_hz
    variant = variant_of(plant_entry(model))
    if table.compensate_delay:
        if not variant.predicts_delay:
            raise SpecError("controller.compensate_delay",
                            f"is not available for {variant.plant_words} (the {variant.name} "
                            "variant): its certificate covers the plain law with a delay up "
                            "to its limit (verify reports it)")
        if not delay > 0.0:
            raise SpecError("controller.compensate_delay", "needs controller.delay > 0: the "
                                                           "delay it predicts over")
        if jitter > 0.0:
            raise SpecError("controller.jitter", "must be 0 with controller.compensate_delay "
                                                 "(the prediction is over exactly "
                                                 "controller.delay)")
        if delay > period:
            raise SpecError("controller.delay", f"= {number_text(delay)} s exceeds the period "
                                                f"1 / rate_hz = {number_text(period)} s (the "
                                                "prediction covers a delay up to one period)")
        return {"delay": float(delay), "jitter": 0.0, "compensate_delay": True}
    if delay + 2.0 * jitter > period:
        field_name = "controller.delay" if delay > 0.0 else "controller.jitter"
        raise SpecError(field_name, f"delay + 2 jitter = {number_text(delay + 2.0 * jitter)} s "
                                    f"exceeds the period 1 / rate_hz = {number_text(period)} s "
                                    "(the proof needs each command to act within the period "
                                    "it was computed for" + ("; controller.compensate_delay "
                                    "covers a delay up to one period)" if
                                    variant.predicts_delay else ")"))
    return {"delay": float(delay), "jitter": float(jitter)}


def _vector(value: list[float], name: str, length: int | None) -> tuple[float, ...]:
    """A validated list of numbers, of ``length`` entries (one per state dimension)."""
    if length is not None and len(value) != length:
        raise SpecError(name, f"must have {length} entries (one per state dimension), "
                              f"got {len(value)}")
    return tuple(value)


def _box(table: BoxTable | BoxObstacle, name: str, length: int | None) -> Box:
    lower = _vector(table.lower, f"{name}.lower", length)
    upper = _vector(table.upper, f"{name}.upper", len(lower))
    for k, (a, b) in enumerate(zip(lower, upper)):
        if a > b:
            raise SpecError(f"{name}.lower", f"lower[{k}] = {a!r} exceeds upper[{k}] = {b!r}")
        if a == b:
            raise SpecError(f"{name}.lower", f"empty box: lower[{k}] = upper[{k}] = {a!r}")
    return Box(lower, upper)


def _interior(point: tuple[float, ...], box: Box, name: str, label: str) -> None:
    for k, (v, a, b) in enumerate(zip(point, box.lower, box.upper)):
        if not a < v < b:
            raise SpecError(name, f"entry {k} = {v!r} is not in the interior ({a!r}, {b!r}) "
                                  f"of the {label}")


def _half_width(value: list[float] | None, name: str, center: tuple[float, ...], box: Box,
                label: str) -> tuple[float, ...]:
    room = tuple(min(c - a, b - c) for c, a, b in zip(center, box.lower, box.upper))
    if value is None:
        return tuple(DEFAULT_HALF_WIDTH_FRACTION * r for r in room)
    width = _vector(value, f"{name}.half_width", len(center))
    for k, (d, r) in enumerate(zip(width, room)):
        if d <= 0:
            raise SpecError(f"{name}.half_width", f"entry {k} must be positive, got {d!r}")
        if d > r + 1e-12:
            raise SpecError(f"{name}.half_width",
                            f"entry {k} = {d!r} puts the box outside the {label} "
                            f"(at most {number_text(r)} around the point)")
    return width


def _matrix(rows: list[list[float]], name: str, n: int) -> tuple[tuple[float, ...], ...]:
    """An n x n matrix given as a list of n rows of n numbers."""
    if len(rows) != n:
        raise SpecError(name, f"must have {n} rows (one per state dimension), got {len(rows)}")
    return tuple(_vector(row, f"{name}[{k}]", n) for k, row in enumerate(rows))


def _linear_plant(table: PlantTable, n: int) -> LinearPlant | None:
    """The matrices ``a``, ``g``, ``c`` of ``[plant]``; only the ``linear`` model takes them
    (and only the ``mujoco`` model its simulator's keys)."""
    owners = {**{key: (owner,) for key, owner in (*MODEL_KEYS.items(), *PARAMETER_KEYS.items())},
              **SIMULATOR_KEYS}
    for key, models in owners.items():
        if getattr(table, key) is not None and table.model not in models:
            names = (models[0] if len(models) == 1
                     else f"{', '.join(models[:-1])} and {models[-1]}")
            raise SpecError(f"plant.{key}", f"only the {names} model"
                                            f"{'s' if len(models) > 1 else ''} take"
                                            f"{'' if len(models) > 1 else 's'} {key} "
                                            f"(plant.model is {table.model!r})")
    if table.model not in MODEL_KEYS.values():
        return None
    identity = tuple(tuple(1.0 if i == j else 0.0 for j in range(n)) for i in range(n))
    zero = tuple(tuple(0.0 for _ in range(n)) for _ in range(n))
    a = _matrix(table.a, "plant.a", n) if table.a is not None else zero
    g = _matrix(table.g, "plant.g", n) if table.g is not None else identity
    c = _vector(table.c, "plant.c", n) if table.c is not None else tuple(0.0 for _ in range(n))
    return LinearPlant(a, g, c)


#: The ``[assumptions]`` keys a second-order model takes (those of its second stage).
SECOND_ORDER_ASSUMPTIONS = ("input_gain", "drift_bound")


def _second_order(doc: Any, n: int) -> SecondOrder | None:
    """The second-order plant of a spec (``plant.model`` second order), or ``None``; the
    second-order keys (:data:`~.second_order.SECOND_ORDER_ONLY`) refused on a first-order
    model, the first-order ``[assumptions]`` keys refused on a second-order one."""
    model = doc.plant.model
    given = {"plant.parameters": doc.plant.parameters, "initial.velocity": doc.initial.velocity,
             "state_space.velocity_bound": doc.state_space.velocity_bound}
    if model not in SECOND_ORDER_PLANTS:
        for field_name, value in given.items():
            if value is not None:
                raise SpecError(field_name, f"only a second-order plant.model "
                                            f"({', '.join(SECOND_ORDER_MODELS)}) takes it "
                                            f"(plant.model is {model!r})")
        return None
    table = doc.assumptions
    _require_declared(model, table.model_fields_set)
    for key in AssumptionsTable.model_fields:
        if key in table.model_fields_set and key not in SECOND_ORDER_ASSUMPTIONS:
            raise SpecError(f"assumptions.{key}",
                            f"a second-order plant.model ({model!r}) takes only "
                            f"{' and '.join(SECOND_ORDER_ASSUMPTIONS)} in [assumptions] "
                            "(the bounds of its second stage)")
    declared = table.model_fields_set
    return parse_second_order(model, n, doc.plant.parameters, doc.initial.velocity,
                              doc.state_space.velocity_bound,
                              table.input_gain if "input_gain" in declared else None,
                              table.drift_bound if "drift_bound" in declared else None,
                              (doc.state_space.lower, doc.state_space.upper))


def _assumptions(table: AssumptionsTable, n: int, amplitude: float, model: str,
                 state_space: Box, linear: LinearPlant | None) -> Assumptions:
    """``[assumptions]`` combined with what the plant model implies over the state space
    (:func:`~.assumptions.combine_assumptions`)."""
    declared = {key: getattr(table, key) for key in AssumptionsTable.model_fields
                if key in table.model_fields_set}
    if isinstance(declared.get("drift_bound"), list):
        raise SpecError("assumptions.drift_bound", "one number per position only for a "
                        "second-order plant.model; a first-order plant's drift_bound bounds "
                        "|f(x)|, one number")
    if _require_declared(model, declared):     # no equations: the declared bounds as they are
        bounds = declared_bounds(model, declared, n)
    else:
        bounds = model_bounds(model, state_space.lower, state_space.upper, linear)
    return combine_assumptions(bounds, declared, n, amplitude)


def _require_declared(model: str, declared) -> bool:
    """Whether ``model`` has no equations (``declared_bounds``); then ``input_gain`` and
    ``drift_bound`` must be among the ``declared`` ``[assumptions]`` keys (``SpecError``
    naming the missing one)."""
    if not plant_entry(model).declared_bounds:
        return False
    for key in ("input_gain", "drift_bound"):
        if key not in declared:
            raise SpecError(f"assumptions.{key}", f"required for plant.model = {model!r}: "
                            "the toolkit has no equations of this plant, so the design and "
                            "verify use the declared bounds (and cannot check them)")
    return True


def _input_bound(table: ActuatorTable | None, model: str, n: int,
                 actuators: list[str] | None = None) -> tuple[float, ...] | None:
    """``[actuator] input_bound``: one positive number per input of ``plant.model`` (for a
    second-order model its physical inputs, forces or torques, in the model's unit; for a
    MuJoCo plant its ``actuators``, named so in the message)."""
    if table is None:
        return None
    plant = plant_entry(model)
    count = plant.input_count(n)
    names = actuators if actuators is not None else plant.input_names(n)
    unit = f" in {plant.input_unit}" if plant.input_unit else ""
    if len(table.input_bound) != count:
        raise SpecError("actuator.input_bound",
                        f"must have {count} entries (one per input of the {model} plant: "
                        f"{', '.join(names)}{unit}), got {len(table.input_bound)}")
    return tuple(float(v) for v in table.input_bound)


def _reverse_speed(table: ActuatorTable | None, model: str, sensing: bool) -> float | None:
    """``[actuator] reverse_speed``: a differential-drive base's, at most its ``v_max``; not
    with ``[sensing]``, whose replanned tubes start from a heading the proof does not
    enclose."""
    if table is None or table.reverse_speed is None:
        return None
    if sensing:
        raise SpecError("actuator.reverse_speed", "is not available with [sensing]: a tube "
                        "replanned at run time starts from a heading the proof of backing up "
                        "does not enclose")
    if not variant_of(plant_entry(model)).turns:
        raise SpecError("actuator.reverse_speed", f"is for a differential-drive base (the "
                        f"speed it may back up at); plant.model is {model!r}, whose "
                        "input_bound already bounds each input both ways")
    v_max = table.input_bound[0]
    if table.reverse_speed > v_max:
        raise SpecError("actuator.reverse_speed", f"= {number_text(table.reverse_speed)} m/s "
                        f"exceeds input_bound's v_max = {number_text(v_max)} m/s, which "
                        "bounds |v| both ways")
    return float(table.reverse_speed)


def _dims(given: list[int] | None, name: str, m: int, n: int,
          coordinates: str) -> tuple[int, ...]:
    if m > n:
        raise SpecError(f"{name}.{coordinates}", f"{m} entries for a {n}-dimensional "
                                                 "state space")
    if given is None:
        return tuple(range(m))
    if len(given) != m:
        raise SpecError(f"{name}.dims", f"must be an array of {m} dimension indices")
    for d in given:
        if not d < n:
            raise SpecError(f"{name}.dims", f"{d!r} is not a dimension index in 0..{n - 1}")
    if len(set(given)) != m:
        raise SpecError(f"{name}.dims", "repeats a dimension")
    return tuple(given)


def _inside(lower, upper, dims, state_space: Box, name: str) -> None:
    for k, i in enumerate(dims):
        if lower[k] < state_space.lower[i] or upper[k] > state_space.upper[i]:
            raise SpecError(name, f"dimension {i} of the obstacle [{lower[k]!r}, {upper[k]!r}] "
                                  "is not inside the state space")


def _moving(table: BoxObstacle, name: str, j: int, state_space: Box, initial_set: Box,
            target_set: Box, prescribed_time: float) -> MovingObstacle:
    """A box with ``active``/``velocity``/``path`` (:mod:`.motion`); it may leave ``X``."""
    box = _box(table, name, None)
    dims = _dims(table.dims, name, len(box.lower), len(state_space.lower), "lower")
    obstacle = moving_obstacle(table, name, j, dims, box.lower, box.upper,
                               space=(tuple(state_space.lower[i] for i in dims),
                                      tuple(state_space.upper[i] for i in dims)))
    check_moving(obstacle, name, initial_set, target_set, prescribed_time)
    return obstacle


def _unsafe_set(table: BoxObstacle | BallObstacle | PolytopeObstacle, name: str,
                state_space: Box, source: int | None = None) -> UnsafeSet:
    from .shapes import Ball, make_polytope
    n = len(state_space.lower)
    if isinstance(table, BoxObstacle):
        box = _box(table, name, None)
        dims = _dims(table.dims, name, len(box.lower), n, "lower")
        _inside(box.lower, box.upper, dims, state_space, name)
        return UnsafeSet("box", dims, box, source=source)
    if isinstance(table, PolytopeObstacle):
        m = len(table.vertices[0])
        points = [_vector(v, f"{name}.vertices[{k}]", m) for k, v in enumerate(table.vertices)]
        dims = _dims(table.dims, name, m, n, "vertices")
        shape: Any = make_polytope([list(p) for p in points], name)
        kind = "polytope"
    else:
        dims = _dims(table.dims, name, len(table.center), n, "center")
        shape, kind = Ball(tuple(table.center), table.radius), "ball"
    _inside(shape.lower, shape.upper, dims, state_space, name)
    return UnsafeSet(kind, dims, shape, table.tolerance, source)


def _cover_all(unsafe_sets: tuple[UnsafeSet, ...], state_space: Box, initial_set: Box,
               target_set: Box) -> tuple[Obstacle, ...]:
    """Check each set against ``X0`` and ``T`` and cover balls and polytopes by boxes."""
    import numpy as np

    from .covering import cover
    obstacles = []
    labels = ("initial", "target")
    for k, unsafe in enumerate(unsafe_sets):
        j = k if unsafe.source is None else unsafe.source
        name = f"obstacles[{j}]"
        dims = list(unsafe.dims)
        forbidden = [(np.array(b.lower)[dims], np.array(b.upper)[dims])
                     for b in (initial_set, target_set)]
        for (lo, hi), label, box in zip(forbidden, labels, (initial_set, target_set)):
            if unsafe.kind == "box":
                meets = _embed(unsafe.shape.lower, unsafe.shape.upper, unsafe.dims,
                               state_space).meets(box)
            else:
                meets = unsafe.shape.meets_box(lo, hi)
            if meets:
                raise SpecError(name, f"meets the {label} set")
        if unsafe.kind == "box":
            obstacles.append(Obstacle(unsafe.shape.lower, unsafe.shape.upper, unsafe.dims, j))
            continue
        for lo, hi in cover(unsafe.shape, unsafe.tolerance, forbidden, name,
                            [f"the {label} set" for label in labels]):
            obstacles.append(Obstacle(tuple(float(v) for v in lo), tuple(float(v) for v in hi),
                                      unsafe.dims, j))
    return tuple(obstacles)


# --------------------------------------------------------------------------- [robot]


def _robot(doc: Any, state_space: Box, initial_set: Box, target_set: Box,
           unsafe_sets: tuple[UnsafeSet, ...], moving: tuple[MovingObstacle, ...],
           offset: float = 0.0) -> Robot | None:
    """``[robot]`` and the sets as given, or ``None`` without the table and ``offset``.

    ``offset``: how far the reference point may lie from the body's centre (a
    differential drive's axle offset), added to the radius: the body's disc of radius
    ``r`` around the axle lies in the disc of radius ``r + offset`` around the point."""
    if doc.robot is None and offset == 0.0:
        return None
    dims = robot_dims(None if doc.robot is None else doc.robot.dims, len(state_space.lower))
    radius = (0.0 if doc.robot is None else float(doc.robot.radius)) + offset
    return Robot(radius, dims, state_space, unsafe_sets, moving, offset)


def law13_plant_terms(doc: Any, linear: LinearPlant | None,
                      drive: DifferentialDrive | None) -> tuple[float, float, Any]:
    """The plant terms of law (13) on the plant's state (first order, and the cascade's
    position stage): the variant's role ``plant_terms`` (:mod:`.variants`).

    Parameters
    ----------
    doc : SpecDocument
        The validated document.
    linear : LinearPlant or None
        The ``linear`` model's matrices.
    drive : DifferentialDrive or None
        ``None`` (no base).

    Returns
    -------
    offset : float
        0: the robot's radius is about the state itself, m.
    amplitude : float
        ``plant.disturbance_amplitude``.
    plant_data : LinearPlant or None
        The ``[plant]`` data the ``[assumptions]`` are checked on.
    """
    return 0.0, doc.plant.disturbance_amplitude, linear


def look_ahead_plant_terms(doc: Any, linear: LinearPlant | None,
                           drive: DifferentialDrive | None) -> tuple[float, float, Any]:
    """The plant terms of a differential-drive base: the variant's role ``plant_terms``
    (:mod:`.variants`).

    Parameters
    ----------
    doc : SpecDocument
        The validated document.
    linear : LinearPlant or None
        ``None`` (not a linear model).
    drive : DifferentialDrive
        The base.

    Returns
    -------
    offset : float
        The axle offset: the robot's radius is about the axle, m.
    amplitude : float
        0: a differential drive's disturbance is its slip (``Spec.drive``).
    plant_data : DifferentialDrive
        The base, the ``[plant]`` data the ``[assumptions]`` are checked on.
    """
    return drive.axle_offset, 0.0, drive


def _differential_drive(doc: Any) -> DifferentialDrive | None:
    """The base of ``plant.model = "differential-drive"`` (its ``[plant]`` parameters and
    ``initial.heading``), or ``None`` for another model (which may not take
    ``initial.heading``); the required keys and the unused ``disturbance_amplitude``
    checked."""
    table = doc.plant
    if not plant_entry(table.model).parameter_keys:
        if doc.initial.heading is not None:
            raise SpecError("initial.heading", f"only plant.model = \"differential-drive\" "
                                               f"takes it (plant.model is {table.model!r})")
        return None
    for key in ("axle_offset", "track_width") + (("wheel_radius",) if table.mjcf else ()):
        if getattr(table, key) is None:
            raise SpecError(f"plant.{key}", f"required for plant.model = {table.model!r}"
                            + (" on MuJoCo (plant.mjcf)" if key == "wheel_radius" else ""))
    if "disturbance_amplitude" in table.model_fields_set:
        raise SpecError("plant.disturbance_amplitude", f"plant.model = {table.model!r} "
                        "takes its disturbance as plant.slip (forward, lateral, turn)")
    heading = float(doc.initial.heading or 0.0)
    if abs(heading) > math.pi:        # radians in [-pi, pi]: 90 is degrees by mistake
        if abs(heading) <= 2.0 * math.pi:
            hint = f"; the same heading is {number_text(_wrapped(heading), 6)}"
        elif abs(heading) <= 360.0:
            hint = (f"; if {number_text(heading)} is in degrees, it is "
                    f"{number_text(_wrapped(math.radians(heading)), 6)} rad")
        else:
            hint = ""
        raise SpecError("initial.heading", f"{number_text(heading)} is beyond pi in magnitude: "
                        f"the heading is in radians, within [-pi, pi]{hint}")
    return DifferentialDrive(
        float(table.axle_offset), float(table.track_width),
        tuple(float(v) for v in table.wheel_radius_error or (0.0, 0.0)),
        tuple(float(v) for v in table.slip or (0.0, 0.0, 0.0)),
        heading,
        None if table.wheel_radius is None else float(table.wheel_radius))


def _wrapped(angle: float) -> float:
    """``angle`` (rad) moved by whole turns into ``[-pi, pi)``."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def _mujoco(table: Any, n: int) -> MujocoModel | None:
    """The MuJoCo model of ``[plant]``: always for a model without equations, for a model
    with equations (the differential drive) when ``plant.mjcf`` is given; one joint per
    state of the plant (the differential drive's ``x, y, theta``)."""
    entry = plant_entry(table.model)
    if not entry.simulator_keys or (not entry.declared_bounds and table.mjcf is None):
        return None
    return mujoco_model(table, entry.plant_states or n, entry.input_count(n))


def _robot_size(robot: Robot) -> str:
    """The robot's radius in words, with the axle offset it includes."""
    if robot.offset:     # a differential drive: its body's radius plus the axle offset
        return (f"radius {number_text(robot.radius)} (robot.radius "
                f"{number_text(robot.radius - robot.offset)} around the axle + "
                f"plant.axle_offset {number_text(robot.offset)} to the look-ahead point)")
    return f"radius {number_text(robot.radius)}"


def _radius_field(robot: Robot, fits: Any) -> str:
    """The field to change when the robot is too large: ``plant.axle_offset`` when the
    body alone (``fits(radius - offset)``) would fit, else ``robot.radius``."""
    if robot.offset and fits(robot.radius - robot.offset):
        return "plant.axle_offset"
    return "robot.radius"


def _grown(unsafe: UnsafeSet, dims: tuple[int, ...], r: float, j: int) -> UnsafeSet:
    """``unsafe`` inflated by ``r`` on the robot's ``dims``."""
    if unsafe.kind == "box":
        return replace(unsafe, shape=Box(*inflate_bounds(unsafe.shape.lower, unsafe.shape.upper,
                                                         unsafe.dims, dims, r)))
    if unsafe.kind == "ball":
        return replace(unsafe, shape=inflate_ball(unsafe.shape, unsafe.dims, dims, r))
    from .shapes import make_polytope
    return replace(unsafe, shape=make_polytope(inflate_polytope(
        unsafe.shape.vertices, unsafe.dims, dims, r), f"obstacles[{j}]"))


def _meets(grown: UnsafeSet, box: Box, space: Box) -> bool:
    """Whether the (inflated) obstacle meets ``box`` (touching counts)."""
    import numpy as np

    if grown.kind == "box":
        return _embed(grown.shape.lower, grown.shape.upper, grown.dims, space).meets(box)
    return grown.shape.meets_box(np.array(box.lower)[list(grown.dims)],
                                 np.array(box.upper)[list(grown.dims)])


def _robot_problem(robot: Robot, state_space: Box, initial_set: Box, target_set: Box,
                   prescribed_time: float, points: tuple[tuple[float, ...], ...]
                   ) -> tuple[Box, tuple[UnsafeSet, ...], tuple[MovingObstacle, ...]]:
    """The state space shrunk and the obstacles inflated by the robot's radius
    (:mod:`.robot`), checked against the initial and target sets of the reference point.

    The error names the field to change: the radius (``robot.radius``, or
    ``plant.axle_offset`` when the body alone would fit) when the robot does not fit in
    the state space, or not at the set's own point (``points``: ``initial.state`` and the
    target's centre) beside an obstacle; the set (``initial``, ``target``) when the robot
    fits there and only the set comes too close to the boundary or to an obstacle.
    """
    r, dims = robot.radius, robot.dims
    size = _robot_size(robot)

    def shrunk_by(radius: float) -> Box | None:
        try:
            return Box(*shrink_bounds(state_space.lower, state_space.upper, dims, radius))
        except SpecError:
            return None

    def room_for(box: Box, radius: float) -> bool:
        """Whether ``box`` fits somewhere in the state space shrunk by ``radius``."""
        space = shrunk_by(radius)
        return space is not None and all(b - a <= hi - lo for a, b, lo, hi in zip(
            box.lower, box.upper, space.lower, space.upper))

    shrunk = shrunk_by(r)
    if shrunk is None:
        d = min(dims, key=lambda i: state_space.upper[i] - state_space.lower[i])
        raise SpecError(_radius_field(robot, lambda q: shrunk_by(q) is not None),
                        f"the robot of {size} no longer fits in the state space: dimension "
                        f"{d} is [{number_text(state_space.lower[d])}, "
                        f"{number_text(state_space.upper[d])}]")
    sets = (("initial", "initial set", initial_set, points[0]),
            ("target", "target set", target_set, points[1]))
    for name, label, box, _ in sets:
        if not shrunk.contains_box(box):
            # the set fits elsewhere: move it; else the radius is too large for it
            field = name if room_for(box, r) else _radius_field(
                robot, lambda q: room_for(box, q))
            raise SpecError(field, f"the {label} comes within the robot's {size} of the "
                                   "state space's boundary: it must lie inside the state space "
                                   f"shrunk by the radius, {_box_text(shrunk)}"
                                   + ("" if field == name else f", which it does not fit in"))
    inflated = []
    for k, unsafe in enumerate(robot.unsafe_sets):
        j = k if unsafe.source is None else unsafe.source
        grown = _grown(unsafe, dims, r, j)
        for name, label, box, point in sets:
            if _meets(grown, box, shrunk):
                at = Box(tuple(point), tuple(point))
                if not _meets(grown, at, shrunk):
                    field = name       # clear at its own point: move or shrink the set
                else:
                    field = _radius_field(robot, lambda q: not _meets(
                        _grown(unsafe, dims, q, j), at, shrunk))
                raise SpecError(field, (
                    f"obstacles[{j}] inflated by the robot's {size} meets the {label}: move "
                    f"the set (or shrink it) away from obstacles[{j}]" if field == name else
                    f"the robot of {size} no longer fits in the {label}: obstacles[{j}] "
                    f"inflated by the radius covers even its point {_point_text(point)} (a "
                    f"smaller radius, or the set farther from obstacles[{j}])"))
        inflated.append(grown)
    moving = []
    for obstacle in robot.moving_obstacles:
        grown = inflate_moving(obstacle, dims, r)
        try:
            check_moving(grown, f"obstacles[{obstacle.source}]", initial_set, target_set,
                         prescribed_time)
        except SpecError as exc:
            label = "initial set" if "initial" in exc.reason else "target set"
            raise SpecError(_radius_field(robot, lambda q: q == 0.0),
                            f"the robot of {size} no longer fits in the {label}: {exc.field} "
                            f"inflated by the radius {exc.reason}") from None
        moving.append(grown)
    return shrunk, tuple(inflated), tuple(moving)


def _point_text(point: tuple[float, ...]) -> str:
    return "[" + ", ".join(number_text(v) for v in point) + "]"


def _box_text(box: Box) -> str:
    return " x ".join(f"[{number_text(a)}, {number_text(b)}]"
                      for a, b in zip(box.lower, box.upper))


def _clipped(obstacles: tuple[Obstacle, ...], state_space: Box) -> tuple[Obstacle, ...]:
    """The obstacle boxes cut to the (shrunk) state space, those outside it dropped: the
    reference point never leaves it, so the parts beyond cannot meet the tube."""
    kept = []
    for o in obstacles:
        lo = tuple(max(a, state_space.lower[d]) for a, d in zip(o.lower, o.dims))
        hi = tuple(min(b, state_space.upper[d]) for b, d in zip(o.upper, o.dims))
        if all(a < b for a, b in zip(lo, hi)):
            kept.append(replace(o, lower=lo, upper=hi))
    return tuple(kept)
