"""Prioritized fleet design: each robot's tube avoids the tubes already designed (docs/fleets.md).

Every robot is first designed alone (:func:`~.search.design_tube`, its own certificate and,
with ``[actuator]``, its input proof); a robot with no tube alone is refused as such. The
robots are then placed one at a time in a priority order (:func:`priority_order`: a robot
whose way crosses another's target goes before it, one whose way crosses another's start
after it, then the robots whose proofs cost most, then the longer trips). A robot keeps its
tube designed alone when the pair certificate (:func:`~.certificate.fleet.pair_margin`)
proves it apart from every placed tube that a space-time index (:mod:`.fleet_index`) finds
near it (with ``[actuator]``, where that tube's input is not proved within the bound, its
designs with the bound instead, :func:`_alone`); else its via boxes are re-timed
(:func:`~.moving.retimed_design`: waits at its start box, which is its start delay, or at a
via box) against the placed tubes near its way, as
moving boxes over at most :data:`CHUNK_SECONDS` each, first through its own via boxes, then
through via boxes planned clear of the other robots' docks; each re-timed tube is accepted
only when its own check, its input proof and the pair certificate against every placed tube
near it pass. A robot that finds no tube is moved to the front and the fleet is placed
again, each robot moved at most :data:`MOVES_PER_ROBOT` times and no order tried twice (a
robot moved once that fails behind a robot moved after it goes before it); a robot placed
in the order tried before keeps that placement where it still holds (:func:`_kept_from`).
Every pair of the fleet is then certified by :func:`certify_fleet` on the robots' own
certificates; nothing is accepted on the planner's word.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

import numpy as np

from ..display import Rows, text
from ..errors import DesignError
from ..spec.fleet import FleetRobot, FleetSpec, load_fleet
from ..spec.loader import Obstacle, Spec
from ..spec.motion import MovingObstacle
from ..spec.variants import variant_of
from ..tube.parameters import CRUISE, ReachSegment
from .certificate.fleet import PairMargin, RobotTube, pair_margin, robot_tube
from .failures import FailureKind, without_advice
from .fleet_index import Chunks, TubeIndex, chunks
from .fleet_paths import Reservations, SpaceTimeGrid, space_time_path, space_time_segments
from .gain import with_gain
from .moving import levelled_timing, retimed_design
from .result import METHOD_VIA, Design, TubeCheck
from .search import check_tube, design_tube

__all__ = ["CHUNK_SECONDS", "DETOURS", "DETOUR_SECONDS", "FLEET_TIME_STEPS", "INDEX_CELL",
           "INDEX_SECONDS", "LEG_METRES", "MOVES_PER_ROBOT", "PLANNER_SPACE_TIME", "PLANNER_TUBES",
           "SCREEN_INTERVALS", "FleetDesign", "Placement", "certify_fleet", "design_fleet",
           "enclosed", "plan_way", "priority_order", "tube_obstacles"]

#: The longest time span of one box standing for another robot's tube in a re-timing,
#: seconds.
CHUNK_SECONDS = 0.5
#: How many times one robot may be moved to the front of the order (an order is never
#: tried twice).
MOVES_PER_ROBOT = 2
#: The longest time span of one box of a placed tube in the space-time index, seconds.
INDEX_SECONDS = 1.0
#: The space-time index's grid cell, state units (metres).
INDEX_CELL = 2.0
#: Steps of a placement's re-timing grid over ``[0, t_c]`` (:func:`~.moving.retime`): finer
#: than a single spec's (:data:`~.moving.TIME_STEPS`, 60), since a robot waits for other
#: robots' tubes that pass a point in a second or so, on trips of a minute or two.
FLEET_TIME_STEPS = 120
#: The longest leg of a re-timed way, state units (metres): a longer leg is cut into
#: pieces on the same line, between which the re-timing may wait.
LEG_METRES = 2.0
#: Detours a robot plans around the placed robots its re-timed way still meets, at most.
DETOURS = 3
#: A detour plans around the other robot's tube over the clash's interval widened by this
#: much on each side, seconds.
DETOUR_SECONDS = 2.0
#: The space-time path's speed: this many times the robot's way's mean speed (its length
#: over ``t_c``), within [MIN_SPEED, MAX_SPEED] (state units per second).
SPEED_FACTOR, MIN_SPEED, MAX_SPEED = 2.0, 0.5, 1.5
#: With ``[actuator]``, a space-time path whose input is not proved within the bound is
#: planned again at these fractions of its speed, in turn (a slower path asks less).
PATH_SLOWER = (1.0, 0.75, 0.5)
#: The placed tubes' boxes on the space-time grid span at most this long, seconds.
STEP_SECONDS = 0.5
#: ``Design.motion`` of a tube along a space-time path.
MOTION_SPACE_TIME_PATH = "space-time path"
#: The refinement budget of a pair checked while a robot is placed (a candidate the pair
#: certificate does not prove apart within it is only a candidate lost; the fleet's own
#: certificate, :func:`certify_fleet`, has the full budget).
SCREEN_INTERVALS = 4000
#: ``design_fleet``'s planners: the tubes kept, re-timed or planned in space-time (the
#: module notes), or every robot's tube along its space-time A* path only, the robots
#: longest trip first (classic prioritized planning, the comparison's baseline).
PLANNER_TUBES, PLANNER_SPACE_TIME = "tubes", "space-time A*"


@dataclass(frozen=True)
class Placement:
    """The cost of placing one robot among the robots placed before it.

    Attributes
    ----------
    robot : str
        Its name.
    placed : int
        The robots placed before it (in the order that succeeded).
    near : int
        Those the space-time index finds near its way (its tube designed alone), whose
        tubes its placement is checked against.
    cpu_s : float
        Processor time of its placement (its checks, re-timings, paths and the pair
        certificates against the robots near it), seconds.
    """

    robot: str
    placed: int
    near: int
    cpu_s: float


@dataclass(frozen=True)
class FleetDesign:
    """A certified design of every robot of a fleet.

    Attributes
    ----------
    fleet : FleetSpec
    designs : dict of str to Design
        Per robot name (in the fleet's order), its certified tube; its spec holds the
        robots designed before it as moving obstacles.
    order : tuple of str
        The priority order the robots were designed in.
    pairs : tuple of PairMargin
        Every pair's certified separation for every ``t >= 0``, narrowest first.
    design_time_s : float
        Wall time of the whole design, seconds (every order tried).
    reordered : tuple of str
        The robots moved to the front after they found no tube, in turn.
    placements : tuple of Placement
        Per robot, in the order that succeeded, what its placement cost and how many
        placed robots were near it.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> sorted(fleet.designs), fleet.order
    (['east', 'west'], ('east', 'west'))
    >>> print(fleet.summary())                                      # doctest: +ELLIPSIS
    Fleet swap-fleet: designed in ... s
      robots: ...
    """

    fleet: FleetSpec
    designs: dict[str, Design]
    order: tuple[str, ...]
    pairs: tuple[PairMargin, ...]
    design_time_s: float = field(default=0.0, compare=False)
    reordered: tuple[str, ...] = ()
    placements: tuple[Placement, ...] = field(default=(), compare=False)

    @property
    def certified(self) -> bool:
        """Every robot's certificate and every pair's separation pass."""
        return (all(d.certificate.passed for d in self.designs.values())
                and all(p.passed for p in self.pairs))

    @property
    def narrowest(self) -> PairMargin | None:
        """The pair with the smallest certified separation (``None`` for one robot)."""
        return self.pairs[0] if self.pairs else None

    def summary_rows(self) -> Rows:
        """The summary as rows (label, value)."""
        rows: list[tuple[str, str]] = [
            ("robots", f"{len(self.designs)}, designed in the order {', '.join(self.order)}"
                       + (f" (moved to the front: {', '.join(self.reordered)})"
                          if self.reordered else ""))]
        for name, d in self.designs.items():
            rows.append((name, f"{d.spec.variant}, {d.method}"
                               + (f" ({d.motion})" if d.motion else "")
                               + f", {len(d.tube.segments)} segments to t_c = "
                               f"{d.spec.prescribed_time:g} s, certified "
                               f"{'yes' if d.certificate.passed else 'no'}"))
        if self.pairs:
            rows.append(("narrowest pair", self.pairs[0].detail))
        rows.append(("certified", f"{'yes' if self.certified else 'no'}, "
                                  f"{len(self.pairs)} pairs for every t >= 0"))
        return rows

    def summary(self) -> str:
        """The summary, one line per robot and the narrowest pair."""
        return text(f"Fleet {self.fleet.name}: designed in {self.design_time_s:.1f} s",
                    self.summary_rows())


def _trip(robot: FleetRobot) -> float:
    """The straight distance from ``x(0)`` to the target's centre, state units."""
    spec = robot.spec
    return math.dist(spec.initial_state, spec.target_center)


def _grown(box, dims: Sequence[int], grow: float) -> tuple[np.ndarray, np.ndarray]:
    """A box (``lower``, ``upper`` over every state dimension) on ``dims``, grown."""
    d = list(dims)
    return np.asarray(box.lower)[d] - grow, np.asarray(box.upper)[d] + grow


def _crosses(way: Chunks, lower: np.ndarray, upper: np.ndarray) -> bool:
    """Whether some box of ``way`` meets ``[lower, upper]`` (in space)."""
    return bool(np.any(np.all((way.lower <= upper) & (way.upper >= lower), axis=1)))


def priority_order(fleet: FleetSpec,
                   tubes: Mapping[str, RobotTube] | None = None) -> list[FleetRobot]:
    """The robots by the tool's priority rule.

    With each robot's tube designed alone: robot ``a`` goes before robot ``b`` when ``a``'s
    tube before its ``t_c`` (its way) meets ``b``'s target box grown by both reaches (``a``
    passes before ``b`` parks there), or when ``b``'s way after ``t = 0`` meets ``a``'s
    start box so grown (``b`` passes after ``a`` has left); among the robots free of such
    constraints, those with ``[actuator]`` first (re-timing them asks for a new input
    proof, the dearest part of a design), then the longest straight trip (from ``x(0)``
    to the target's centre), then the fleet's order. Where the constraints form a cycle
    (no order keeps them all), the robot with the fewest constraints left goes next.
    Without ``tubes``: the longest straight trip first, ties in the fleet's order.

    Parameters
    ----------
    fleet : FleetSpec
    tubes : mapping of str to RobotTube, optional
        Each robot's tube designed alone (:func:`enclosed`), by name.

    Returns
    -------
    list of FleetRobot

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.load_fleet("swap-fleet")
    >>> [r.name for r in priority_order(fleet)]
    ['east', 'west']
    """
    def key(robot: FleetRobot) -> tuple:
        return (robot.spec.input_bound is None, -round(_trip(robot), 9), robot.index)

    robots = list(fleet.robots)
    if tubes is None:
        return sorted(robots, key=lambda r: (-round(_trip(r), 9), r.index))
    ways = {r.name: chunks(tubes[r.name], r.dims, INDEX_SECONDS) for r in robots}
    before: dict[str, set[str]] = {r.name: set() for r in robots}   # b: the robots before b
    for a in robots:
        way_a = ways[a.name]
        moving = np.isfinite(way_a.t_end)
        way_a = Chunks(way_a.t_start[moving], way_a.t_end[moving], way_a.lower[moving],
                       way_a.upper[moving])
        for b in robots:
            if b is a:
                continue
            grow = a.reach + b.reach
            if _crosses(way_a, *_grown(b.spec.target_set, a.dims, grow)):
                before[b.name].add(a.name)             # a passes b's target before b parks
            way_b = ways[b.name]
            later = way_b.t_start > 0.0
            way_b = Chunks(way_b.t_start[later], way_b.t_end[later], way_b.lower[later],
                           way_b.upper[later])
            if _crosses(way_b, *_grown(a.spec.initial_set, a.dims, grow)):
                before[b.name].add(a.name)             # b passes a's start after a left
    order: list[FleetRobot] = []
    left = sorted(robots, key=key)
    while left:
        done = {r.name for r in order}
        free = [r for r in left if before[r.name] <= done]
        nxt = free[0] if free else min(left, key=lambda r: (len(before[r.name] - done),
                                                            key(r)))
        order.append(nxt)
        left.remove(nxt)
    return order


def enclosed(design: Design, span: float = CHUNK_SECONDS) -> RobotTube:
    """A design's tube enclosed on intervals of at most ``span`` seconds (or one sample).

    Parameters
    ----------
    design : Design
        A certified design (its certificate's partition is cut further).
    span : float
        The longest bounded interval, seconds.

    Returns
    -------
    RobotTube
    """
    return robot_tube(design.tube, design.certificate).finer(span)


def tube_obstacles(tube: RobotTube, reach: float, dims: Sequence[int], first_source: int,
                   chunk: float = CHUNK_SECONDS) -> tuple[MovingObstacle, ...]:
    """A designed robot's tube as moving obstacles for another robot.

    Parameters
    ----------
    tube : RobotTube
        The robot's enclosed tube (:func:`enclosed`).
    reach : float
        Both robots' reaches added, state units: each box is grown by it on ``dims``.
    dims : sequence of int
        The bodies' state dimensions.
    first_source : int
        The obstacle index of the first box (the next ones follow).
    chunk : float
        The longest time span of one box, seconds.

    Returns
    -------
    tuple of MovingObstacle
        Boxes that do not move, each present over its span (``active``, closed); together
        they cover the tube grown by ``reach`` at every ``t >= 0`` (the last one until
        ``inf``).
    """
    c = chunks(tube, dims, chunk)
    lo, hi = c.lower - reach, c.upper + reach
    return tuple(MovingObstacle(
        source=first_source + k, dims=tuple(int(d) for d in dims),
        half_size=tuple(float(v) for v in (hi[k] - lo[k]) / 2), times=(float(c.t_start[k]),),
        centres=(tuple(float(v) for v in (hi[k] + lo[k]) / 2),),
        active=(float(c.t_start[k]), float(c.t_end[k])), motion="still")
        for k in range(c.t_start.size))


def certify_fleet(fleet: FleetSpec, designs: Mapping[str, Design],
                  tubes: Mapping[str, RobotTube] | None = None) -> tuple[PairMargin, ...]:
    """Every pair's separation, certified for every ``t >= 0`` from the robots' certificates.

    Parameters
    ----------
    fleet : FleetSpec
        The robots (names, reaches, body dimensions).
    designs : mapping of str to Design
        Each robot's design, by name (designed together or apart).
    tubes : mapping of str to RobotTube, optional
        The robots' tubes already enclosed (:func:`enclosed`); computed when omitted.

    Returns
    -------
    tuple of PairMargin
        Per pair, narrowest first (:func:`~.certificate.fleet.pair_margin`).

    Examples
    --------
    Two robots designed apart, each certified, whose tubes cross:

    >>> import stt_codegen as stt
    >>> from stt_codegen.design.fleet import certify_fleet
    >>> fleet = stt.load_fleet("swap-fleet")
    >>> alone = {r.name: stt.design_tube(r.spec) for r in fleet.robots}
    >>> print(certify_fleet(fleet, alone)[0].detail)                # doctest: +ELLIPSIS
    east and west: their tubes, grown by both radii, may meet on [...] s (separation ...)
    """
    tubes = dict(tubes or {})
    for name, design in designs.items():
        if name not in tubes:
            tubes[name] = enclosed(design)
    robots = fleet.robots
    pairs = []
    for a in range(len(robots)):
        for b in range(a + 1, len(robots)):
            ra, rb = robots[a], robots[b]
            pairs.append(pair_margin((ra.name, rb.name), (tubes[ra.name], tubes[rb.name]),
                                     (ra.reach, rb.reach), ra.dims))
    return tuple(sorted(pairs, key=lambda p: p.margin))


@dataclass
class _Placing:
    """What the placement of one order keeps: each robot's way (its planned design, by
    name, computed once), each robot's designs with ``[actuator]`` (by name, computed
    once when first asked: :func:`_alone`), the robots placed
    so far (design and enclosed tube, by name) and their index."""

    fleet: FleetSpec
    ways: dict[str, tuple[Design, RobotTube]]
    alone: dict[str, tuple[Design, ...]] = field(default_factory=dict)
    placed: dict[str, tuple[FleetRobot, Design, RobotTube]] = field(default_factory=dict)
    index: TubeIndex = field(default_factory=lambda: TubeIndex(INDEX_CELL))
    grids: dict[str, SpaceTimeGrid] = field(default_factory=dict)
    planner: str = PLANNER_TUBES
    log: list[Placement] = field(default_factory=list)

    @property
    def widest(self) -> float:
        """The largest reach of a placed robot (0 before the first)."""
        return max((r.reach for r, _, _ in self.placed.values()), default=0.0)


def _free(spec: Spec) -> Spec:
    """``spec`` without ``[actuator]``: the tube's design, whose input proof comes once, on
    the tube kept (:func:`_proved`)."""
    return spec.without_actuator()


def _docks(robot: FleetRobot, fleet: FleetSpec) -> tuple[Obstacle, ...]:
    """Every other robot's start and target box, grown by both reaches, on the body
    dimensions, where it misses ``robot``'s own start and target (as obstacles of its
    spec, numbered after them)."""
    spec = robot.spec
    mine = [_grown(box, robot.dims, 0.0) for box in (spec.initial_set, spec.target_set)]
    docks: list[Obstacle] = []
    for other in fleet.robots:
        if other is robot:
            continue
        for box in (other.spec.initial_set, other.spec.target_set):
            lo, hi = _grown(box, robot.dims, robot.reach + other.reach)
            if any(np.all(lo <= m_hi) and np.all(hi >= m_lo) for m_lo, m_hi in mine):
                continue
            docks.append(Obstacle(tuple(float(v) for v in lo), tuple(float(v) for v in hi),
                                  tuple(robot.dims), len(spec.unsafe_sets) + len(docks)))
    return tuple(docks)


def plan_way(robot: FleetRobot, fleet: FleetSpec) -> Design:
    """``robot``'s way: its via design (without ``[actuator]``; with it, cruise legs) on
    its spec with every other robot's start and target box as obstacles (:func:`_docks`: a
    way that crosses no dock, so no robot waiting at its start or parked at its target
    stands in it), else its design alone without ``[actuator]``.

    Parameters
    ----------
    robot : FleetRobot
    fleet : FleetSpec

    Returns
    -------
    Design
        For ``robot.spec`` without ``[actuator]`` when the way crosses docks, or for that
        spec with the docks as obstacles; not yet a design of ``robot.spec`` (placing it
        checks it again, with its input proof).

    Raises
    ------
    DesignError
        The robot has no tube even alone (without ``[actuator]``).
    """
    spec = _free(robot.spec)
    try:
        return design_tube(_via_planning(robot, spec, _docks(robot, fleet)))
    except DesignError:
        pass
    try:
        return design_tube(spec)
    except DesignError as exc:
        raise DesignError(f"robot {robot.name} has no tube even alone: {exc}",
                          kind=exc.kind, tried=exc.tried) from None


def _clash(robot: FleetRobot, tube: RobotTube, near: Sequence[str], placing: _Placing,
           max_intervals: int = SCREEN_INTERVALS) -> PairMargin | None:
    """The first pair of ``robot`` (tube ``tube``) and a robot of ``near`` not certified
    apart, or ``None``."""
    for name in near:
        other, _, placed = placing.placed[name]
        m = pair_margin((other.name, robot.name), (placed, tube), (other.reach, robot.reach),
                        robot.dims, max_intervals)
        if not m.passed:
            return m
    return None


def _timing_spec(robot: FleetRobot, way: Chunks, placing: _Placing) -> Spec:
    """``robot``'s spec with, as moving obstacles, the placed tubes near its via boxes
    (``way``: boxes holding the tube through them; in space, whenever) as boxes over at
    most :data:`CHUNK_SECONDS`, each grown by both reaches and kept only where it comes
    near those boxes (the re-timing's input)."""
    spec = robot.spec
    grow = robot.reach + placing.widest
    extra: list[MovingObstacle] = []
    first = len(spec.unsafe_sets) + len(spec.moving_obstacles)
    dims = tuple(int(d) for d in robot.dims)
    for name in placing.index.near(way, grow, timed=False):
        other, _, tube = placing.placed[name]
        c = chunks(tube, robot.dims, CHUNK_SECONDS)
        reach = other.reach + robot.reach
        lo, hi = c.lower - reach, c.upper + reach
        near = np.any(np.all((way.lower[None, :, :] <= hi[:, None, :])
                             & (way.upper[None, :, :] >= lo[:, None, :]), axis=2), axis=1)
        for k in np.flatnonzero(near):
            extra.append(MovingObstacle(
                source=first + len(extra), dims=dims,
                half_size=tuple(float(v) for v in (hi[k] - lo[k]) / 2),
                times=(float(c.t_start[k]),),
                centres=(tuple(float(v) for v in (hi[k] + lo[k]) / 2),),
                active=(float(c.t_start[k]), float(c.t_end[k])), motion="still"))
    return replace(spec, moving_obstacles=spec.moving_obstacles + tuple(extra))


def _profile(robot: FleetRobot) -> str:
    """The via legs' profile: with ``[actuator]`` (and no tasks), cruise legs (peak rate
    1.25 times the mean, not 1.875), as the bound's own procedure tries them
    (:func:`~.actuator.slower_variants`); else the spec's."""
    spec = robot.spec
    return (CRUISE if spec.input_bound is not None and not spec.tasks
            else spec.tube.via_profile)


def _via_planning(robot: FleetRobot, spec: Spec,
                  obstacles: tuple[Obstacle, ...] = ()) -> Spec:
    """``spec`` planned as a via design with ``robot``'s legs (:func:`_profile`), with
    ``obstacles`` added (numbered after the spec's)."""
    return replace(spec, obstacles=spec.obstacles + obstacles,
                   tube=replace(spec.tube, method=METHOD_VIA, via_profile=_profile(robot)))


def _own_via(robot: FleetRobot) -> Design | None:
    """``robot``'s via design on its own spec (no ``[actuator]``), ``None`` when there is
    none."""
    spec = _free(robot.spec)
    try:
        return design_tube(_via_planning(robot, spec))
    except DesignError:
        return None


def _alone(robot: FleetRobot, placing: _Placing) -> tuple[Design, ...]:
    """``robot``'s designs with its ``[actuator]`` (:func:`~.search.design_tube`: the bound's
    procedure slows the tube until its input proof keeps it), computed once per fleet
    design: where its design alone crosses other robots' docks (:func:`_docks`), first its
    design with those docks as obstacles (when there is one), then its design alone; none
    when it has no design alone. The first is a design of a spec with more obstacles than
    ``robot.spec``, not yet one of ``robot.spec``."""
    if robot.name not in placing.alone:
        spec = robot.spec
        designs: list[Design] = []
        with without_advice():                  # a refusal's advice is not read here
            try:
                alone = design_tube(spec)
            except DesignError:
                alone = None
            if alone is not None:
                way = chunks(enclosed(alone), robot.dims, INDEX_SECONDS)
                first = len(spec.unsafe_sets)
                crossed = tuple(replace(dock, source=first + k) for k, dock in enumerate(
                    d for d in _docks(robot, placing.fleet)
                    if _crosses(way, np.array(d.lower), np.array(d.upper))))
                if crossed:
                    try:
                        designs.append(design_tube(_via_planning(robot, spec, crossed)))
                    except DesignError:
                        pass
                designs.append(alone)
        placing.alone[robot.name] = tuple(designs)
    return placing.alone[robot.name]


def _proved(design: Design, spec: Spec) -> Design | None:
    """``design`` as a design of ``spec`` with its ``[actuator]`` proof (the variant's
    role ``within_bound`` on this tube alone: the bound carried as that variant carries
    it), ``None`` when the proof fails; ``design`` for ``spec`` without ``[actuator]``."""
    if spec.input_bound is None:
        return replace(design, spec=spec)
    given: list[Design] = []

    def this_tube(free: Spec) -> Design:
        # the bound's procedure tries slower variants after a proof that fails; each would
        # be this same tube proved again, so there is none
        if given:
            raise DesignError("the fleet proves the tube it placed, no slower variant",
                              kind=FailureKind.FLEET)
        given.append(replace(design, spec=free))
        return given[0]

    with without_advice():
        try:
            return variant_of(spec).entry("within_bound")(spec, this_tube)
        except DesignError:
            return None


def _pieces(via: Design, spec: Spec) -> Design:
    """``via`` with every leg longer than :data:`LEG_METRES` cut into pieces along the same
    straight line (the same boxes, each piece its own profile over its share of the leg's
    time), as long as each piece keeps at least two steps of the re-timing's grid
    (:data:`FLEET_TIME_STEPS`); ``via`` itself for a spec with tasks (their holds are whole
    segments)."""
    if spec.tasks:
        return via
    tau = spec.prescribed_time / FLEET_TIME_STEPS
    out: list[ReachSegment] = []
    for seg in via.tube.segments:
        a_lo, a_hi = np.array(seg.lower_from), np.array(seg.upper_from)
        b_lo, b_hi = np.array(seg.lower_to), np.array(seg.upper_to)
        length = float(np.linalg.norm((b_lo + b_hi - a_lo - a_hi) / 2))
        count = max(1, min(math.ceil(length / LEG_METRES),
                           math.floor((seg.end - seg.start) / (2 * tau))))
        for j in range(count):
            p, q = j / count, (j + 1) / count
            out.append(replace(
                seg, start=seg.start + p * (seg.end - seg.start),
                end=seg.end if j == count - 1 else seg.start + q * (seg.end - seg.start),
                lower_from=tuple(float(v) for v in a_lo + p * (b_lo - a_lo)),
                upper_from=tuple(float(v) for v in a_hi + p * (b_hi - a_hi)),
                lower_to=(seg.lower_to if j == count - 1 else
                          tuple(float(v) for v in a_lo + q * (b_lo - a_lo))),
                upper_to=(seg.upper_to if j == count - 1 else
                          tuple(float(v) for v in a_hi + q * (b_hi - a_hi)))))
    return replace(via, tube=replace(via.tube, segments=tuple(out)))


def _around(robot: FleetRobot, clash: PairMargin, placing: _Placing) -> tuple[Obstacle, ...]:
    """The placed robot of ``clash``'s tube over its interval widened by
    :data:`DETOUR_SECONDS`, as static boxes grown by both reaches (those that miss
    ``robot``'s start and target): what a detour plans around."""
    other, _, tube = placing.placed[clash.pair[0]]
    way = chunks(tube, robot.dims, INDEX_SECONDS)
    spec = robot.spec
    mine = [_grown(box, robot.dims, 0.0) for box in (spec.initial_set, spec.target_set)]
    grow = robot.reach + other.reach
    out = []
    for t0, t1, lo, hi in zip(way.t_start, way.t_end, way.lower - grow, way.upper + grow):
        if t1 < clash.t_start - DETOUR_SECONDS or t0 > clash.t_end + DETOUR_SECONDS:
            continue
        if any(np.all(lo <= m_hi) and np.all(hi >= m_lo) for m_lo, m_hi in mine):
            continue
        out.append(Obstacle(tuple(float(v) for v in lo), tuple(float(v) for v in hi),
                            tuple(robot.dims), 0))
    return tuple(out)


def _space_time(robot: FleetRobot, way: Design, placing: _Placing,
                check) -> tuple[Design | None, str]:
    """``robot``'s tube along a space-time A* path among the placed tubes
    (:mod:`.fleet_paths`), checked by ``check``; the design, or ``None`` and why not. With
    ``[actuator]``, a path whose input is not proved within the bound is planned again at
    each of :data:`PATH_SLOWER` times its speed."""
    spec = robot.spec
    if len(robot.dims) != 2 or spec.dimension != 2:
        return None, "no space-time path (planned on two body dimensions only)"
    grid = placing.grids.get(robot.name)
    if grid is None:
        grid = placing.grids[robot.name] = SpaceTimeGrid.of(way.spec, robot.dims)
    length = float(np.sum([np.linalg.norm(np.subtract(s.lower_to, s.lower_from))
                           for s in way.tube.segments]))
    speed = min(max(SPEED_FACTOR * length / spec.prescribed_time, MIN_SPEED), MAX_SPEED)
    placed = [(other, tube) for other, _, tube in placing.placed.values()]
    ends = [float(np.max(t.enclosure.t_start)) for _, t in placed]
    boxes = []
    for other, tube in placed:
        c = chunks(tube, robot.dims, STEP_SECONDS)
        grow = other.reach + robot.reach
        boxes.append((c.t_start, c.t_end, c.lower - grow, c.upper + grow))
    start = grid.index(np.array(spec.initial_state)[list(robot.dims)])
    goal = grid.index(np.array(spec.target_center)[list(robot.dims)])
    factors = PATH_SLOWER if spec.input_bound is not None else PATH_SLOWER[:1]
    for factor in factors:
        step = grid.cell / (speed * factor)
        steps = math.ceil(max([spec.prescribed_time] + ends) / step) + 1
        taken = Reservations(grid, step, steps)
        for box in boxes:
            taken.add(*box)
        path = space_time_path(grid, taken, start, goal, math.floor(spec.prescribed_time / step))
        if path is None:
            return None, ("no space-time path among the placed tubes" if factor == factors[0]
                          else f"its space-time path: its input is not proved within "
                               f"actuator.input_bound, and at {factor:g} times its speed "
                               f"there is no path within prescribed_time")
        searched = space_time_segments(path, grid, way.tube, step, _profile(robot))
        timings = [searched]
        if spec.input_bound is not None:          # its waits spent driving slower first
            levelled = levelled_timing(searched, _timing_spec(
                robot, _segment_boxes(searched, robot.dims), placing))
            timings = [levelled] + ([searched] if levelled != searched else [])
        checked = []
        for segments in timings:
            tube = replace(way.tube, circumvents=(), segments=segments)
            found = check(tube, _free(spec))
            checked.append(found)
            if not found.passed:
                continue
            design = _proved(Design(with_gain(tube, found.min_width, spec), METHOD_VIA,
                                    found, 0.0, spec=spec, motion=MOTION_SPACE_TIME_PATH),
                             spec)
            if design is not None:
                return design, ""
        if not any(found.passed for found in checked):
            return None, f"its space-time path: {checked[0].reason}"
    return None, ("its space-time path: its input is not proved within actuator.input_bound "
                  f"(at {', '.join(f'{f:g}' for f in factors)} times its speed)")


def _segment_boxes(segments: Sequence[ReachSegment], dims: Sequence[int]) -> Chunks:
    """The box holding each reach segment (its start and end boxes), on ``dims``."""
    d = list(dims)
    lower = np.array([np.minimum(s.lower_from, s.lower_to)[d] for s in segments])
    upper = np.array([np.maximum(s.upper_from, s.upper_to)[d] for s in segments])
    t_end = np.array([s.end for s in segments])
    t_end[-1] = np.inf
    return Chunks(np.array([s.start for s in segments]), t_end, lower, upper)


def _fit(robot: FleetRobot, placing: _Placing) -> tuple[Design, RobotTube] | str:
    """``robot``'s design among the placed robots (module notes), or why there is none."""
    started = time.perf_counter()
    way, way_tube = placing.ways[robot.name]
    grow = robot.reach + placing.widest
    spec = robot.spec
    clashes: list[PairMargin] = []
    enclosures: dict[tuple, RobotTube] = {}

    def check(candidate, checked: Spec) -> TubeCheck:
        found = check_tube(candidate, checked)
        if not found.passed:
            return found
        enclosure = robot_tube(candidate, found.certificate).finer(CHUNK_SECONDS)
        around = placing.index.near(chunks(enclosure, robot.dims, INDEX_SECONDS), grow)
        met = _clash(robot, enclosure, around, placing)
        if met is not None:
            clashes.append(met)
            return replace(found, passed=False, reason=met.detail, kind=FailureKind.FLEET)
        enclosures[candidate.segments] = enclosure
        return found

    def kept(design: Design) -> tuple[Design, RobotTube]:
        """The design with its enclosed tube (the one its check computed)."""
        tube = enclosures.get(design.tube.segments)
        if tube is None:
            return design, enclosed(design)
        return design, RobotTube(design.tube, tube.enclosure, tube.state)

    if placing.planner == PLANNER_SPACE_TIME:
        design, why = _space_time(robot, way, placing, check)
        return why if design is None else kept(design)
    reasons = []
    found = check(way.tube, _free(spec))
    if found.passed:
        design = _proved(replace(way, check=found), spec)
        if design is not None:
            return kept(design)
        reasons.append("its way: its input is not proved within actuator.input_bound")
        for alone in _alone(robot, placing):
            found = check(alone.tube, _free(spec))
            if found.passed:
                return kept(replace(alone, spec=spec, check=found))
            reasons.append(f"its way at its actuators' speed: {found.reason}")
    else:
        reasons.append(f"its way: {found.reason}")

    def timed(label: str, plan: Design | None) -> Design | None:
        if plan is None:
            reasons.append(f"{label}: no via design")
            return None
        with without_advice():              # the verdict of each re-timing's input proof
            got = retimed_design(_pieces(plan, spec), _timing_spec(robot, chunks(
                way_tube if plan is way else enclosed(plan), robot.dims, INDEX_SECONDS),
                placing), spec, check, started, FLEET_TIME_STEPS)
        if isinstance(got, Design):
            design = _proved(got, spec)
            if design is not None:
                return design
            got = "its input is not proved within actuator.input_bound"
        reasons.append(f"{label}: " + (got or "no re-timing keeps clear of the placed tubes"))
        return None

    design = timed("its way re-timed", way if way.method == METHOD_VIA else _own_via(robot))
    if design is None:
        design, why = _space_time(robot, way, placing, check)
        if design is None:
            reasons.append(why)
    planning = _via_planning(robot, way.spec)
    avoided: set[tuple[str, float]] = set()
    for _ in range(DETOURS if design is None else 0):
        clash = clashes[-1] if clashes else None
        if clash is None or (clash.pair[0], clash.t_start) in avoided:
            break
        avoided.add((clash.pair[0], clash.t_start))
        extra = _around(robot, clash, placing)
        first = len(planning.unsafe_sets) + len(planning.obstacles)
        planning = replace(planning, obstacles=planning.obstacles + tuple(
            replace(ob, source=first + k) for k, ob in enumerate(extra)))
        try:
            plan = design_tube(planning)
        except DesignError:
            reasons.append(f"a detour around {clash.pair[0]}: no via design")
            break
        design = timed(f"a detour around {clash.pair[0]} re-timed", plan)
        if design is not None:
            break
    if design is None and way.spec.obstacles != _free(spec).obstacles:
        design = timed("its own via boxes re-timed", _own_via(robot))
    if design is not None:
        return kept(design)
    return "; ".join(reasons)


def _conflicts(robot: FleetRobot, placing: _Placing, reason: str) -> DesignError:
    """The refusal of ``robot``: its way, against each placed robot's tube."""
    _, alone = placing.ways[robot.name]
    clashes = []
    for other, _, tube in placing.placed.values():
        m = pair_margin((other.name, robot.name), (tube, alone), (other.reach, robot.reach),
                        robot.dims)
        if not m.passed:
            clashes.append(f"{m.pair[0]} and {m.pair[1]} on [{m.t_start:.4f}, "
                           f"{m.t_end:.4f}] s")
    where = "; ".join(clashes) if clashes else "none of them (its tube alone misses theirs)"
    placed = ", ".join(placing.placed) or "none"
    return DesignError(f"robot {robot.name}: no tube avoids the tubes of the robots placed "
                       f"before it ({placed}); its way meets: {where}. "
                       f"Tried: {reason}", kind=FailureKind.FLEET)


def _kept_from(robot: FleetRobot, earlier: _Placing | None,
               placing: _Placing) -> tuple[Design, RobotTube] | None:
    """``robot``'s placement in the order tried before (``earlier``), when it still holds:
    every robot placed before it then is placed now, and its tube is certified apart from
    each robot placed now that was not placed before it then or was placed otherwise (the
    others it was certified against then). ``None`` otherwise (it is placed again)."""
    if earlier is None or robot.name not in earlier.placed:
        return None
    before = list(earlier.placed)
    then = set(before[:before.index(robot.name)])
    if then - set(placing.placed):
        return None
    new = [name for name, (_, design, _) in placing.placed.items()
           if name not in then or design is not earlier.placed[name][1]]
    _, design, tube = earlier.placed[robot.name]
    near = placing.index.near(chunks(tube, robot.dims, INDEX_SECONDS),
                              robot.reach + placing.widest)
    if _clash(robot, tube, [name for name in near if name in new], placing) is not None:
        return None
    return design, tube


def _place(order: Sequence[FleetRobot], placing: _Placing,
           earlier: _Placing | None = None) -> tuple[FleetRobot, str] | None:
    """The robots designed in ``order`` into ``placing`` until one fails (that robot and
    the reason), or ``None``. With ``earlier`` (the placement of the order tried before), a
    robot keeps its earlier placement where it still holds (:func:`_kept_from`)."""
    for robot in order:
        way = chunks(placing.ways[robot.name][1], robot.dims, INDEX_SECONDS)
        near = len(placing.index.near(way, robot.reach + placing.widest))
        cpu = time.process_time()
        found = _kept_from(robot, earlier, placing) or _fit(robot, placing)
        placing.log.append(Placement(robot.name, len(placing.placed), near,
                                     time.process_time() - cpu))
        if isinstance(found, str):
            return robot, found
        design, tube = found
        placing.placed[robot.name] = (robot, design, tube)
        placing.index.add(robot.name, chunks(tube, robot.dims, INDEX_SECONDS))
    return None


def design_fleet(fleet: FleetSpec | str | os.PathLike,
                 planner: str = PLANNER_TUBES) -> FleetDesign:
    """Design and certify every robot's tube so that no two bodies can meet at any ``t``.

    Parameters
    ----------
    fleet : FleetSpec, str or path
        From :func:`stt_codegen.load_fleet` or :meth:`FleetSpec.from_dict`, or what
        :func:`~stt_codegen.load_fleet` takes (a bundled fleet's name or a fleet file).
    planner : {"tubes", "space-time A*"}
        :data:`PLANNER_TUBES` (module notes), or :data:`PLANNER_SPACE_TIME`: each robot,
        longest trip first, along its space-time A* path among the placed tubes only
        (:mod:`.fleet_paths`), checked and certified the same way.

    Returns
    -------
    FleetDesign
        Each robot's certified design (its spec its own task: the other robots' tubes are
        certified apart by the pair certificate) and every pair's certified separation.

    Raises
    ------
    DesignError
        A robot with no tube even alone: that design's error (its kind), the message
        starting ``robot <name> has no tube even alone``. Kind ``FailureKind.FLEET``: no
        order found a tube for every robot (the message names the robot, the robots its
        tube designed alone meets and on which intervals, and what was tried), or a pair
        is not certified apart (the pair and the interval).
    SpecError
        ``fleet`` names no fleet, or a field fails validation (:func:`~stt_codegen.load_fleet`).
    ValueError
        ``planner`` is neither.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> fleet.certified, len(fleet.designs), len(fleet.pairs)
    (True, 2, 1)
    >>> print(fleet.narrowest.detail)                               # doctest: +ELLIPSIS
    east and west: bodies apart by >= ... (narrowest on [...] s, along dimension ...; ...)
    """
    if planner not in (PLANNER_TUBES, PLANNER_SPACE_TIME):
        raise ValueError(f"planner must be {PLANNER_TUBES!r} or {PLANNER_SPACE_TIME!r}, "
                         f"got {planner!r}")
    if not isinstance(fleet, FleetSpec):
        fleet = load_fleet(fleet)
    start = time.perf_counter()
    ways = {}
    for robot in fleet.robots:
        way = plan_way(robot, fleet)
        ways[robot.name] = (way, enclosed(way))
    order = (priority_order(fleet) if planner == PLANNER_SPACE_TIME else
             priority_order(fleet, {name: tube for name, (_, tube) in ways.items()}))
    moved: list[str] = []
    alone: dict[str, tuple[Design, ...]] = {}
    tried = {tuple(r.name for r in order)}
    placing = None
    while True:
        earlier, placing = placing, _Placing(fleet, ways, alone, planner=planner)
        failed = _place(order, placing, earlier)
        if failed is None:
            break
        robot, reason = failed
        order = [robot] + [r for r in order if r is not robot]
        names = tuple(r.name for r in order)
        if moved.count(robot.name) >= MOVES_PER_ROBOT or names in tried:
            raise _conflicts(robot, placing, reason)
        tried.add(names)
        moved.append(robot.name)
    designs = {r.name: placing.placed[r.name][1] for r in fleet.robots}
    pairs = certify_fleet(fleet, designs, {r.name: placing.placed[r.name][2]
                                           for r in fleet.robots})
    bad = [p for p in pairs if not p.passed]
    if bad:
        raise DesignError("the fleet is not certified: " + "; ".join(p.detail for p in bad),
                          kind=FailureKind.FLEET)
    return FleetDesign(fleet, designs, tuple(r.name for r in order), pairs,
                       time.perf_counter() - start, tuple(moved), tuple(placing.log))
