"""Certified replanning around obstacles sensed at run time (docs/sensing.md).

A spec with ``[sensing]`` (:class:`~stt_codegen.spec.sensing.Sensing`) runs a tube at a time,
a :class:`SensedPlan`: a certified :class:`~.result.Design` in its own time, started at an
absolute instant. From each measurement (the robot's reference point ``s`` and the
obstacles seen at ``t_m``, :class:`~stt_codegen.spec.sensing.SensedObstacle`), available at
``t_m + L``, :func:`replan` makes the next plan, for the switch instant
``t_s = t_m + L + tau`` (rounded up to a sample):

1. **kept**: the active tube, certified again against the new measurement over
   ``[t_m, t_s + H]``; no switch;
2. **switched**: else a new tube designed by :func:`~.search.design_tube` from the active
   tube's certified box at ``t_s`` (the initial set ``X_0``, with ``x(0)`` its centre and
   ``d_0`` its half width) to the spec's target within ``max(t_c - t_s, LATE_TIME)``,
   avoiding the static obstacles, the known moving ones (shifted to its time) and each
   sensed obstacle's reachable set over ``[t_s, t_s + H]`` as moving boxes over spans of
   at most :data:`CHUNK_SECONDS` (the fleet's pattern, :mod:`.fleet`), certified for every
   ``t`` by the design's own space-time certificate (:mod:`.certificate.motion`); else
   the same from a smaller box around where the robot will be at ``t_s``;
3. **escape**: else a tube to a temporary goal near the robot, away from where the sensed
   obstacles may be, certified the same way (:data:`ESCAPE_DISTANCES`);
4. **over the shortest horizon**: else steps 1-3 again with ``H_min``
   (``[sensing] shortest_horizon``, at least ``T_u``) in place of ``H``; the reachable
   sets of the shorter span are smaller.

Each plan is also certified to keep the robot's body, over the same span, inside the
region no obstacle unseen at ``t_m`` can have reached: the ball of radius
``R - V (t - t_m)`` around ``s`` (:func:`region_margin`, on the certificate's enclosure,
cut where needed). A plan that fails either certificate is a :class:`ReplanFailure`; the
robot then keeps its tube, whose guarantee ends at its own ``guarantee_until``. Whether
the robot lies in the new tube at the switch is the run time's test (a state with
``|e| <= MAX_INITIAL_ERROR`` in the new tube at its ``t = 0``), since it is only known then.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import DesignError, SpecError, number_text
from ..spec.loader import DEFAULT_HALF_WIDTH_FRACTION, Box, Spec
from ..spec.motion import MovingObstacle
from ..spec.sensing import SensedObstacle, Sensing, on_sensing_dims
from .certificate.fleet import RobotTube, robot_tube
from .certificate.motion import MOVING_PROPERTY
from .certificate.report import ROUNDING_MARGIN
from .failures import FailureKind, without_advice
from .result import Design, require_design
from .search import check_tube, design_tube
from .sensed_blend import continuing, going_on
from .sensed_evade import (EVADE_DISTANCES, EVADE_SAFE, EVADE_TIME, chasing,
                           evasion_clearance, pursuers, ring_ahead)
from .sensed_path import MIN_SPEED, PREDICTION_SPAN, path_design
from .sensed_switch import proved_error, state_at, switch_error

__all__ = ["CHUNK_SECONDS", "ESCAPE_CLEARANCE", "ESCAPE_DIRECTIONS", "ESCAPE_DISTANCES",
           "ESCAPE_TIME", "FORESIGHT", "LATE_TIME", "MAX_ESCAPES", "ReplanFailure",
           "SensedPlan", "escape_directions", "foresight_boxes", "reachable_boxes",
           "region_margin", "replan", "start_plan", "switch_time", "uncertified_plan"]

#: The longest time span of one box standing for a sensed obstacle's reachable set, s.
CHUNK_SECONDS = 0.25
#: A replanned tube reaches the target within at least this long after its switch, s (a
#: plan after ``t_c`` or just before it is late, and says so: ``SensedPlan.arrival``).
LATE_TIME = 2.0
#: A new tube that leaves the region no unseen obstacle can reach is designed again to
#: arrive this many times later (a slower tube, a late arrival), in turn.
SLOWER = (1.0, 1.5, 2.0, 3.0)
#: Most intervals the region certificate may cut the tube's enclosure into.
REGION_INTERVALS = 20_000
#: A kept replanned tube that arrives later than this before ``t_c`` is replaced by a
#: space-time path that arrives at least this much sooner, s.
EARLIER = 1.0
#: Seconds past the certified horizon over which a new tube to the target is first
#: designed to keep clear of where the sensed obstacles are headed (:func:`foresight_boxes`).
FORESIGHT = 2.0
#: Distances (state units) of the temporary goals an escape tube may go to from where the
#: robot will be at the switch, in the order tried; 0 holds a box around that point.
ESCAPE_DISTANCES = (0.0, 0.6, 1.2, 2.4)
#: Directions of the temporary goals, evenly spaced on the first two sensing dimensions.
ESCAPE_DIRECTIONS = 16
#: Seconds an escape tube takes to reach its temporary goal (then it holds it).
ESCAPE_TIME = 1.0
#: Most escape tubes designed from one measurement (the best ranked first).
MAX_ESCAPES = 6
#: Temporary goals at least this far (state units) from where every sensed obstacle is
#: headed until the escape tube has arrived plus the horizon rank equal on that count; the
#: nearest to the target among them first.
ESCAPE_CLEARANCE = 1.0
#: The time step at which an escape's goal is compared with where each sensed obstacle is
#: headed, s.
HEADED_STEP = 0.125
#: An obstacle whose velocity estimate points within this angle (radians) of the robot is
#: *closing*: it may turn after the robot (a pursuer), and is not taken for a straight walk
#: (:func:`_pursued`, :func:`_escape`); a fast one (:data:`CLOSING_SPEED`) only within
#: :data:`FAST_CLOSING_ANGLE`.
CLOSING_ANGLE = math.pi / 4.0
#: The fastest *slow* closing obstacle, as a share of the slowest path
#: (:data:`~.sensed_path.MIN_SPEED`): the robot outruns a slow one, so it is followed for
#: :data:`FORESIGHT` past a tube's horizon and while an escape holds its goal; a faster one
#: only for :data:`FAST_PURSUIT`, and over an escape's way and horizon (it reaches every
#: goal the robot would wait at).
CLOSING_SPEED = 0.5
#: Seconds past a tube's certified horizon over which a fast closing obstacle (faster than
#: :data:`CLOSING_SPEED` times the slowest path) is taken to turn after the robot.
FAST_PURSUIT = 1.0
#: The angle (radians) within which a fast obstacle's estimate points at the robot when it
#: is closing: a pursuer heads for the robot; a fast straight walk taken for one (within
#: :data:`CLOSING_ANGLE`) ranked escapes into the corner behind the robot.
FAST_CLOSING_ANGLE = math.pi / 12.0


@dataclass(frozen=True)
class SensedPlan:
    """The tube a robot runs with sensed obstacles: a certified design in its own time.

    Attributes
    ----------
    design : Design
        The certified tube; its time ``t' = t - start``. Its spec holds the sensed
        obstacles' reachable sets it was certified against (moving obstacles).
    task : Spec
        The spec as given, in absolute time (its target, ``t_c``, obstacles and
        ``[sensing]``): what every replanned tube is designed for.
    local : Spec
        The task in the tube's time without the sensed obstacles: the static obstacles and
        the known moving ones shifted by ``start`` (what the next check starts from).
    start : float
        The absolute instant of the tube's ``t' = 0``, s.
    measured_at : float
        The measurement the plan was certified against, s.
    certified_from, guarantee_until : float
        The absolute span over which the tube is certified to miss every sensed
        obstacle's reachable set and to keep the body where no unseen obstacle can be,
        s.
    switch_at : float
        The absolute instant the plan takes over, a sample, s (``start`` for a new tube).
    arrival : float
        The absolute instant from which the tube lies in the target, s (after the spec's
        ``t_c`` when the plan is late); for an escape, when it lies in its ``goal``.
    kept : bool
        The active tube, certified again (no switch); False: a new tube.
    sensed : tuple of SensedObstacle
        The measurement.
    sensed_margin : float
        Smallest certified separation from the sensed obstacles' reachable boxes, state
        units (``inf``: none was sensed).
    region_margin : float
        Smallest certified room between the body and the region an unseen obstacle may
        have reached, state units.
    time_s, cpu_s : float
        Wall and processor time of the call that made the plan, s.
    goal : Box or None
        An escape's temporary goal, which the tube reaches instead of the target and then
        holds (the next plans try the target first); ``None``: the tube goes to the target.
    reached : bool
        The robot has been measured inside the target by this plan's measurement or an
        earlier one in its chain of replans (an obstacle closing on it is then taken to
        pursue it, docs/sensing.md).
    best_effort : bool
        No certificate against the sensed obstacles (``certified_from`` and
        ``guarantee_until`` are its switch): the best escape found after no plan was
        certified (:attr:`ReplanFailure.fallback`), which takes over when the certified
        span of the plan it replaces has run out.
    chasers : tuple of int
        The track numbers (``SensedObstacle.label``) taken for pursuers by this plan's
        measurement or an earlier one in its chain of replans: a track whose velocity
        estimate changed as the envelope's adversary's would, turning after the robot
        (:func:`~.sensed_evade.chasing`). A fast one approaching is run from by an
        *evasion* (docs/sensing.md).
    state_bounds : (ndarray, ndarray) or None
        Where the tube's sampled-data proof keeps the state at its samples ``t' = k /
        rate_hz``: lower and upper corners, shape (K + 1, n) each, from where the state
        may be at the plan's switch (:mod:`.sensed_switch`; the spec's tube from its
        ``x(0)``); the next switch starts from it. ``None`` for a best-effort escape not
        proved from its switch.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("hall-crossing"))
    >>> plan = stt.start_plan(design)
    >>> plan.start, plan.kept, plan.guarantee_until
    (0.0, True, 1.6)
    """

    design: Design
    task: Spec = field(repr=False)
    local: Spec = field(repr=False)
    start: float
    measured_at: float
    certified_from: float
    guarantee_until: float
    switch_at: float
    arrival: float
    kept: bool
    sensed: tuple[SensedObstacle, ...] = field(default=(), repr=False)
    sensed_margin: float = math.inf
    region_margin: float = math.inf
    time_s: float = 0.0
    cpu_s: float = 0.0
    goal: Box | None = field(default=None, repr=False)
    reached: bool = False
    best_effort: bool = False
    chasers: tuple[int, ...] = ()
    state_bounds: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False,
                                                                compare=False)

    @property
    def shortened(self) -> bool:
        """Certified over the envelope's ``shortest_horizon`` ``H_min`` past its switch, not
        over its ``horizon`` ``H``: no plan was certified over ``H`` from its measurement
        (docs/sensing.md, "How the next plan is made"). False when ``H_min = H``."""
        sensing = self.task.sensing
        if self.best_effort or sensing is None or not (
                sensing.shortest_horizon < sensing.horizon):
            return False
        span = self.guarantee_until - switch_time(sensing, self.measured_at,
                                                  self.task.rate_hz)
        return span < 0.5 * (sensing.horizon + sensing.shortest_horizon)


@dataclass(frozen=True)
class ReplanFailure:
    """No certified plan from a measurement: the robot keeps its tube.

    Attributes
    ----------
    measured_at : float
        The measurement's instant, s.
    reason : str
        What failed, in words: the design's refusal, or the region certificate.
    kind : {"design", "region", "envelope"}
        ``design``: no tube found or certified (the design's :class:`~stt_codegen.errors.DesignError`);
        ``region``: the tube leaves the region no unseen obstacle can reach; ``envelope``:
        the measurement is outside the spec's envelope (a shape larger than
        ``max_obstacle_radius``).
    guarantee_until : float
        Until when the plan that stays active is certified, s.
    time_s, cpu_s : float
        Wall and processor time of the call, s.
    fallback : SensedPlan or None
        A best-effort escape (:attr:`SensedPlan.best_effort`) for a ``design`` or
        ``region`` failure: a temporary goal reached by a tube certified against every
        sensed obstacle's reachable set except those that already meet the box it starts
        from, which it avoids only where they are headed (or not at all); ``None`` when
        none is designed. Running it leaves the robot uncertified as the failure does,
        but moving away rather than holding its tube (docs/sensing.md).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("hall-crossing"))
    >>> wall = [stt.SensedObstacle.box((0.8, 0.0), (1.2, 4.0))]     # across the hall
    >>> failed = stt.start_plan(design, wall)
    >>> failed.kind, failed.guarantee_until
    ('envelope', 0.0)
    """

    measured_at: float
    reason: str
    kind: str
    guarantee_until: float
    time_s: float = 0.0
    cpu_s: float = 0.0
    fallback: SensedPlan | None = field(default=None, repr=False)


def switch_time(sensing: Sensing, measured_at: float, rate_hz: float) -> float:
    """The sample at which a tube planned from a measurement takes over.

    Parameters
    ----------
    sensing : Sensing
        The envelope (its latency and replanning budget).
    measured_at : float
        ``t_m``, s.
    rate_hz : float
        The controller's rate, Hz.

    Returns
    -------
    float
        The first sampling instant ``k / rate_hz`` at or after ``t_m + L + tau``, s.
    """
    k = math.ceil((measured_at + sensing.switch_delay) * rate_hz - 1e-9)
    return k / rate_hz


def reachable_boxes(sensed: Sequence[SensedObstacle], speed: float, reach: float,
                    dims: Sequence[int], start: float, t_from: float, t_to: float,
                    first_source: int, chunk: float = CHUNK_SECONDS, *,
                    acceleration: float | None = None, velocity_error: float = 0.0
                    ) -> tuple[MovingObstacle, ...]:
    """Each sensed obstacle's reachable set, grown by the robot's radius, as boxes over spans.

    Over a span ``[a, b]`` of a tube's time the box is the obstacle's shape grown by
    ``V (start + b - seen_at)`` and by ``reach`` (the reachable set only grows), present
    on ``[a, b]`` only (``active``, closed): together the boxes cover the reachable set
    at every ``t`` of ``[t_from, t_to]``. With ``acceleration`` (the envelope's ``A``) an
    obstacle with a velocity estimate is also in its
    :meth:`~stt_codegen.spec.sensing.SensedObstacle.drift_box` over the span, and the box
    is the intersection of the two (each holds it).

    Parameters
    ----------
    sensed : sequence of SensedObstacle
        The obstacles, on ``dims``.
    speed : float
        ``V``, state units per second.
    reach : float
        The robot's radius around its reference point, state units.
    dims : sequence of int
        The state dimensions of the obstacles.
    start : float
        The absolute instant of the tube's ``t' = 0``, s.
    t_from, t_to : float
        The span to cover, in the tube's time, s, ``t_from < t_to``.
    first_source : int
        The obstacle index of the first box (the next ones follow).
    chunk : float
        The longest span of one box, s.
    acceleration : float, optional
        ``A``, state units per second squared; ``None``: the speed bound alone.
    velocity_error : float
        ``E``, state units per second (with ``acceleration``).

    Returns
    -------
    tuple of MovingObstacle
        Boxes that do not move, each present over its span.
    """
    def box(ob: SensedObstacle, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = ob.reach_box(start + b, speed)
        drift = None if acceleration is None else ob.drift_box(
            start + a, start + b, acceleration, velocity_error)
        if drift is not None:
            lo, hi = np.maximum(lo, drift[0]), np.minimum(hi, drift[1])
        return lo, hi

    return _span_boxes(sensed, box, reach, dims, t_from, t_to, first_source, chunk)


def _span_boxes(sensed: Sequence[SensedObstacle], box, reach: float, dims: Sequence[int],
                t_from: float, t_to: float, first_source: int,
                chunk: float) -> tuple[MovingObstacle, ...]:
    """Standing boxes, one per obstacle and span of at most ``chunk`` of
    ``[t_from, t_to]``: ``box(ob, a, b)`` (lower and upper corners over ``[a, b]``) grown
    by ``reach``, present on ``[a, b]``, numbered from ``first_source``."""
    count = max(1, math.ceil((t_to - t_from) / chunk - 1e-9))
    edges = np.linspace(t_from, t_to, count + 1)
    out: list[MovingObstacle] = []
    for ob in sensed:
        for a, b in zip(edges[:-1], edges[1:]):
            lo, hi = box(ob, float(a), float(b))
            half = (hi - lo) / 2 + reach
            out.append(MovingObstacle(
                source=first_source + len(out), dims=tuple(int(d) for d in dims),
                half_size=tuple(float(v) for v in half), times=(float(a),),
                centres=(tuple(float(v) for v in (hi + lo) / 2),),
                active=(float(a), float(b)), motion="still"))
    return tuple(out)


def region_margin(design: Design, sensing: Sensing, reach: float, start: float,
                  measured_at: float, position: Sequence[float], t_from: float,
                  t_to: float) -> tuple[float, float]:
    """The certified room between the body and where an obstacle unseen at ``t_m`` may be.

    An obstacle not in the measurement at ``t_m`` had no point within ``R`` of ``s``; by
    ``t`` it may have come ``V (t - t_m)`` nearer. On each interval of the tube's
    certificate enclosure that meets ``[t_from, t_to]`` the farthest corner of the tube's
    box from ``s`` (on the sensing dimensions), plus the robot's radius, must stay below
    ``R - V (t_end - t_m)`` (``t_end`` the interval's end, clipped to ``t_to``). Intervals
    where it does not are cut (``alpha`` followed again on the cuts,
    :meth:`~.certificate.fleet.RobotTube.cut`) until it does, they are single samples, or
    :data:`REGION_INTERVALS` is reached.

    Parameters
    ----------
    design : Design
        The certified tube.
    sensing : Sensing
        The envelope.
    reach : float
        The robot's radius, state units.
    start : float
        The absolute instant of the tube's ``t' = 0``, s.
    measured_at : float
        ``t_m``, s.
    position : sequence of float
        ``s``, the reference point on ``sensing.dims`` at ``t_m``.
    t_from, t_to : float
        The span, in the tube's time, s.

    Returns
    -------
    margin : float
        The smallest room over the span, state units (positive: certified).
    t : float
        Where it is smallest, in the tube's time, s.
    """
    tube: RobotTube = robot_tube(design.tube, design.certificate)
    s = np.asarray(position, dtype=float)
    while True:
        t0, t1, lo, hi = tube.boxes(sensing.dims)
        within = (t1 >= t_from) & (t0 <= t_to)
        end = np.minimum(t1, t_to)
        far = np.sqrt(np.sum(np.maximum(np.abs(lo - s), np.abs(hi - s)) ** 2, axis=1))
        room = (sensing.range - sensing.max_obstacle_speed * (start + end - measured_at)
                - far - reach)
        room = np.where(within, room, np.inf)
        bad = room <= ROUNDING_MARGIN
        if not bad.any() or t0.size > REGION_INTERVALS:
            break
        cut = tube.cut(bad)
        if cut is tube:
            break
        tube = cut
    k = int(np.argmin(room))
    return float(room[k]), float(t0[k])


def _drift(sensing: Sensing) -> dict:
    """:func:`reachable_boxes`' keywords of the envelope's acceleration bound."""
    return {"acceleration": sensing.max_obstacle_acceleration,
            "velocity_error": sensing.velocity_error}


def _sensed_margin(design: Design, first_source: int) -> float:
    """The smallest certified separation from the moving boxes numbered from
    ``first_source`` on (the sensed obstacles'), ``inf`` without any."""
    prefix = f"{MOVING_PROPERTY} "
    values = [m.margin for m in design.certificate.margins if m.name.startswith(prefix)
              and int(m.name[len(prefix):]) >= first_source]
    return min(values, default=math.inf)


def _checked(sensed: Sequence[SensedObstacle], sensing: Sensing,
             measured_at: float) -> tuple[SensedObstacle, ...]:
    """The measurement, each obstacle on the sensing dimensions and seen by ``t_m``."""
    out = on_sensing_dims(sensed, SensedObstacle, "centre", sensing, "sensed")
    for j, ob in enumerate(out):
        if ob.seen_at > measured_at:
            raise SpecError(f"sensed[{j}].seen_at", f"= {ob.seen_at!r} s is after the "
                                                    f"measurement instant {measured_at!r} s")
    return out


def _too_large(sensed: Sequence[SensedObstacle], sensing: Sensing) -> str | None:
    """Why the measurement is outside the envelope's size, or ``None``."""
    for j, ob in enumerate(sensed):
        if ob.extent > sensing.max_obstacle_radius * (1.0 + 1e-9):
            return (f"sensed[{j}] has extent {ob.extent:.4g} > max_obstacle_radius "
                    f"{sensing.max_obstacle_radius:g}: outside the envelope")
    return None


def _reach(spec: Spec) -> float:
    """The robot's radius around its reference point (0: a point robot)."""
    return 0.0 if spec.robot is None else float(spec.robot.radius)


def _shifted(obstacles: Sequence[MovingObstacle], shift: float) -> tuple[MovingObstacle, ...]:
    """Moving obstacles in the time of a tube started at ``shift``: every time minus it;
    those gone before it dropped, ``active`` clipped at 0."""
    out = []
    for ob in obstacles:
        t_on, t_off = ob.active[0] - shift, ob.active[1] - shift
        if t_off < 0.0:
            continue
        out.append(replace(ob, times=tuple(t - shift for t in ob.times),
                           active=(max(0.0, t_on), t_off)))
    return tuple(out)


def _position(spec: Spec, sensing: Sensing, position: Sequence[float] | None) -> np.ndarray:
    """The reference point on the sensing dimensions (``x(0)``'s when ``None``)."""
    if position is None:
        return np.array([spec.initial_state[d] for d in sensing.dims])
    try:
        p = np.asarray(position, dtype=float).ravel()
    except (TypeError, ValueError):
        raise SpecError("position", f"must be numbers, got {position!r}") from None
    if p.size != len(sensing.dims) or not np.all(np.isfinite(p)):
        raise SpecError("position", f"must be {len(sensing.dims)} finite numbers (the "
                                    f"reference point on dims {list(sensing.dims)}), got "
                                    f"{position!r}")
    return p


def _certify(design: Design, local: Spec, sensing: Sensing, sensed: Sequence[SensedObstacle],
             start: float, measured_at: float, position: np.ndarray, t_from: float,
             t_to: float) -> tuple[Design | None, str, float, float]:
    """``design``'s tube checked against the sensed obstacles' boxes over ``[t_from, t_to]``
    (its time) and the region certificate: the design with that check, or ``None`` and the
    reason, with the two margins."""
    first = _first_source(local)
    boxes = reachable_boxes(sensed, sensing.max_obstacle_speed, _reach(local), sensing.dims,
                            start, t_from, t_to, first, **_drift(sensing))
    spec = replace(local, moving_obstacles=local.moving_obstacles + boxes)
    check = check_tube(design.tube, spec)
    if not check.passed:
        return None, check.reason, -math.inf, -math.inf
    checked = replace(design, check=check, spec=spec)
    sensed_margin = _sensed_margin(checked, first)
    room, at = region_margin(checked, sensing, _reach(local), start, measured_at, position,
                             t_from, t_to)
    if room <= ROUNDING_MARGIN:
        return None, (f"the tube may leave the region no unseen obstacle can reach (room "
                      f"{room:.3g} at t = {start + at:.4f} s)"), sensed_margin, room
    return checked, "", sensed_margin, room


def _sensing(spec: Spec) -> Sensing:
    """The spec's ``[sensing]``, or a :class:`SpecError` saying it has none."""
    if spec.sensing is None:
        raise SpecError("sensing", f"spec {spec.name!r} has no [sensing] table: the "
                                   "envelope replanning needs (docs/sensing.md)")
    if spec.tasks:
        raise SpecError("sensing", "replanning a spec with [[tasks]] is not supported")
    return spec.sensing


def start_plan(design: Design, sensed: Sequence[SensedObstacle] = (),
               position: Sequence[float] | None = None) -> SensedPlan | ReplanFailure:
    """The spec's own design as the first plan, certified against a measurement at ``t = 0``.

    The robot stands at ``x(0)`` until it has the measurement taken at ``t = 0``; the
    design's tube is then certified against the obstacles seen (their reachable sets) and
    the region no unseen obstacle can reach, over ``[0, L + tau + H]``: until the first
    replanned tube's switch and its horizon (else over ``[0, L + tau + H_min]``,
    ``[sensing] shortest_horizon``).

    Parameters
    ----------
    design : Design
        :func:`~.search.design_tube` of a spec with ``[sensing]``.
    sensed : sequence of SensedObstacle
        The obstacles seen at ``t = 0`` (``seen_at <= 0``).
    position : sequence of float, optional
        The reference point on the sensing dimensions at ``t = 0``; default ``x(0)``'s.

    Returns
    -------
    SensedPlan or ReplanFailure
        The plan (``kept``, ``start`` 0), or why the design is not certified against the
        measurement.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~.result.Design`.
    SpecError
        The spec has no ``[sensing]`` or has ``[[tasks]]`` (field ``sensing``); a sensed
        obstacle not on the sensing dimensions (``sensed[j].centre``) or seen after
        ``t = 0`` (``sensed[j].seen_at``); a bad ``position``.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("hall-crossing"))
    >>> person = stt.SensedObstacle.ball((7.0, 3.0), 0.3)      # far ahead
    >>> plan = stt.start_plan(design, [person])
    >>> plan.kept, plan.guarantee_until, plan.sensed_margin > 0
    (True, 1.6, True)
    """
    design = require_design(design, "start_plan")
    spec = design.spec
    sensing = _sensing(spec)
    started, cpu = time.perf_counter(), time.process_time()
    sensed = _checked(sensed, sensing, 0.0)
    s = _position(spec, sensing, position)
    until = sensing.switch_delay + sensing.horizon
    local = spec

    def failed(reason: str, kind: str) -> ReplanFailure:
        return ReplanFailure(0.0, reason, kind, 0.0, time.perf_counter() - started,
                             time.process_time() - cpu)

    large = _too_large(sensed, sensing)
    if large is not None:
        return failed(large, "envelope")
    checked, reason, margin, room = _certify(design, local, sensing, sensed, 0.0, 0.0, s,
                                             0.0, until)
    if checked is None and sensing.shortest_horizon < sensing.horizon:
        until = sensing.switch_delay + sensing.shortest_horizon
        checked, short, margin, room = _certify(design, local, sensing, sensed, 0.0, 0.0, s,
                                                0.0, until)
        reason = _over_both(reason, sensing.shortest_horizon, short)
    if checked is None:
        return failed(reason, "region" if room > -math.inf else "design")
    return SensedPlan(checked, spec, local, 0.0, 0.0, 0.0, until, 0.0, spec.prescribed_time,
                      True, sensed, margin, room, time.perf_counter() - started,
                      time.process_time() - cpu, state_bounds=proved_error(design, spec)[0])


def uncertified_plan(design: Design) -> SensedPlan:
    """The spec's design as the active plan with no certificate against sensed obstacles
    (``guarantee_until`` 0): what the robot runs when :func:`start_plan` fails.

    Parameters
    ----------
    design : Design
        :func:`~.search.design_tube` of a spec with ``[sensing]``.

    Returns
    -------
    SensedPlan
    """
    design = require_design(design, "uncertified_plan")
    _sensing(design.spec)
    return SensedPlan(design, design.spec, design.spec, 0.0, 0.0, 0.0, 0.0, 0.0,
                      design.spec.prescribed_time, True,
                      state_bounds=proved_error(design, design.spec)[0])


def _box_at(plan: SensedPlan, t_local: float, state_space: Box) -> Box:
    """The active tube's certified box at its time ``t_local`` (an interval of its
    enclosure holding it, cut to a single sample where it can be), clipped to ``X``."""
    tube = robot_tube(plan.design.tube, plan.design.certificate)
    while True:
        enc = tube.enclosure
        k = int(np.searchsorted(enc.t_start, t_local, side="right") - 1)
        mask = np.zeros(enc.t_start.size, dtype=bool)
        mask[k] = True
        cut = tube.cut(mask)
        if cut is tube:
            break
        tube = cut
    lo = np.maximum(enc.lower_min[k], state_space.lower)
    hi = np.minimum(enc.upper_max[k], state_space.upper)
    return Box(tuple(float(v) for v in lo), tuple(float(v) for v in hi))


def replan(plan: SensedPlan, measured_at: float, position: Sequence[float],
           sensed: Sequence[SensedObstacle]) -> SensedPlan | ReplanFailure:
    """The next certified plan from a measurement, or why there is none.

    The switch instant is ``t_s = t_m + L + tau`` rounded up to a sample
    (:func:`switch_time`). First the active tube is certified again against the
    measurement over ``[t_m, t_s + H]`` (``kept``: no switch), unless it is headed where
    a sensed obstacle is going (then a space-time path or an escape, when one is
    certified) or, replanned, due later than ``t_c - EARLIER`` (then a space-time path
    that arrives :data:`EARLIER` sooner, when one is certified). Else a new tube is designed
    from the active tube's certified box at ``t_s`` to the target, avoiding every known
    obstacle and the sensed obstacles' reachable sets over ``[t_s, t_s + H]``, and
    certified for every ``t``, then the same from a box of the spec's ``d_0`` around where
    the robot will be at ``t_s``; else an *escape*: a tube to a temporary goal near the
    robot (``SensedPlan.goal``), reached in :data:`ESCAPE_TIME` and held (an escape's own
    tube is kept only after the target has been tried again). Every plan must keep the
    body inside the region no obstacle unseen at ``t_m`` can have reached
    (:func:`region_margin`). When no plan is certified over ``[t_s, t_s + H]``, the same
    steps run over ``[t_s, t_s + H_min]`` (``[sensing] shortest_horizon``; the plan is
    then :attr:`SensedPlan.shortened`). When none is certified either, the failure carries
    a best-effort escape, not certified against the reachable sets
    (:attr:`ReplanFailure.fallback`). The run time switches to a new tube at ``t_s`` only
    if the state lies in it then (docs/sensing.md).

    Parameters
    ----------
    plan : SensedPlan
        The active plan (:func:`start_plan`, or a previous :func:`replan`).
    measured_at : float
        ``t_m``, s, not before the active plan's ``measured_at``.
    position : sequence of float
        The robot's reference point on the sensing dimensions at ``t_m``, state units.
    sensed : sequence of SensedObstacle
        The obstacles seen at ``t_m`` (each ``seen_at <= t_m``).

    Returns
    -------
    SensedPlan or ReplanFailure
        The kept or new plan; or the failure, with the active plan's ``guarantee_until``
        and its ``fallback``.

    Raises
    ------
    TypeError
        ``plan`` is not a :class:`SensedPlan`.
    SpecError
        ``measured_at`` before the active plan's measurement (field ``measured_at``); a
        sensed obstacle not on the sensing dimensions or seen after ``t_m``; a bad
        ``position``.

    Examples
    --------
    A person stands in the base's way; the tube from the start does not keep clear of where
    they may be, so a new one is designed (it waits, then passes):

    >>> import stt_codegen as stt
    >>> plan = stt.start_plan(stt.design_tube(stt.load_spec("hall-crossing")))
    >>> person = stt.SensedObstacle.ball((4.0, 2.8), 0.3, seen_at=1.0)
    >>> new = stt.replan(plan, 1.0, (1.0, 3.0), [person])
    >>> new.kept, new.switch_at, new.guarantee_until, new.sensed_margin > 0
    (False, 1.6, 2.6, True)
    """
    # a failure needs its reason, not the rate or the time that would work (those
    # searches take seconds)
    with without_advice():
        made = _replan(plan, measured_at, position, sensed, None)
        sensing = _sensing(plan.task)
        if isinstance(made, ReplanFailure) and sensing.shortest_horizon < sensing.horizon:
            short = _replan(plan, measured_at, position, sensed, sensing.shortest_horizon)
            spent = {"time_s": short.time_s + made.time_s, "cpu_s": short.cpu_s + made.cpu_s}
            made = replace(short, **spent) if isinstance(short, SensedPlan) else replace(
                made, reason=_over_both(made.reason, sensing.shortest_horizon, short.reason),
                **spent)
        if not isinstance(made, ReplanFailure) or made.kind == "envelope":
            return made
        # no plan certified: an escape all the same, for the robot to run uncertified
        started, cpu = time.perf_counter(), time.process_time()
        best = _best_effort(plan, made.measured_at, position, sensed)
    spent = {"time_s": made.time_s + time.perf_counter() - started,
             "cpu_s": made.cpu_s + time.process_time() - cpu}
    return replace(made, fallback=None if best is None else replace(best, **spent), **spent)


def _over_both(reason: str, shortest: float, short_reason: str) -> str:
    """A failure's reason over the horizon and over the shortest horizon."""
    return f"{reason}; over the shortest horizon ({number_text(shortest)} s): {short_reason}"


def _replan(plan: SensedPlan, measured_at: float, position: Sequence[float],
            sensed: Sequence[SensedObstacle], horizon: float | None
            ) -> SensedPlan | ReplanFailure:
    """:func:`replan`'s work, certified over ``horizon`` (default the envelope's ``H``)."""
    if not isinstance(plan, SensedPlan):
        raise TypeError(f"replan(): parameter 'plan' must be a SensedPlan (from start_plan "
                        f"or replan), not {type(plan).__name__}")
    local = plan.local
    sensing = _sensing(plan.task)
    if horizon is not None:
        sensing = replace(sensing, horizon=horizon)
    started, cpu = time.perf_counter(), time.process_time()
    try:
        t_m = float(measured_at)
    except (TypeError, ValueError):
        raise SpecError("measured_at", f"must be a number of seconds, got "
                                       f"{measured_at!r}") from None
    if not math.isfinite(t_m) or t_m < plan.measured_at:
        raise SpecError("measured_at", f"= {measured_at!r} s must be finite and not before "
                                       f"the active plan's measurement at "
                                       f"{plan.measured_at!r} s")
    sensed = _checked(sensed, sensing, t_m)
    s = _position(local, sensing, position)
    t_s = switch_time(sensing, t_m, local.rate_hz)
    until = t_s + sensing.horizon
    reached = _reached(plan, s, sensing)
    tracked = chasing(plan.sensed, plan.chasers, sensed, s, sensing)

    def done(**fields) -> SensedPlan:
        return SensedPlan(**fields, measured_at=t_m, guarantee_until=until, sensed=sensed,
                          reached=reached, chasers=tracked,
                          time_s=time.perf_counter() - started,
                          cpu_s=time.process_time() - cpu)

    def failed(reason: str, kind: str) -> ReplanFailure:
        return ReplanFailure(t_m, reason, kind, plan.guarantee_until,
                             time.perf_counter() - started, time.process_time() - cpu)

    large = _too_large(sensed, sensing)
    if large is not None:
        return failed(large, "envelope")

    def kept_plan() -> SensedPlan | None:
        kept, _, margin, room = _certify(plan.design, local, sensing, sensed, plan.start,
                                         t_m, s, max(0.0, t_m - plan.start),
                                         until - plan.start)
        if kept is None:
            return None
        return done(design=kept, task=plan.task, local=local, start=plan.start,
                    certified_from=t_m, switch_at=plan.switch_at, arrival=plan.arrival,
                    kept=True, sensed_margin=margin, region_margin=room, goal=plan.goal,
                    state_bounds=plan.state_bounds)

    base = plan.task
    first = _first_source(base)
    boxes = reachable_boxes(sensed, sensing.max_obstacle_speed, _reach(base), sensing.dims,
                            t_s, 0.0, sensing.horizon, first, **_drift(sensing))
    moving = _shifted(base.moving_obstacles, t_s)
    remaining = max(base.prescribed_time - t_s, LATE_TIME)

    @functools.cache
    def at_switch() -> tuple[Box, np.ndarray, Box | None]:
        # computed once, when a new tube is looked for
        return _taking_over(plan, t_s, s, t_m, sensing)

    # where the active plan's proof leaves the state at the switch
    state = state_at(plan.state_bounds, base.rate_hz, t_s - plan.start)
    # the active tube and the switch in its time, for a new tube that goes on with its move
    going = (plan.design.tube, t_s - plan.start)

    def escape() -> dict | str:
        active, point, near = at_switch()
        return _escape(base, near or active, moving, boxes, sensed, sensing, s, t_m, t_s,
                       first, point, state)

    # 0. a fast track taken for a pursuer approaching the robot: an evasion, an escape
    #    ranked against its pursuit, when one is certified (with the envelope's
    #    acceleration bound only: a robot no faster than a pursuer that turns at once
    #    gains nothing by turning)
    chasers = ([] if sensing.max_obstacle_acceleration is None else
               pursuers([ob for ob in sensed if ob.label in tracked], s,
                        CLOSING_SPEED * MIN_SPEED))
    if chasers:
        active, point, near = at_switch()
        made = _escape(base, near or active, moving, boxes, sensed, sensing, s, t_m, t_s,
                       first, point, state, chasers=chasers, going=going)
        if isinstance(made, dict):
            return done(task=plan.task, **made)

    def chased(made: dict) -> bool:
        # a new tube due late, or holding its goal, that an obstacle closing on the robot
        # would catch were it to turn after it: certified, but kept only as a spare
        return _pursued(made["design"], made["start"], made["arrival"], base, sensed,
                        sensing, until, s, reached)

    # 1. the active tube, certified again from the measurement on (an escape's after the
    #    target has been tried again; a best-effort escape's first, for its certificate to
    #    cover the time since it took over)
    kept = kept_plan() if plan.goal is None or plan.best_effort else None
    if kept is not None:
        # a kept tube headed where an obstacle is going: a way round it, else out of its
        # way; a replanned tube due near t_c or late (not the spec's own, which starts at
        # 0 and is due at t_c): a way that arrives sooner; each if one is certified now,
        # else the kept tube, certified
        headed = _headed_into(kept, sensed, sensing, until, first, s)
        if not headed and (plan.start == 0.0 or plan.arrival <= max(
                t_s, base.prescribed_time - EARLIER)):
            return kept
        made = _along_path(base, at_switch()[0], moving, boxes, sensed, sensing, s, t_m,
                           t_s, remaining, first, state)
        spare = None
        if made is not None and (headed or made["arrival"] <= plan.arrival - EARLIER):
            if not chased(made):
                return done(task=plan.task, **made)
            spare = made if headed else None
        made = escape() if headed else None
        made = made if isinstance(made, dict) else spare
        return done(task=plan.task, **made) if made is not None else kept
    # 2. a new tube to the target from the active tube's box at the switch, then from a
    #    box around where the robot will be
    active, point, near = at_switch()
    ahead = foresight_boxes(sensed, _reach(base), sensing.dims, t_s, sensing.horizon,
                            sensing.horizon + FORESIGHT, first + len(boxes),
                            sensing.velocity_error)
    outcome: tuple[str, str] | None = None
    # a way through where the sensed obstacles are headed over the whole tube, then the
    # design for the horizon and a short foresight, then without the foresight
    made = _along_path(base, active, moving, boxes, sensed, sensing, s, t_m, t_s, remaining,
                       first, state)
    spare = None
    if made is not None:
        if not chased(made):
            return done(task=plan.task, **made)
        spare = made
    # over the shortest horizon a tube is certified for a moment only: one that heads
    # where an obstacle is going would drive into it if the next replanning fails
    tries = [(active, boxes + ahead)] + ([] if horizon is not None else (
        [(active, boxes)] + ([] if near is None else [(near, boxes)])))
    for box, avoided in tries:
        made = _to_target(base, box, moving, avoided, sensing, s, t_m, t_s, remaining,
                          first, state)
        if isinstance(made, dict):
            if not chased(made):
                return done(task=plan.task, **made)
            spare = spare or made
            continue
        outcome = outcome or made
    # 3. an escape's tube kept (unless headed where an obstacle is going), or a new
    #    escape to a temporary goal, else the escape's tube kept all the same
    if plan.goal is not None and not plan.best_effort:       # (tried in step 1)
        kept = kept_plan()
        if kept is not None and not _headed_into(kept, sensed, sensing, until, first, s):
            return kept
    made = escape()
    if isinstance(made, dict):
        return done(task=plan.task, **made)
    if spare is not None:
        return done(task=plan.task, **spare)
    if kept is not None:
        return kept
    assert outcome is not None
    return failed(outcome[0] + f"; and no escape: {made}", outcome[1])


def _headed_into(kept: SensedPlan, sensed: Sequence[SensedObstacle], sensing: Sensing,
                 until: float, first: int, s: np.ndarray) -> bool:
    """Whether the kept tube may meet where a sensed obstacle is headed over the
    :data:`FORESIGHT` after its certified horizon (``until``, absolute); a closing one
    (:func:`_closing`, towards ``s``) anywhere within its estimated speed too."""
    if not sensed:
        return False
    t_from = until - kept.start
    reach = _reach(kept.task)
    ahead = foresight_boxes(sensed, reach, sensing.dims, kept.start, t_from,
                            t_from + FORESIGHT, first, sensing.velocity_error)
    spec = replace(kept.local, moving_obstacles=kept.local.moving_obstacles + ahead)
    if not check_tube(kept.design.tube, spec).passed:
        return True
    return _pursued(kept.design, kept.start, kept.arrival, kept.task, sensed, sensing, until,
                    s, kept.reached)


def _pursued(design: Design, start: float, arrival: float, task: Spec,
             sensed: Sequence[SensedObstacle], sensing: Sensing, until: float,
             s: np.ndarray, reached: bool = False) -> bool:
    """Whether a tube (``design`` from ``start``, due at ``arrival``, both absolute, s)
    of a robot that has ``reached`` the target, or that is due after ``task``'s prescribed
    time, or holds its goal from ``until`` on, is caught by an obstacle closing on the
    robot at ``s`` (:func:`_closing`) that heads for the tube's box (:func:`_pursuit`):
    its shape meets the box (grown by the robot's radius and ``velocity_error`` times the
    time since) between ``until`` and :data:`FORESIGHT` after it.

    A prediction, not a bound: while a tube is due by ``t_c`` the obstacles' straight
    walks steer it; once its arrival is lost or made (also on the way back to the target
    after an escape), a closing obstacle is taken to turn after the robot (a pursuer),
    and a tube that waits for it is not chosen."""
    if not reached and arrival <= task.prescribed_time and until < arrival:
        return False
    closing = [ob for ob in sensed if _closing(ob, s)]
    if not closing:
        return False
    dims = list(sensing.dims)
    reach = _reach(task)
    enc = robot_tube(design.tube, design.certificate).enclosure
    last = enc.t_start.size - 1

    def box(t: float) -> tuple[np.ndarray, np.ndarray]:
        k = min(last, max(0, int(np.searchsorted(enc.t_start, t - start, side="right")) - 1))
        return enc.lower_min[k][dims], enc.upper_max[k][dims]

    def centre(t: float) -> np.ndarray:
        lo, hi = box(t)
        return (lo + hi) / 2.0

    for ob in closing:
        ahead = FAST_PURSUIT if _fast(ob) else FORESIGHT
        for t, p in _pursuit(ob, sensing, until + ahead, centre):
            lo, hi = box(t)
            gap = float(np.linalg.norm(p - np.clip(p, lo, hi)))
            if t >= until and gap <= ob.extent + reach + sensing.velocity_error * (
                    t - ob.seen_at):
                return True
    return False


def _pursuit(ob: SensedObstacle, sensing: Sensing, t_to: float,
             aim: Callable[[float], np.ndarray]) -> Iterator[tuple[float, np.ndarray]]:
    """``ob`` turning after the robot: its centre at every :data:`HEADED_STEP` from when
    it was seen until ``t_to`` (absolute, s), each step heading for ``aim(t)`` at its
    estimated speed (and ``velocity_error``); ``(t, centre)`` pairs."""
    p = np.asarray(ob.centre, dtype=float)
    step = (_speed(ob) + sensing.velocity_error) * HEADED_STEP
    t = ob.seen_at
    while t <= t_to:
        yield t, p
        towards = aim(t) - p
        far = float(np.linalg.norm(towards))
        p = p + towards * min(1.0, step / far) if far > 0.0 else p
        t += HEADED_STEP


def _speed(ob: SensedObstacle) -> float:
    """The speed of ``ob``'s velocity estimate (0 without one), state units per second."""
    return 0.0 if ob.velocity is None else float(np.linalg.norm(ob.velocity))


def _fast(ob: SensedObstacle) -> bool:
    """Whether ``ob``'s estimate is faster than :data:`CLOSING_SPEED` times
    :data:`~.sensed_path.MIN_SPEED` (a pursuer the robot does not outrun)."""
    return _speed(ob) > CLOSING_SPEED * MIN_SPEED


def _closing(ob: SensedObstacle, point: np.ndarray) -> bool:
    """Whether ``ob``'s velocity estimate points within :data:`CLOSING_ANGLE` of ``point``
    (on the sensing dimensions); a fast one's (:func:`_fast`) within
    :data:`FAST_CLOSING_ANGLE`."""
    if ob.velocity is None:
        return False
    v = np.asarray(ob.velocity, dtype=float)
    towards = np.asarray(point, dtype=float) - np.asarray(ob.centre, dtype=float)
    size = float(np.linalg.norm(v) * np.linalg.norm(towards))
    angle = FAST_CLOSING_ANGLE if _fast(ob) else CLOSING_ANGLE
    return size > 0.0 and float(v @ towards) >= math.cos(angle) * size


def foresight_boxes(sensed: Sequence[SensedObstacle], reach: float, dims: Sequence[int],
                    start: float, t_from: float, t_to: float, first_source: int,
                    velocity_error: float = 0.0, chunk: float = 2 * CHUNK_SECONDS
                    ) -> tuple[MovingObstacle, ...]:
    """Where each sensed obstacle is headed past the certified horizon, as boxes over spans:
    its shape moved along its velocity estimate (standing where it was seen without one),
    grown by ``velocity_error`` times the time since it was seen and by ``reach``.

    Not a reachable set: a new tube is designed to keep clear of these too, when it can,
    so that the next measurement is less likely to find it in an obstacle's way (a plan
    that sees only its certified horizon walks into what comes after it). Its certificate
    proves them missed like any moving obstacle, which the plan's guarantee does not need.

    Parameters
    ----------
    sensed : sequence of SensedObstacle
        The obstacles, on ``dims``.
    reach : float
        The robot's radius, state units.
    dims : sequence of int
        The state dimensions of the obstacles.
    start : float
        The absolute instant of the tube's ``t' = 0``, s.
    t_from, t_to : float
        The span, in the tube's time, s.
    first_source : int
        The obstacle index of the first box.
    velocity_error : float
        ``E``, state units per second.
    chunk : float
        The longest span of one box, s.

    Returns
    -------
    tuple of MovingObstacle
        Boxes that do not move, each present over its span.

    Examples
    --------
    A person seen at 1 s walking at 0.5 m/s, from 1 to 2 s past a tube's start at 2 s:

    >>> from stt_codegen import SensedObstacle
    >>> from stt_codegen.design.sensed import foresight_boxes
    >>> person = SensedObstacle.ball((3.0, 2.0), 0.3, seen_at=1.0, velocity=(0.5, 0.0))
    >>> boxes = foresight_boxes([person], 0.25, (0, 1), 2.0, 1.0, 2.0, 100)
    >>> [(b.active, b.centres[0]) for b in boxes]
    [((1.0, 1.5), (4.125, 2.0)), ((1.5, 2.0), (4.375, 2.0))]
    """
    def box(ob: SensedObstacle, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
        moving = ob if ob.velocity is not None else replace(
            ob, velocity=(0.0,) * len(ob.centre))
        return moving.drift_box(start + a, start + b, 0.0, velocity_error)

    return _span_boxes(sensed, box, reach, dims, t_from, t_to, first_source, chunk)


def _new_local(base: Spec, box: Box, moving: tuple[MovingObstacle, ...],
               prescribed_time: float, goal: Box | None = None) -> Spec:
    """The task of a new tube in its time: from ``box``, within ``prescribed_time``, to the
    target (or to ``goal``), among the known obstacles (``moving`` shifted to its time)."""
    local = replace(base, prescribed_time=prescribed_time, initial_set=box,
                    initial_state=box.center,
                    initial_half_width=tuple((b - a) / 2 for a, b in zip(box.lower,
                                                                         box.upper)),
                    moving_obstacles=moving, target_any_of=())
    if goal is not None:        # the tube ends in the goal's middle, as a spec's default
        local = replace(local, target_set=goal, target_center=goal.center,
                        target_half_width=tuple(DEFAULT_HALF_WIDTH_FRACTION * (b - a) / 2
                                                for a, b in zip(goal.lower, goal.upper)),
                        target_half_width_given=True)
    return local


def _to_target(base: Spec, box: Box, moving: tuple[MovingObstacle, ...],
               boxes: tuple[MovingObstacle, ...], sensing: Sensing, s: np.ndarray,
               t_m: float, t_s: float, remaining: float, first: int,
               state: tuple[np.ndarray, np.ndarray] | None = None
               ) -> dict | tuple[str, str]:
    """A certified tube from ``box`` to the target (arriving later while it leaves the
    region): the new plan's fields, or why not and the failure's kind."""
    rooms = []
    for slower in SLOWER:
        within = remaining * slower
        try:
            made = _new_plan(_new_local(base, box, moving, within), boxes, sensing, s, t_m,
                             t_s, t_s + within, first, state=state)
        except DesignError as exc:
            return (f"no tube from the box at t = {t_s:.4f} s to the target within "
                    f"{within:.4g} s: {exc}", "design")
        if isinstance(made, dict):
            return made
        room, at = made
        rooms.append(f"{room:.3g} at t = {t_s + at:.4f} s within {within:.4g} s")
    return ("the new tube may leave the region no unseen obstacle can reach, even slower "
            "(room " + "; ".join(rooms) + ")", "region")


def _along_path(base: Spec, box: Box, moving: tuple[MovingObstacle, ...],
                boxes: tuple[MovingObstacle, ...], sensed: Sequence[SensedObstacle],
                sensing: Sensing, s: np.ndarray, t_m: float, t_s: float, remaining: float,
                first: int, state: tuple[np.ndarray, np.ndarray] | None = None
                ) -> dict | None:
    """A certified tube from ``box`` to the target along a space-time path among where
    the sensed obstacles are headed (:func:`~.sensed_path.path_design`), held to the
    region certificate: the plan's fields, or ``None``."""
    local = _new_local(base, box, moving, remaining)

    def predict(t_to: float) -> tuple[MovingObstacle, ...]:
        return foresight_boxes(sensed, _reach(base), sensing.dims, t_s, 0.0, t_to,
                               first + len(boxes), sensing.velocity_error, PREDICTION_SPAN)

    found = path_design(local, boxes, predict, sensing.dims,
                        sensing.max_obstacle_speed * (t_s - t_m + sensing.horizon))
    if found is None:
        return None
    # a late path's task is due when it arrives (the next checks hold it to that)
    local = replace(local, prescribed_time=found.tube.prescribed_time)
    arrival = t_s + found.tube.segments[-1].end
    try:
        made = _new_plan(local, boxes, sensing, s, t_m, t_s, arrival, first, found=found,
                         state=state)
    except DesignError:
        return None
    return made if isinstance(made, dict) else None


def _new_plan(local: Spec, boxes: tuple[MovingObstacle, ...], sensing: Sensing,
              s: np.ndarray, t_m: float, t_s: float, arrival: float, first: int,
              goal: Box | None = None, found: Design | None = None,
              state: tuple[np.ndarray, np.ndarray] | None = None, proved: bool = True
              ) -> dict | tuple[float, float]:
    """A new tube for ``local`` designed against the sensed obstacles' ``boxes`` too (or
    ``found``, already certified against them), held to the region certificate and, from
    where the state may be at the switch (``state``, :mod:`.sensed_switch`), to the
    sampled-data proof: the plan's fields, or the room and where it is smallest (in the
    tube's time) when the tube leaves the region. :class:`DesignError` when no tube is
    designed or (``proved``) its sampled loop is not proved from the switch; without
    ``proved`` such a tube carries no ``state_bounds``."""
    new = found or design_tube(replace(local, moving_obstacles=local.moving_obstacles + boxes))
    room, at = region_margin(new, sensing, _reach(local), t_s, t_m, s, 0.0, sensing.horizon)
    if room <= ROUNDING_MARGIN:
        return room, at
    initial = switch_error(new, state)
    bounds, why = (proved_error(new, local, initial) if initial is not None else
                   (None, "the state at the switch cannot meet the switch test"))
    if bounds is None and proved:
        raise DesignError(f"a tube from the switch at t = {t_s:.4f} s: {why}",
                          kind=FailureKind.SAMPLING_RATE, tried=new.tube)
    return dict(design=new, local=local, start=t_s, certified_from=t_s, switch_at=t_s,
                arrival=arrival, kept=False, sensed_margin=_sensed_margin(new, first),
                region_margin=room, goal=goal, state_bounds=bounds)


def _taking_over(plan: SensedPlan, t: float, s: np.ndarray, t_m: float,
                 sensing: Sensing) -> tuple[Box, np.ndarray, Box | None]:
    """Where a new tube taking over from ``plan`` at ``t`` (absolute, a sample) starts:
    the active tube's box then, where the robot will be then (:func:`_predicted`, from
    ``s`` measured at ``t_m``), and the spec's ``d_0`` around that point
    (:func:`_switch_box`)."""
    active = _box_at(plan, t - plan.start, plan.task.state_space)
    point = _predicted(plan, active, s, t_m, sensing)
    return active, point, _switch_box(plan.task, active, point, sensing)


def _predicted(plan: SensedPlan, active: Box, s: np.ndarray, t_m: float,
               sensing: Sensing) -> np.ndarray:
    """Where the reference point will be at the switch: ``s`` moved as the plan's tube's
    centre moves from ``t_m`` to ``t_s`` (the robot follows its tube); the tube's centre at
    ``t_s`` for a plan that takes over after ``t_m`` (the robot is not on it yet)."""
    dims = list(sensing.dims)
    if t_m < plan.start:
        return np.asarray(active.center, dtype=float)[dims]
    then = _box_at(plan, t_m - plan.start, plan.task.state_space)
    return s + (np.asarray(active.center)[dims] - np.asarray(then.center)[dims])


def _switch_box(base: Spec, active: Box, point: np.ndarray, sensing: Sensing) -> Box | None:
    """A box around ``point``, where the robot will be at the switch (:func:`_predicted`),
    of the spec's initial half width on the sensing dimensions, inside the active tube's
    box there; ``None`` when it is not smaller than that box. A tube from it is sound
    whatever the prediction's error: the switch is refused where the state is not in it."""
    lo, hi = list(active.lower), list(active.upper)
    for k, d in enumerate(sensing.dims):
        w = base.initial_half_width[d]
        a, b = max(lo[d], point[k] - w), min(hi[d], point[k] + w)
        if not b > a:
            return None
        lo[d], hi[d] = a, b
    box = Box(tuple(lo), tuple(hi))
    return None if box == active else box


def _escape(base: Spec, box: Box, moving: tuple[MovingObstacle, ...],
            boxes: tuple[MovingObstacle, ...], sensed: Sequence[SensedObstacle],
            sensing: Sensing, s: np.ndarray, t_m: float, t_s: float, first: int,
            point: np.ndarray, state: tuple[np.ndarray, np.ndarray] | None = None,
            proved: bool = True, chasers: Sequence[SensedObstacle] = (),
            going: tuple | None = None) -> dict | str:
    """A certified tube from ``box`` to a temporary goal near ``point`` (where the robot
    will be at the switch), reached in :data:`ESCAPE_TIME` and then held: the plan's
    fields, or why there is none.

    Each escape is the paper's tube (``tube.method = "paper"``: one segment, with
    circumvents, and the moving-obstacle design's swept step), not a via-point search. The
    goals are boxes of the spec's initial half width around ``point`` and around the
    points :data:`ESCAPE_DISTANCES` away in :data:`ESCAPE_DIRECTIONS` directions, inside
    the state space and clear of the static obstacles, ranked by their distance from where
    every sensed obstacle is headed from the switch until the tube has arrived plus the
    horizon (:func:`_headed_clearance`; from an obstacle closing on the robot at ``s`` or at
    ``point``, :func:`_closing`, taken to turn after the robot on its way there and, a
    slow one, while it holds the goal for :data:`FORESIGHT` more, :func:`_pursuit_clearance`)
    and from the state space's boundary (the largest first, up to
    :data:`ESCAPE_CLEARANCE`), then by their distance to the target; at most
    :data:`MAX_ESCAPES` designs.

    An *evasion* runs from ``chasers`` (:func:`~.sensed_evade.pursuers`): going on with
    ``going``'s move (the active tube and the switch in its time,
    :func:`~.sensed_blend.continuing`) where it moves, its goals are
    :data:`~.sensed_evade.EVADE_DISTANCES` from where that move ends (else from ``point``),
    reached in :data:`~.sensed_evade.EVADE_TIME`, ranked by their least clearance from the
    chasers as the robot runs on past them (:func:`~.sensed_evade.evasion_clearance`) and
    from the other obstacles as above, counted up to :data:`~.sensed_evade.EVADE_SAFE` to
    the tenth, then by their distance to the point ahead on the evasion's ring
    (:func:`~.sensed_evade.ring_ahead`).
    """
    dims = list(sensing.dims)
    reach = _reach(base)
    half = np.array([base.initial_half_width[d] for d in dims])
    target = np.asarray(base.target_center)[dims]
    closing = [(ob, _closing(ob, point) or _closing(ob, s)) for ob in sensed]
    ranked = []
    directions = escape_directions(len(dims))
    if chasers:
        lower = np.array([base.state_space.lower[d] for d in dims]) + half
        upper = np.array([base.state_space.upper[d] for d in dims]) - half
        others = [(ob, heads) for ob, heads in closing if not any(ob is c for c in chasers)]
    on = going_on(*going) if (chasers and going is not None) else None
    if on is not None and on.end > EVADE_TIME:
        on = None               # a longer move than an evasion's: not gone on with
    origin = point.astype(float)
    if on is not None:
        origin = np.array([(on.lower_to[d] + on.upper_to[d]) / 2 for d in dims])
    if chasers:
        ahead = ring_ahead(base, dims, origin, chasers, origin - point.astype(float))
    for distance in EVADE_DISTANCES if chasers else ESCAPE_DISTANCES:
        for direction in directions if distance > 0.0 else directions[:1]:
            p = origin + (distance * direction if distance > 0.0 else 0.0)
            lo, hi = list(box.lower), list(box.upper)
            for j, d in enumerate(dims):
                lo[d], hi[d] = p[j] - half[j], p[j] + half[j]
            goal = Box(tuple(lo), tuple(hi))
            if not base.state_space.contains_box(goal) or _meets_static(base, goal, reach):
                continue
            if chasers:
                speed = distance / (sensing.period if on is not None else EVADE_TIME)
                carry = None if on is None else (origin - point, sensing.period)
                clear = min([evasion_clearance(ob, s, t_m, point, t_s, direction, speed,
                                               lower, upper, sensing, carry)
                             for ob in chasers]
                            + [_goal_clearance(ob, heads, point, p, t_s, base.state_space,
                                               reach, sensing) for ob, heads in others])
                ranked.append((-round(min(clear, EVADE_SAFE), 1),
                               float(np.linalg.norm(p - ahead)), len(ranked), goal))
                continue
            clear = min((_goal_clearance(ob, heads, point, p, t_s, base.state_space, reach,
                                         sensing) for ob, heads in closing),
                        default=math.inf) - reach - float(np.linalg.norm(half))
            # a goal near the state space's boundary leaves fewer ways out next time (a
            # corner is a trap): its room to the boundary counts as a clearance too
            room = min(min(p[j] - base.state_space.lower[d], base.state_space.upper[d] - p[j])
                       for j, d in enumerate(dims))
            clear = min(clear, room)
            ranked.append((-min(clear, ESCAPE_CLEARANCE),
                           float(np.linalg.norm(p - target)), len(ranked), goal))
    ranked.sort(key=lambda r: r[:3])
    reasons = []
    for _, _, _, goal in ranked[:MAX_ESCAPES]:
        # the straight tube (and its circumvents) only: a goal it cannot reach is left for
        # the next one, not searched around (re-timings and detours take seconds)
        local = _new_local(replace(base, tube=replace(base.tube, method="paper")), box,
                           moving, EVADE_TIME if chasers else ESCAPE_TIME, goal)
        if on is not None:
            try:
                template = design_tube(local)
                against = replace(local, moving_obstacles=local.moving_obstacles + boxes)
                went = continuing(going[0], going[1], template, against)
                made = (None if went is None else
                        _new_plan(local, boxes, sensing, s, t_m, t_s, t_s + EVADE_TIME, first,
                                  goal, found=went, state=state, proved=proved))
            except DesignError:
                made = None
            if isinstance(made, dict):
                return made
        try:
            made = _new_plan(local, boxes, sensing, s, t_m, t_s,
                             t_s + (EVADE_TIME if chasers else ESCAPE_TIME), first,
                             goal, state=state, proved=proved)
        except DesignError as exc:
            reasons.append(f"{exc.kind}")
            continue
        if isinstance(made, dict):
            return made
        reasons.append("region")
    if not ranked:
        return "no temporary goal inside the state space and clear of the obstacles"
    return (f"{min(len(ranked), MAX_ESCAPES)} temporary goals tried, none certified ("
            + ", ".join(str(r) for r in reasons) + ")")


def escape_directions(n: int) -> np.ndarray:
    """The unit directions of an escape's temporary goals on ``n`` sensing dimensions
    (:func:`_escape`): :data:`ESCAPE_DIRECTIONS` evenly spaced on the first two (their
    first coordinates on one); with a third, as many again at 45 degrees up and down,
    half of them each, and straight up and down it (a drone steps over or under a ball
    as well as around it); 0 on the others.

    Parameters
    ----------
    n : int
        The number of sensing dimensions (``len([sensing] dims)``), at least 1.

    Returns
    -------
    ndarray, shape (D, n)
        ``D = ESCAPE_DIRECTIONS`` on one or two dimensions, ``2 ESCAPE_DIRECTIONS + 2`` on
        three or more.
    """
    rows = [(math.cos(2.0 * math.pi * k / ESCAPE_DIRECTIONS),
             math.sin(2.0 * math.pi * k / ESCAPE_DIRECTIONS), 0.0)
            for k in range(ESCAPE_DIRECTIONS)]
    if n >= 3:
        tilt, half = math.sqrt(0.5), ESCAPE_DIRECTIONS // 2
        for up in (1.0, -1.0):
            rows += [(tilt * math.cos(2.0 * math.pi * k / half),
                      tilt * math.sin(2.0 * math.pi * k / half), up * tilt)
                     for k in range(half)]
        rows += [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    out = np.zeros((len(rows), n))
    out[:, :min(n, 3)] = np.array(rows)[:, :min(n, 3)]
    return out


def _best_effort(plan: SensedPlan, t_m: float, position: Sequence[float],
                 sensed: Sequence[SensedObstacle]) -> SensedPlan | None:
    """:attr:`ReplanFailure.fallback` for a measurement at ``t_m`` (``sensed`` and the
    reference point at ``position``, checked by :func:`_replan`), or ``None``: an escape
    (:func:`_escape`) that takes over at the switch ``t_s`` or, later, at the first sample
    from which ``plan`` is no longer certified. It avoids each sensed obstacle's reachable
    set over the horizon; where that meets the box the escape starts from (no tube avoids
    it), where the obstacle is headed (:func:`foresight_boxes`); where that meets it too,
    nothing (the goal's ranking alone keeps away from it). Certified against those boxes,
    against nothing that bounds where the obstacles may be."""
    base = plan.task
    sensing = _sensing(base)
    sensed = _checked(sensed, sensing, t_m)
    s = _position(plan.local, sensing, position)
    rate = base.rate_hz
    t_f = max(switch_time(sensing, t_m, rate),
              math.ceil(plan.guarantee_until * rate - 1e-9) / rate)
    active, point, near = _taking_over(plan, t_f, s, t_m, sensing)
    box = near or active
    reach = _reach(base)
    avoided: list[MovingObstacle] = []
    for ob in sensed:
        for spans in (reachable_boxes([ob], sensing.max_obstacle_speed, reach, sensing.dims,
                                      t_f, 0.0, sensing.horizon, 0, **_drift(sensing)),
                      foresight_boxes([ob], reach, sensing.dims, t_f, 0.0, sensing.horizon, 0,
                                      sensing.velocity_error)):
            if not _meets_start(spans, box):
                avoided.extend(spans)
                break
    first = _first_source(base)
    boxes = tuple(replace(b, source=first + k) for k, b in enumerate(avoided))
    made = _escape(base, box, _shifted(base.moving_obstacles, t_f), boxes, sensed, sensing,
                   s, t_m, t_f, first, point,
                   state_at(plan.state_bounds, base.rate_hz, t_f - plan.start), proved=False)
    if not isinstance(made, dict):
        return None
    return SensedPlan(**dict(made, certified_from=t_f), task=base, measured_at=t_m,
                      guarantee_until=t_f, sensed=sensed, best_effort=True,
                      reached=_reached(plan, s, sensing),
                      chasers=chasing(plan.sensed, plan.chasers, sensed, s, sensing))


def _first_source(spec: Spec) -> int:
    """The obstacle index of the first box standing for a sensed obstacle in a tube
    designed or checked for ``spec`` (past its own obstacles)."""
    return len(spec.unsafe_sets) + len(spec.moving_obstacles) + 1_000


def _reached(plan: SensedPlan, s: np.ndarray, sensing: Sensing) -> bool:
    """:attr:`SensedPlan.reached` for the next plan after ``plan``, the reference point
    at ``s`` (on the sensing dimensions)."""
    target = plan.task.target_set
    return plan.reached or all(target.lower[d] <= s[k] <= target.upper[d]
                               for k, d in enumerate(sensing.dims))


def _meets_start(boxes: Sequence[MovingObstacle], box: Box) -> bool:
    """Whether one of ``boxes`` meets ``box`` at ``t' = 0``."""
    return any(b.meeting_times(box.lower, box.upper, 0.0, 0.0) for b in boxes)


def _goal_clearance(ob: SensedObstacle, closing: bool, point: np.ndarray, goal: np.ndarray,
                    t_s: float, state_space: Box, reach: float, sensing: Sensing) -> float:
    """The least distance between an escape from ``point`` at ``t_s`` to ``goal`` (reached
    :data:`ESCAPE_TIME` later and held) and ``ob`` until the escape's horizon: a
    ``closing`` one turning after the robot (:func:`_pursuit_clearance`; a slow one, not
    :func:`_fast`, also while the goal is held for :data:`FORESIGHT` more), another where
    it is headed (:func:`_headed_clearance`); state units, negative inside. A ranking."""
    later = t_s + ESCAPE_TIME + sensing.horizon
    if closing:
        return _pursuit_clearance(ob, point, goal, t_s, t_s + ESCAPE_TIME,
                                  later + (0.0 if _fast(ob) else FORESIGHT), sensing)
    return _headed_clearance(ob, goal, t_s, later, state_space, reach, sensing)


def _headed_clearance(ob: SensedObstacle, point: np.ndarray, t_from: float, t_to: float,
                      state_space: Box, reach: float, sensing: Sensing) -> float:
    """The least distance from ``point`` to where ``ob`` is headed over ``[t_from, t_to]``
    (absolute, s), sampled every :data:`HEADED_STEP`: its centre moved along its velocity
    estimate (standing without one) and kept inside the walls (the state space of the
    reference point grown by the robot's radius ``reach``) shrunk by its extent,
    less its extent and ``velocity_error`` times the time since it was seen; state units,
    negative inside.

    A ranking, not a reachable set: the distance from the reachable set at ``t_to`` (which
    grows in every direction) ranks a corner that two obstacles are heading into above the
    open floor they are leaving.
    """
    dims = list(sensing.dims)
    lo = np.array([state_space.lower[d] for d in dims]) - reach + ob.extent
    hi = np.array([state_space.upper[d] for d in dims]) + reach - ob.extent
    c = np.asarray(ob.centre, dtype=float)
    v = np.zeros_like(c) if ob.velocity is None else np.asarray(ob.velocity, dtype=float)
    steps = max(1, int(math.ceil((t_to - t_from) / HEADED_STEP)))
    tau = np.maximum(0.0, t_from + (t_to - t_from) * np.arange(steps + 1) / steps
                     - ob.seen_at)
    centres = np.clip(c + tau[:, None] * v, np.minimum(lo, hi), np.maximum(lo, hi))
    gaps = (np.linalg.norm(centres - point, axis=1) - ob.extent
            - sensing.velocity_error * tau)
    return float(gaps.min())


def _pursuit_clearance(ob: SensedObstacle, start: np.ndarray, goal: np.ndarray,
                       t_from: float, t_goal: float, t_to: float, sensing: Sensing) -> float:
    """The least distance between the robot's reference point, moving straight from
    ``start`` at ``t_from`` to ``goal`` at ``t_goal`` and holding it until ``t_to``
    (absolute, s), and ``ob`` turning after it (a pursuer, :func:`_closing`,
    :func:`_pursuit`), less its extent and ``velocity_error`` times the time since it was
    seen; state units, negative inside.

    A ranking, not a bound: it prefers a goal the pursuer reaches late, by a way that
    does not pass it, to the corner behind the robot."""
    def robot(t: float) -> np.ndarray:
        share = min(1.0, max(0.0, (t - t_from) / (t_goal - t_from)))
        return start + share * (goal - start)

    return min((float(np.linalg.norm(robot(t) - p)) - ob.extent
                - sensing.velocity_error * (t - ob.seen_at)
                for t, p in _pursuit(ob, sensing, t_to, robot) if t >= t_from),
               default=math.inf)


def _meets_static(spec: Spec, box: Box, reach: float) -> bool:
    """Whether ``box`` grown by ``reach`` meets a static obstacle of ``spec``."""
    for ob in spec.obstacles:
        if all(box.lower[d] - reach <= hi and lo <= box.upper[d] + reach
               for d, lo, hi in zip(ob.dims, ob.lower, ob.upper)):
            return True
    return False
