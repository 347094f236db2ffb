"""The closed loop with obstacles sensed at run time (docs/sensing.md).

The loop of :func:`~.simulate.run_closed_loop` (a sampled controller, the plant held over
each period and integrated by Runge-Kutta), with obstacles the controller does not know in
advance: discs on the sensing dimensions (:class:`WalkingObstacle`), moved by a script
(a velocity or a path) or heading for the robot. At each measurement instant
``t_m = j T_u`` the obstacles with a point within ``R`` of the robot's reference point are
measured (a ball each, with its velocity as the estimate and its index as the track
number), checked against the envelope (:func:`~stt_codegen.spec.sensing.envelope_violations`)
and revealed at ``t_m + L``; the replanner (:func:`~stt_codegen.design.sensed.replan`) then
makes the next plan, which takes over at its switch instant if the state lies in its tube
then (``|e_i| <= MAX_INITIAL_ERROR`` at its ``t = 0``); else the switch is refused and the
active tube runs on. The run's verdict is :class:`~.simulate.SimulationResult`'s, with the
sensed obstacles among the obstacles, and its ``sensing`` record: every plan's event, the
spans no certificate covered, the replanner's times and the envelope's violations.

The simulated clock does not run while the replanner computes: a plan always arrives in
time. Its processor time is measured and compared with ``replan_time`` (``over_budget``);
with ``enforce_replan_time`` a plan over the budget is refused as it would be on a robot.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

import control as ct

from ..design.prediction import delay_predictor
from ..design.result import Design, require_design
from ..design.samples import check_step_budget
from ..design.search import MAX_INITIAL_ERROR
from ..design.sensed import (ReplanFailure, SensedPlan, replan, start_plan,
                             uncertified_plan)
from ..errors import SpecError
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..spec.sensing import (EnvelopeViolation, SensedObstacle, Sensing, envelope_violations,
                            on_sensing_dims)
from ..tube import reference
from ..tube.parameters import Status
from .backends import default_backend, make_controller
from .plants import check_seed, spec_plant
from .simulate import (RungeKutta, SimulationResult, Trajectory, hold_period,
                       sampling_offsets)
from .state_split import initial_state, positions

__all__ = ["PEOPLE_CASES", "PlanEvent", "SensingRecord", "WalkingObstacle", "bundled_people",
           "check_walking", "simulate_sensed"]


@dataclass(frozen=True)
class WalkingObstacle:
    """A disc (ball) obstacle of a sensed run on the sensing dimensions, unknown to the
    controller until it is measured.

    At most one of ``velocity``, ``path`` and ``pursuit_speed`` moves it; with none it
    stands still.

    Attributes
    ----------
    start : tuple of float, shape (m,)
        Its centre at ``t = 0``, state units (with ``path``: the first row's centre is
        used from ``t = 0`` until the first row's time).
    radius : float
        Positive, state units.
    velocity : tuple of float or None
        A constant velocity, state units per second.
    path : tuple of tuple of float or None
        Rows ``(t, centre...)``, times increasing: the centre moves linearly between rows
        and is held before the first and after the last.
    pursuit_speed : float or None
        Heads for the robot's reference point at this speed (the adversary), state units
        per second: each period it moves straight at the point where the robot was at
        the period's start.
    pursuit_acceleration : float or None
        With ``pursuit_speed``: the pursuer's velocity turns towards the one heading for the
        robot at ``pursuit_speed`` by at most this much per second (an adversary within an
        envelope's ``max_obstacle_acceleration``), state units per second squared;
        ``None``: at once.

    Examples
    --------
    >>> from stt_codegen.runtime.sensed import WalkingObstacle
    >>> person = WalkingObstacle((5.0, 0.5), 0.3, velocity=(0.0, 0.6))
    >>> WalkingObstacle((8.0, 3.0), 0.3, pursuit_speed=0.8).pursuit_speed
    0.8
    >>> WalkingObstacle((8.0, 3.0), 0.3, pursuit_speed=0.8, pursuit_acceleration=1.0).start
    (8.0, 3.0)
    """

    start: tuple[float, ...]
    radius: float
    velocity: tuple[float, ...] | None = None
    path: tuple[tuple[float, ...], ...] | None = None
    pursuit_speed: float | None = None
    pursuit_acceleration: float | None = None

    def __post_init__(self) -> None:
        m = len(self.start)
        given = [k for k in ("velocity", "path", "pursuit_speed") if getattr(self, k) is not None]
        if len(given) > 1:
            raise SpecError(f"WalkingObstacle.{given[1]}", f"give one of velocity, path, "
                                                           f"pursuit_speed, not {given}")
        for name, values in (("start", self.start), ("radius", (self.radius,)),
                             ("velocity", self.velocity or ())):
            if not all(math.isfinite(float(v)) for v in values):
                raise SpecError(f"WalkingObstacle.{name}", "must be finite")
        if not self.radius > 0:
            raise SpecError("WalkingObstacle.radius", f"must be positive, got {self.radius!r}")
        if self.velocity is not None and len(self.velocity) != m:
            raise SpecError("WalkingObstacle.velocity", f"must have {m} entries")
        if self.path is not None:
            times = [row[0] for row in self.path]
            if any(len(row) != m + 1 for row in self.path) or any(
                    b <= a for a, b in zip(times, times[1:])):
                raise SpecError("WalkingObstacle.path", f"rows (t, centre...) of {m + 1} "
                                                        "numbers, times increasing")
        if self.pursuit_speed is not None and not self.pursuit_speed >= 0:
            raise SpecError("WalkingObstacle.pursuit_speed", "must be non-negative")
        if self.pursuit_acceleration is not None and (
                self.pursuit_speed is None or not math.isfinite(self.pursuit_acceleration)
                or not self.pursuit_acceleration > 0):
            raise SpecError("WalkingObstacle.pursuit_acceleration", "must be positive and "
                                                                    "finite, with "
                                                                    "pursuit_speed")

    def scripted(self, t: np.ndarray) -> np.ndarray:
        """The scripted centre at times ``t`` (shape (N,)), shape (N, m); a pursuer's
        start."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        c = np.asarray(self.start, dtype=float)
        if self.velocity is not None:
            return c + t[:, None] * np.asarray(self.velocity)
        if self.path is not None:
            times, centres = self._path_columns
            return np.stack([np.interp(t, times, column) for column in centres], axis=1)
        return np.repeat(c[None], t.size, axis=0)

    @functools.cached_property
    def _path_columns(self) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """``path``'s times and centre coordinates as arrays, converted once (the closed
        loop asks for the centre at every sample)."""
        rows = np.asarray(self.path, dtype=float)
        return rows[:, 0], tuple(rows[:, 1 + k] for k in range(rows.shape[1] - 1))


#: The bundled cases with people of their own (:func:`bundled_people`).
PEOPLE_CASES = ("hall-crossing",)


def bundled_people(name: str) -> tuple[WalkingObstacle, ...]:
    """The people ``stt-codegen demo`` walks through a bundled case with ``[sensing]``:
    obstacles its design does not know, revealed only by sensing.

    Parameters
    ----------
    name : str
        A bundled case with ``[sensing]`` (``"hall-crossing"``).

    Returns
    -------
    tuple of WalkingObstacle
        For ``hall-crossing``: a person (radius 0.3 m) walking up across the hall at
        0.5 m/s from (5, 0.5), and another (0.35 m) walking down its far side from (7, 5.5)
        at 0.625 m/s from t = 2 s, both within the envelope (0.4 m, 0.8 m/s).

    Raises
    ------
    SpecError
        No bundled people for that case (field ``case``).

    Examples
    --------
    >>> from stt_codegen.runtime.sensed import bundled_people
    >>> [p.radius for p in bundled_people("hall-crossing")]
    [0.3, 0.35]
    """
    if name not in PEOPLE_CASES:
        raise SpecError("case", f"no bundled people for {name!r} (known: "
                                f"{', '.join(PEOPLE_CASES)})")
    return (WalkingObstacle((5.0, 0.5), 0.3, velocity=(0.0, 0.5)),
            WalkingObstacle((7.0, 5.5), 0.35, path=((2.0, 7.0, 5.5), (10.0, 7.0, 0.5))))


def check_walking(obstacles: Sequence[WalkingObstacle], spec: Spec,
                  field: str = "obstacles") -> None:
    """Refuse obstacles :func:`simulate_sensed` cannot run ``spec`` among, before any work.

    Parameters
    ----------
    obstacles : sequence of WalkingObstacle
        The obstacles the controller is to sense.
    spec : Spec
        The spec run among them.
    field : str
        How the obstacles are named in an error (``"walking_obstacles"`` for a file's).

    Raises
    ------
    SpecError
        The spec has no ``[sensing]`` (field ``sensing``); an entry that is not a
        :class:`WalkingObstacle` (``<field>[j]``) or whose ``start`` is not on the
        ``[sensing] dims`` (``<field>[j].start``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.runtime.sensed import WalkingObstacle, check_walking
    >>> spec = stt.load_spec("hall-crossing")
    >>> check_walking([WalkingObstacle((5.0, 0.5), 0.3)], spec)
    >>> try:
    ...     check_walking([WalkingObstacle((5.0, 0.5, 0.0), 0.3)], spec)
    ... except stt.SpecError as error:
    ...     print(error.field, "|", error.reason)
    obstacles[0].start | must have 2 entries (one per sensing dimension, dims [0, 1]), got 3
    """
    sensing = spec.sensing
    if sensing is None:
        raise SpecError("sensing", f"spec {spec.name!r} has no [sensing] table: its "
                                   "controller senses no obstacle (docs/sensing.md)")
    on_sensing_dims(obstacles, WalkingObstacle, "start", sensing, field)


@dataclass(frozen=True)
class PlanEvent:
    """One event of the replanning: a plan kept, switched in, refused or failed.

    Attributes
    ----------
    time : float
        When it happened (a sample), s.
    event : {"start", "uncertified start", "kept", "switched", "refused", "failed", "dropped"}
        ``start``: the spec's tube certified against the measurement at 0; ``kept``: the
        active tube certified again; ``switched``: a new tube took over; ``refused``: the
        state was not in the new tube at its switch; ``failed``: no certified plan from a
        measurement; ``dropped``: a plan certified for a tube that did not take over.
    tube : int
        The tube active after the event (0: the spec's).
    measured_at : float
        The measurement the plan came from, s.
    guarantee_until : float
        Until when the active tube is certified after the event, s.
    cpu_s : float
        The replanner's processor time for it, s.
    detail : str
        The reason, in words.
    """

    time: float
    event: str
    tube: int
    measured_at: float
    guarantee_until: float
    cpu_s: float = 0.0
    detail: str = ""


@dataclass
class SensingRecord:
    """What the sensing and the replanning did in a run (``SimulationResult.sensing``).

    Attributes
    ----------
    events : list of PlanEvent
        Every plan's event, in time order.
    measurements : int
        Measurements taken.
    switches, refused, failures : int
        Tubes switched in; switches refused (the state not in the new tube); measurements
        with no certified plan.
    escapes : int
        The tubes switched in that go to a temporary goal instead of the target
        (``SensedPlan.goal``), among ``switches``.
    best_effort : int
        The escapes switched in with no certificate (``SensedPlan.best_effort``: a failed
        replan's ``fallback``), among ``escapes``; the robot is uncertified while they
        run, as it is after any failure.
    shortened : int
        The plans taken (kept or switched in) that are certified over the envelope's
        ``shortest_horizon`` only (``SensedPlan.shortened``): none was certified over its
        ``horizon``.
    replans : int
        Calls of the replanner (the start included).
    replan_cpu_max, replan_cpu_p95, replan_cpu_mean : float
        Its processor time per call, s: the worst, the 95th percentile, the mean.
    over_budget : int
        Calls whose processor time exceeded ``replan_time``.
    uncertified : list of [float, float]
        Spans of the run (s) no certificate covered: no plan certified against the
        sensed obstacles then (after failures, before the first plan).
    sensed_collision : bool
        The body met a sensed obstacle (checked at every integration point).
    collision_time : float or None
        When it first did, s; ``None`` without a collision.
    collision_certified : bool
        Some instant of contact (any, not only the first) lies in a span some certificate
        covered (never, while the envelope holds: the proof of docs/sensing.md says so).
    min_sensed_clearance : float or None
        Smallest distance between the body and a sensed obstacle, state units.
    violations : list of EnvelopeViolation
        The measurements' breaks of the envelope (the monitor).
    outside_envelope : bool
        The monitor reported a violation: the run's guarantee does not hold.
    script_outside_envelope : bool
        The obstacles as scripted left the envelope (faster than ``max_obstacle_speed``,
        larger than ``max_obstacle_radius``, or with ``max_obstacle_acceleration`` a
        velocity that changed faster than it from one period to the next), whether or not
        a measurement showed it.
    guaranteed : bool
        No uncertified span and no violation: the run was covered by the proof of
        docs/sensing.md throughout.
    """

    events: list[PlanEvent] = field(default_factory=list)
    measurements: int = 0
    switches: int = 0
    escapes: int = 0
    best_effort: int = 0
    shortened: int = 0
    refused: int = 0
    failures: int = 0
    replans: int = 0
    replan_cpu_max: float = 0.0
    replan_cpu_p95: float = 0.0
    replan_cpu_mean: float = 0.0
    over_budget: int = 0
    uncertified: list[list[float]] = field(default_factory=list)
    sensed_collision: bool = False
    collision_time: float | None = None
    collision_certified: bool = False
    min_sensed_clearance: float | None = None
    violations: list[EnvelopeViolation] = field(default_factory=list)
    outside_envelope: bool = False
    script_outside_envelope: bool = False
    guaranteed: bool = False

    def summary(self) -> str:
        """The record in one line: the plans, the replanner's worst time, the guarantee."""
        cover = ("certified throughout" if not self.uncertified else "UNCERTIFIED on "
                 + ", ".join(f"[{a:.4g}, {b:.4g}] s" for a, b in self.uncertified))
        envelope = ("; OUTSIDE the envelope (" + ", ".join(sorted({v.kind for v in
                                                                   self.violations})) + ")"
                    if self.outside_envelope else "")
        best = f", {self.best_effort} best effort" if self.best_effort else ""
        escapes = f" ({self.escapes} escapes{best})" if self.escapes else ""
        shortened = (f", {self.shortened} over the shortest horizon" if self.shortened
                     else "")
        return (f"{self.measurements} measurements, {self.switches} switches{escapes}, "
                f"{self.refused} refused, {self.failures} failed{shortened}; replanning max "
                f"{self.replan_cpu_max:.3g} s CPU (p95 {self.replan_cpu_p95:.3g}); {cover}"
                + envelope)


class _World:
    """The walking obstacles' positions, advanced a period at a time."""

    def __init__(self, obstacles: Sequence[WalkingObstacle], m: int, dt: float) -> None:
        self.obstacles = list(obstacles)          # checked by check_walking
        self.radius = np.array([ob.radius for ob in self.obstacles]).reshape(-1)
        self.p = (np.array([ob.scripted([0.0])[0] for ob in self.obstacles]).reshape(-1, m))
        # the velocity before t = 0 (the first measurement's estimate): a scripted
        # obstacle's over the first period, a pursuer's 0 (it starts at rest)
        self.v = np.array([(ob.scripted([dt])[0] - ob.scripted([0.0])[0]) / dt
                           if ob.pursuit_speed is None else np.zeros(m)
                           for ob in self.obstacles]).reshape(-1, m)
        self.fastest = float(max(np.linalg.norm(self.v, axis=1), default=0.0))
        #: the largest change of an obstacle's velocity from one period to the next over
        #: the period, state units per second squared
        self.sharpest = 0.0

    def advance(self, t: float, dt: float, point: np.ndarray) -> np.ndarray:
        """Move every obstacle over ``[t, t + dt]`` (a pursuer towards ``point``); returns
        the positions at ``t + dt`` and sets the period's velocities."""
        new = self.p.copy()
        for j, ob in enumerate(self.obstacles):
            if ob.pursuit_speed is not None:
                gap = point - self.p[j]
                norm = float(np.linalg.norm(gap))
                if ob.pursuit_acceleration is not None:
                    wanted = gap / norm * ob.pursuit_speed if norm > 0 else 0.0 * gap
                    turn = wanted - self.v[j]
                    most = ob.pursuit_acceleration * dt
                    size = float(np.linalg.norm(turn))
                    velocity = self.v[j] + (turn if size <= most else turn * (most / size))
                    new[j] = self.p[j] + velocity * dt
                    continue
                step = min(ob.pursuit_speed * dt, norm)
                new[j] = self.p[j] + (gap / norm * step if norm > 0 else 0.0)
            else:
                new[j] = ob.scripted([t + dt])[0]
        v = (new - self.p) / dt
        if v.size:
            self.fastest = max(self.fastest, float(np.max(np.linalg.norm(v, axis=1))))
            self.sharpest = max(self.sharpest,
                                float(np.max(np.linalg.norm(v - self.v, axis=1))) / dt)
        self.v = v
        return new


def simulate_sensed(design: Design, obstacles: Sequence[WalkingObstacle], *,
                    backend: str | None = None, horizon: float | None = None,
                    seed: int = 0, plant: ct.NonlinearIOSystem | None = None,
                    enforce_replan_time: bool = False) -> SimulationResult:
    """Run a design with obstacles it only sees at run time, replanning its tube.

    The controller starts on the design's tube, certified against the measurement at
    ``t = 0`` (:func:`~stt_codegen.design.sensed.start_plan`); each later measurement
    ``t_m = j T_u`` (the obstacles with a point within ``R`` of the robot's reference
    point, as balls, each with its velocity and its index as track number) is checked
    against the envelope and revealed at ``t_m + L``, and
    :func:`~stt_codegen.design.sensed.replan` makes the next plan from the latest one.
    A new tube takes over at its switch instant, a sample, only if the state lies in it
    then (``|e_i| <= MAX_INITIAL_ERROR`` at its ``t = 0``, ``alpha = 0``); otherwise the
    switch is refused and the active tube runs on. The controller of each tube is the
    backend's (law (13) at the tube's own time).

    Parameters
    ----------
    design : Design
        :func:`stt_codegen.design_tube` of a spec with ``[sensing]``.
    obstacles : sequence of WalkingObstacle
        The obstacles the controller senses (on ``spec.sensing.dims``).
    backend : str, optional
        The controller's backend (:func:`~.backends.backend_names`); default
        :func:`~.backends.default_backend`, as :func:`~.simulate.simulate`'s (``"c"``: the
        spec's C with the tube as data, compiled once, each tube loaded into it,
        :class:`~.data_controller.TubeDataController`, the CasADi model's run bit for bit;
        ``"python"``: its Python module with the tube as data, generated once,
        :class:`~.data_module.TubeDataModule`; ``"casadi"``: the CasADi model;
        ``"reference"`` is ten times slower).
    horizon : float, optional
        Simulated time, s; default ``t_c``.
    seed : int
        Seed of the plant's disturbance.
    plant : control.NonlinearIOSystem, optional
        Another plant, as :func:`~.simulate.simulate` takes.
    enforce_replan_time : bool
        Refuse a plan whose processor time exceeded ``replan_time`` (default: count it in
        ``over_budget`` and use it).

    Returns
    -------
    SimulationResult
        Definition 2.1 judged with the sensed obstacles among the obstacles
        (``collision``, ``min_obstacle_clearance``), ``stayed_in_tube`` in whichever tube
        was active, ``trajectory.tube`` the active tube at each sample (0: the design's),
        and ``sensing`` (:class:`SensingRecord`).

    Raises
    ------
    TypeError
        ``design`` is not a Design.
    SpecError
        The spec has no ``[sensing]``; an obstacle that is not a :class:`WalkingObstacle`
        on the sensing dimensions; a bad horizon, seed or plant.

    Examples
    --------
    A person walks across the hall's middle; the base replans around where they may be:

    >>> import stt_codegen as stt
    >>> from stt_codegen.runtime.sensed import WalkingObstacle
    >>> design = stt.design_tube(stt.load_spec("hall-crossing"))
    >>> person = WalkingObstacle((5.0, 0.5), 0.3, velocity=(0.0, 0.5))
    >>> run = stt.simulate_sensed(design, [person])
    >>> run.collision, run.stayed_in_tube, run.sensing.outside_envelope
    (False, True, False)
    >>> run.sensing.switches > 0
    True
    """
    design = require_design(design, "simulate_sensed")
    spec = design.spec
    obstacles = list(obstacles)
    check_walking(obstacles, spec)
    sensing: Sensing = spec.sensing
    seed = check_seed(seed)
    backend = default_backend() if backend is None else backend
    variant = variant_of(spec)
    generated = ("c", "python")                  # the backends that run the data form
    if backend in generated and backend not in variant.tube_data:
        usable = [b for b in generated if b in variant.tube_data] + ["casadi", "reference"]
        raise SpecError("backend", f"{backend!r} runs the generated code with the tube as "
                                   f"data, not generated in {backend} for "
                                   f"{variant.plant_words} (the {variant.name} variant): use "
                                   f"{', '.join(repr(b) for b in usable)} (docs/sensing.md)")
    t_c = spec.prescribed_time
    horizon = t_c if horizon is None else _horizon(horizon)
    rate = spec.rate_hz
    dt = 1.0 / rate
    steps = int(math.ceil(horizon * rate - 1e-9))
    check_step_budget(steps, horizon, rate)
    dims = list(sensing.dims)
    world = _World(obstacles, len(dims), dt)
    reach = 0.0 if spec.robot is None else float(spec.robot.radius)
    x = initial_state(spec)
    n = spec.dimension
    if plant is None:
        plant = spec_plant(spec, seed)
    elif (getattr(plant, "nstates", None), getattr(plant, "ninputs", None)) != (x.size, n):
        raise SpecError("plant", f"must be a control.NonlinearIOSystem with {x.size} states "
                                 f"and {n} inputs for this spec")
    stepper = plant if hasattr(plant, "advance") else RungeKutta(plant)
    x = stepper.reset(x)
    record = SensingRecord()
    cpu: list[float] = []

    def measure(k: int) -> tuple[float, np.ndarray, list[SensedObstacle]]:
        t_m = k * dt
        s = positions(spec, states[k][None])[0][dims]
        seen = [SensedObstacle.ball(world.p[j], world.radius[j], seen_at=t_m,
                                    velocity=world.v[j], label=j)
                for j in range(world.radius.size)
                if np.linalg.norm(world.p[j] - s) - world.radius[j] <= sensing.range]
        return t_m, s, seen

    ts = np.arange(steps + 1) * dt
    reads = ts + sampling_offsets(spec.jitter, steps, seed)
    lengths = np.diff(reads) if spec.jitter > 0.0 else np.full(steps, dt)
    states = np.zeros((steps + 1, x.size))
    us = np.zeros((steps + 1, n))
    alphas = np.zeros((steps + 1, 2 * n))
    status = np.zeros(steps + 1, dtype=int)
    tubes = np.zeros(steps + 1, dtype=int)
    starts = np.zeros(steps + 1)
    states[0] = x
    # the start: the design's tube against the measurement at 0
    t_m, s, seen = measure(0)
    earlier = (t_m, s, seen)
    record.measurements = 1
    record.violations += envelope_violations(sensing, seen, s)
    first = start_plan(design, seen, s)
    cpu.append(first.cpu_s)
    if isinstance(first, ReplanFailure):
        active = uncertified_plan(design)
        record.events.append(PlanEvent(0.0, "uncertified start", 0, 0.0, 0.0, first.cpu_s,
                                       first.reason))
    else:
        active = first
        record.shortened += first.shortened
        record.events.append(PlanEvent(0.0, "start", 0, 0.0, first.guarantee_until,
                                       first.cpu_s))
    designs = [active.design]
    covered = [(active.certified_from, active.guarantee_until)] if active.guarantee_until \
        else []
    latest = active                               # the plan new ones are made from
    pending: list[SensedPlan] = []
    reveals: list[tuple[int, tuple]] = []
    next_measure = 1
    runner = _Runner(backend, design)
    controller = runner.controller(active.design)
    predict = delay_predictor(spec, active.design.tube, active.design.stage)
    alpha, u_prev = np.zeros(2 * n), np.zeros(n)
    dense, dense_t = [positions(spec, x[None])], [np.zeros(1)]
    obstacle_path = [world.p.reshape(1, -1).copy()]
    for k in range(steps + 1):
        t = float(ts[k])
        states[k] = x
        # 1. plans whose switch is due
        for plan in [p for p in pending if p.switch_at <= t + 1e-9]:
            if not any(p is plan for p in pending):    # dropped after a refusal
                continue
            pending = [p for p in pending if p is not plan]
            if plan.kept:
                if plan.design.tube != active.design.tube:
                    record.events.append(PlanEvent(t, "dropped", len(designs) - 1,
                                                   plan.measured_at, active.guarantee_until,
                                                   plan.cpu_s, "certified for a tube that "
                                                   "did not take over"))
                    continue
                active = plan
                record.shortened += plan.shortened
                covered.append((plan.certified_from, plan.guarantee_until))
                record.events.append(PlanEvent(t, "kept", len(designs) - 1, plan.measured_at,
                                               plan.guarantee_until, plan.cpu_s))
                continue
            e, incoming = runner.admit(plan, x)
            if incoming is None:
                record.refused += 1
                record.events.append(PlanEvent(
                    t, "refused", len(designs) - 1, plan.measured_at,
                    active.guarantee_until, plan.cpu_s,
                    f"the state is at |e| = {e:.3g} of the new tube at its start (limit "
                    f"{MAX_INITIAL_ERROR})"))
                # the plans made after it start from its tube, which the robot does not
                # follow: dropped, and the next plan is made from the active one
                for later in pending:
                    record.events.append(PlanEvent(t, "dropped", len(designs) - 1,
                                                   later.measured_at, active.guarantee_until,
                                                   later.cpu_s, "made from a plan refused "
                                                   "at its switch"))
                pending.clear()
                latest = active
                continue
            active = plan
            designs.append(plan.design)
            controller = incoming
            predict = delay_predictor(spec, plan.design.tube, plan.design.stage)
            alpha = np.zeros(2 * n)
            record.switches += 1
            record.escapes += plan.goal is not None
            record.best_effort += plan.best_effort
            record.shortened += plan.shortened
            covered.append((plan.certified_from, plan.guarantee_until))
            record.events.append(PlanEvent(t, "switched", len(designs) - 1, plan.measured_at,
                                           plan.guarantee_until, plan.cpu_s,
                                           f"|e| = {e:.3g} in the new tube"
                                           + _escape_words(plan, spec)))
        # 2. a measurement: taken now, revealed after the latency
        if next_measure * sensing.period <= t + 1e-9:
            taken = measure(k)
            record.measurements += 1
            record.violations += envelope_violations(sensing, taken[2], taken[1], earlier)
            earlier = taken
            reveals.append((math.ceil((t + sensing.latency) * rate - 1e-9), taken))
            next_measure = int(math.floor((t + 1e-9) / sensing.period)) + 1
        # 3. measurements revealed now: replan from the latest plan
        for due in [r for r in reveals if r[0] <= k]:
            reveals.remove(due)
            t_m, s, seen = due[1]
            made = replan(latest, t_m, s, seen)
            cpu.append(made.cpu_s)
            if isinstance(made, SensedPlan) and enforce_replan_time \
                    and made.cpu_s > sensing.replan_time:
                made = ReplanFailure(t_m, f"over the replanning budget: {made.cpu_s:.3g} s > "
                                          f"replan_time {sensing.replan_time:g} s", "budget",
                                     active.guarantee_until, made.time_s, made.cpu_s)
            if isinstance(made, ReplanFailure):
                record.failures += 1
                record.events.append(PlanEvent(t, "failed", len(designs) - 1, t_m,
                                               active.guarantee_until, made.cpu_s,
                                               made.reason))
                if made.fallback is None or (enforce_replan_time
                                             and made.cpu_s > sensing.replan_time):
                    continue
                made = made.fallback         # uncertified, but away from the obstacles
            latest = made
            pending.append(made)
        # 4. the controller of the active tube, at its own time
        local = t - active.start
        tubes[k], starts[k] = len(designs) - 1, active.start
        seen_x = x if predict is None else np.asarray(predict(x, u_prev), dtype=float).ravel()
        u, alpha_next, code = controller.step(seen_x, local, dt, alpha)
        us[k], status[k], alphas[k] = u, code, alpha
        if k == steps:
            break
        point = positions(spec, x[None])[0][dims]
        before = world.p.copy()
        after = world.advance(t, dt, point)
        points, times = hold_period(stepper, reads[k], u_prev, u, lengths[k], spec.delay)
        world.p = after
        u_prev = us[k]
        x = points[-1]
        dense.append(positions(spec, points))
        dense_t.append(times)
        share = ((times - t) / dt)[:, None, None]
        obstacle_path.append((before[None] + share * (after - before)[None]).reshape(
            len(times), -1))
        alpha = alpha_next
    record.replans = len(cpu)
    record.replan_cpu_max = float(max(cpu))
    record.replan_cpu_p95 = float(np.percentile(cpu, 95))
    record.replan_cpu_mean = float(np.mean(cpu))
    record.over_budget = int(sum(c > sensing.replan_time for c in cpu))
    record.uncertified = _gaps(covered, min(horizon, ts[-1]))
    record.outside_envelope = bool(record.violations)
    accel = sensing.max_obstacle_acceleration
    record.script_outside_envelope = bool(
        world.fastest > sensing.max_obstacle_speed * (1.0 + 1e-9) + 1e-12
        or (world.radius.size and world.radius.max() > sensing.max_obstacle_radius)
        or (accel is not None and world.sharpest > accel * (1.0 + 1e-9) + 1e-12))
    record.guaranteed = not record.uncertified and not record.outside_envelope
    return _judged(design, backend, horizon, ts, states, us, alphas, status, tubes, starts,
                   designs, np.vstack(dense), np.concatenate(dense_t), obstacle_path, world,
                   reach, record, stepper)


class _Runner:
    """The controllers of a run and its switch test, by backend: on ``c``, the spec's C
    with the tube as data compiled once (:class:`~.data_controller.TubeDataController`), on
    ``python`` its Python module with the tube as data generated once
    (:class:`~.data_module.TubeDataModule`): each plan's tube loaded into it and its switch
    deciding, as on a robot; else the backend's controller of each tube, and the oracle's
    ``|e|`` (:func:`_error`)."""

    def __init__(self, backend: str, design: Design) -> None:
        self.backend, self.spec = backend, design.spec
        self.library = None
        if backend == "c":
            self.library = variant_of(design.spec).entry("data_controller")(design)
        elif backend == "python":
            self.library = variant_of(design.spec).entry("data_module")(design)

    def controller(self, design: Design):
        """The controller running ``design``'s tube."""
        if self.library is not None:
            return self.library.load(design.tube)
        return make_controller(self.backend, design.tube, design.stage)

    def admit(self, plan: SensedPlan, x: np.ndarray) -> tuple[float, object | None]:
        """``(|e|, controller)`` of the plan's tube at its ``t = 0`` for the state ``x``;
        the controller is ``None`` where ``|e| > MAX_INITIAL_ERROR`` (the switch refused)."""
        if self.library is not None:
            loaded = self.library.load(plan.design.tube)
            e = loaded.switch_error(x)            # P_switch's test, on the measured state
            return e, (loaded if e <= MAX_INITIAL_ERROR else None)
        e = _error(plan, x, self.spec)
        return e, (self.controller(plan.design) if e <= MAX_INITIAL_ERROR else None)


def _escape_words(plan: SensedPlan, spec) -> str:
    """``"; an escape to (x, y)"`` for a plan going to a temporary goal, else ``""``."""
    if plan.goal is None:
        return ""
    centre = np.asarray(plan.goal.center)[list(spec.sensing.dims)]
    return ("; " + ("an uncertified best-effort" if plan.best_effort else "an")
            + " escape to (" + ", ".join(f"{c:.3g}" for c in centre) + ")")


def _horizon(value: object) -> float:
    """``horizon`` as a positive, finite float."""
    try:
        h = float(value)
    except (TypeError, ValueError):
        raise SpecError("horizon", f"must be a positive number of seconds, got "
                                   f"{value!r}") from None
    if not math.isfinite(h) or h <= 0:
        raise SpecError("horizon", f"must be a positive number of seconds, got {h!r}")
    return h


def _error(plan: SensedPlan, x: np.ndarray, spec) -> float:
    """``max_i |e_i|`` of the state in the plan's tube at its ``t = 0`` (``alpha = 0``)."""
    point = positions(spec, x[None])
    with reference.numpy_math():
        e, _, _, _ = reference.error_transform(plan.design.tube, point, np.zeros(1),
                                               np.zeros((1, 2 * spec.dimension)))
    value = float(np.max(np.abs(e)))
    return value if math.isfinite(value) else math.inf


def _gaps(covered: list[tuple[float, float]], end: float) -> list[list[float]]:
    """The spans of ``[0, end]`` outside every covered interval."""
    gaps, at = [], 0.0
    for a, b in sorted(c for c in covered if c[1] > c[0]):
        if a > at + 1e-9:
            gaps.append([at, min(a, end)])
        at = max(at, b)
        if at >= end:
            break
    if at < end - 1e-9:
        gaps.append([at, end])
    return [g for g in gaps if g[1] > g[0]]


def _certified_contact(contacts: np.ndarray, uncertified: list[list[float]]) -> bool:
    """Whether some instant of ``contacts`` (s) lies outside every ``uncertified`` span:
    every instant, not only the first, since a later contact may fall in a span a
    certificate covered."""
    return any(not any(a <= hit <= b for a, b in uncertified) for hit in contacts)


def _judged(design, backend, horizon, ts, states, us, alphas, status, tubes, starts, designs,
            path, path_t, obstacle_path, world, reach, record, stepper) -> SimulationResult:
    """Definition 2.1 on the run, the sensed obstacles among the obstacles."""
    spec = design.spec
    t_c = spec.prescribed_time
    judged = path_t <= t_c + 1e-12
    within = path[judged]
    xs = positions(spec, states)
    dims = list(spec.sensing.dims)
    t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
    in_target = np.all((xs >= t_lo) & (xs <= t_hi), axis=1) & (ts <= t_c + 1e-12)
    reached = bool(in_target.any())
    clear = [u.signed_clearance(within) for u in spec.unsafe_sets]
    clear += [ob.signed_clearance(within, path_t[judged]) for ob in spec.moving_obstacles]
    sensed_clear, sampled = None, None
    if world.radius.size:
        where = np.vstack(obstacle_path).reshape(len(path_t), -1, len(dims))
        sampled = np.stack([[np.interp(ts, path_t, where[:, j, c]) for c in range(len(dims))]
                            for j in range(world.radius.size)]).transpose(2, 0, 1)
        gaps = (np.linalg.norm(path[:, None, dims] - where, axis=2) - world.radius[None]
                - reach)
        sensed_clear = float(gaps.min())
        record.sensed_collision = bool(sensed_clear <= 0.0)
        record.min_sensed_clearance = sensed_clear
        if record.sensed_collision:
            contacts = path_t[gaps.min(axis=1) <= 0.0]
            record.collision_time = float(contacts[0])
            record.collision_certified = _certified_contact(contacts, record.uncertified)
        clear.append(gaps[judged].min(axis=1))
    if clear:
        min_clear = float(np.min([np.min(c) for c in clear]))
        collision = bool(min_clear <= 0.0)
        min_clear = min_clear if math.isfinite(min_clear) else None
    else:
        min_clear, collision = None, False
    lo, hi = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    left = bool(np.any((within < lo) | (within > hi)))
    widths, errors = [], []
    gamma_l, gamma_u = np.zeros_like(xs), np.zeros_like(xs)
    with reference.numpy_math():
        for q, d in enumerate(designs):
            rows = tubes == q
            if rows.any():
                g_l, g_u, _, _ = reference.adaptive_tube(d.tube, ts[rows] - starts[rows],
                                                         alphas[rows])
                gamma_l[rows], gamma_u[rows] = g_l, g_u
                widths.append(g_u - g_l)
                errors.append(np.abs(2.0 * xs[rows] - (g_u + g_l)) / (g_u - g_l))
    width = np.vstack(widths)
    max_abs_e = float(np.max(np.vstack(errors))) if np.all(width > 0.0) else None
    outside = (status == Status.OUTSIDE_TUBE) | (status == Status.INVALID_INPUT)
    satisfied = reached and not collision and not left and horizon >= t_c
    steps = ts.size - 1
    dt = 1.0 / spec.rate_hz
    return SimulationResult(
        spec=spec.name, backend=backend, satisfied=satisfied, reached=reached,
        reach_time=float(ts[int(np.argmax(in_target))]) if reached else None,
        prescribed_time=t_c, collision=collision, min_obstacle_clearance=min_clear,
        left_state_space=left, stayed_in_tube=not bool(np.any(outside)),
        max_abs_e=max_abs_e, max_abs_u=[float(v) for v in np.abs(us).max(axis=0)],
        steps=steps, control_effort=float(np.sum(us[:steps] ** 2) * dt),
        clamped_steps=int(np.sum(status == Status.INPUT_CLAMPED)),
        trajectory=Trajectory(ts, xs, us, alphas, status, tube=tubes, gamma_L=gamma_l,
                              gamma_U=gamma_u, sensed_positions=sampled,
                              sensed_radii=world.radius.copy() if sampled is not None
                              else None),
        contacts=stepper.contact_count, sensing=record)
