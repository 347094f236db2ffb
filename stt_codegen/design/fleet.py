"""Prioritized fleet design: each robot's tube avoids the tubes already designed (docs/fleets.md).

The robots are designed one at a time in a priority order. A robot designed later sees each
robot designed before it as moving obstacles (:class:`~stt_codegen.spec.motion.MovingObstacle`,
docs/moving-obstacles.md): that robot's certified tube enclosure (its certificate's boxes,
``alpha`` included, on a partition of ``[0, inf)``), merged into boxes over at most
:data:`CHUNK_SECONDS` each, grown by both robots' reaches, each box present only over its
time span. The single-robot design (:func:`~.search.design_tube`, with its space-time
certificate, re-timing and waiting) then finds a tube that misses them at every ``t``.
The order: longer trips first (straight line from ``x(0)`` to the target's centre), then
the file's order; a robot that finds no tube is moved to the front and the fleet is
designed again, each robot moved at most once. Every pair is then certified by
:func:`~.certificate.fleet.pair_margin` on the robots' own certificates; nothing is
accepted on the planner's word.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

import numpy as np

from ..display import Rows, text
from ..errors import DesignError, SpecError
from ..spec.fleet import FleetRobot, FleetSpec, load_fleet
from ..spec.loader import Spec
from ..spec.motion import MovingObstacle, check_moving
from .certificate.fleet import PairMargin, RobotTube, pair_margin, robot_tube
from .failures import FailureKind
from .result import Design
from .search import design_tube

__all__ = ["CHUNK_SECONDS", "FleetDesign", "certify_fleet", "design_fleet", "enclosed",
           "priority_order", "tube_obstacles"]

#: The longest time span of one box standing for another robot's tube, seconds.
CHUNK_SECONDS = 0.25


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


def priority_order(fleet: FleetSpec) -> list[FleetRobot]:
    """The robots by the tool's priority rule: the longest straight trip first.

    Parameters
    ----------
    fleet : FleetSpec

    Returns
    -------
    list of FleetRobot
        Sorted by decreasing distance from ``x(0)`` to the target's centre, ties in the
        fleet's order.
    """
    def trip(robot: FleetRobot) -> float:
        spec = robot.spec
        return math.dist(spec.initial_state, spec.target_center)
    return sorted(fleet.robots, key=lambda r: (-round(trip(r), 9), r.index))


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
    t0, t1, lo, hi = tube.boxes(dims)
    out: list[MovingObstacle] = []
    k, n = 0, t0.size
    while k < n:
        end = k + 1
        while end < n and np.isfinite(t1[end]) and t1[end] - t0[k] <= chunk:
            end += 1
        b_lo, b_hi = lo[k:end].min(axis=0) - reach, hi[k:end].max(axis=0) + reach
        out.append(MovingObstacle(
            source=first_source + len(out), dims=tuple(int(d) for d in dims),
            half_size=tuple(float(v) for v in (b_hi - b_lo) / 2), times=(float(t0[k]),),
            centres=(tuple(float(v) for v in (b_hi + b_lo) / 2),),
            active=(float(t0[k]), float(t1[end - 1])), motion="still"))
        k = end
    return tuple(out)


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


Placed = Sequence[tuple[FleetRobot, RobotTube]]


def _against(robot: FleetRobot, placed: Placed) -> Spec:
    """``robot``'s spec with the placed robots' tubes as moving obstacles. A tube box over
    the robot's start at ``t = 0`` or over its target after its ``t_c`` is a
    :class:`DesignError` naming the pair."""
    spec = robot.spec
    extra: list[MovingObstacle] = []
    first = len(spec.unsafe_sets) + len(spec.moving_obstacles)
    for other, tube in placed:
        boxes = tube_obstacles(tube, other.reach + robot.reach, robot.dims, first + len(extra))
        for box in boxes:
            try:
                check_moving(box, other.name, spec.initial_set, spec.target_set,
                             spec.prescribed_time)
            except SpecError as exc:       # "meets the initial set at t = 0", ...
                reason = exc.reason.replace("the ", f"{robot.name}'s ", 1)
                raise DesignError(
                    f"robots {other.name} and {robot.name} conflict: {other.name}'s tube, "
                    f"grown by both radii, {reason} (its box on [{box.active[0]:.4f}, "
                    f"{box.active[1]:.4f}] s)", kind=FailureKind.FLEET) from None
        extra.extend(boxes)
    return replace(spec, moving_obstacles=spec.moving_obstacles + tuple(extra))


def _conflicts(robot: FleetRobot, placed: Placed, reason: str) -> DesignError:
    """The refusal of ``robot``: its tube designed alone, against each placed robot's."""
    try:
        alone = enclosed(design_tube(robot.spec))
    except DesignError as exc:
        return DesignError(f"robot {robot.name} has no tube even alone: {exc}",
                           kind=exc.kind, tried=exc.tried)
    clashes = []
    for other, tube in placed:
        m = pair_margin((other.name, robot.name), (tube, alone), (other.reach, robot.reach),
                        robot.dims)
        if not m.passed:
            clashes.append(f"{m.pair[0]} and {m.pair[1]} on [{m.t_start:.4f}, "
                           f"{m.t_end:.4f}] s")
    where = "; ".join(clashes) if clashes else "none of them (its tube alone misses theirs)"
    return DesignError(f"robot {robot.name}: no tube avoids the tubes of the robots placed "
                       f"before it ({', '.join(o.name for o, _ in placed) or 'none'}); its "
                       f"tube designed alone meets: {where}. Its design said: {reason}",
                       kind=FailureKind.FLEET)


def _place(order: Sequence[FleetRobot]
           ) -> tuple[list[tuple[FleetRobot, Design, RobotTube]], tuple[FleetRobot, str] | None]:
    """The robots designed in ``order`` until one fails (that robot and the reason)."""
    placed: list[tuple[FleetRobot, Design, RobotTube]] = []
    for robot in order:
        try:
            design = design_tube(_against(robot, [(r, t) for r, _, t in placed]))
        except DesignError as exc:
            return placed, (robot, str(exc))
        placed.append((robot, design, enclosed(design)))
    return placed, None


def design_fleet(fleet: FleetSpec | str | os.PathLike) -> FleetDesign:
    """Design and certify every robot's tube so that no two bodies can meet at any ``t``.

    Parameters
    ----------
    fleet : FleetSpec, str or path
        From :func:`stt_codegen.load_fleet` or :meth:`FleetSpec.from_dict`, or what
        :func:`~stt_codegen.load_fleet` takes (a bundled fleet's name or a fleet file).

    Returns
    -------
    FleetDesign
        Each robot's certified design and every pair's certified separation.

    Raises
    ------
    DesignError
        Kind ``FailureKind.FLEET``: no order found a tube for every robot (the message
        names the robot, the pairs its own tube conflicts with and the intervals), or a
        pair is not certified apart (the pair and the interval); a robot with no tube even
        alone: that design's error.
    SpecError
        ``fleet`` names no fleet, or a field fails validation (:func:`~stt_codegen.load_fleet`).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> fleet.certified, len(fleet.designs), len(fleet.pairs)
    (True, 2, 1)
    >>> print(fleet.narrowest.detail)                               # doctest: +ELLIPSIS
    east and west: bodies apart by >= 0.3471 (narrowest on [...] s, along dimension 0; ...)
    """
    if not isinstance(fleet, FleetSpec):
        fleet = load_fleet(fleet)
    start = time.perf_counter()
    order = priority_order(fleet)
    moved: list[str] = []
    while True:
        placed, failed = _place(order)
        if failed is None:
            break
        robot, reason = failed
        if robot.name in moved or robot is order[0]:
            raise _conflicts(robot, [(r, t) for r, _, t in placed], reason)
        moved.append(robot.name)
        order = [robot] + [r for r in order if r is not robot]
    placed.sort(key=lambda p: p[0].index)
    designs = {r.name: d for r, d, _ in placed}
    pairs = certify_fleet(fleet, designs, {r.name: t for r, _, t in placed})
    bad = [p for p in pairs if not p.passed]
    if bad:
        raise DesignError("the fleet is not certified: " + "; ".join(p.detail for p in bad),
                          kind=FailureKind.FLEET)
    return FleetDesign(fleet, designs, tuple(r.name for r in order), pairs,
                       time.perf_counter() - start, tuple(moved))
