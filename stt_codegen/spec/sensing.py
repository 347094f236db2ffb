"""Obstacles sensed at run time: the sensing envelope ``[sensing]`` and a sensed obstacle.

A spec's ``[sensing]`` table states the envelope within which the replanner of
docs/sensing.md guarantees avoidance of obstacles it only sees while it runs:

* ``range`` ``R`` (state units on the robot's dimensions): every obstacle with a point
  within ``R`` of the robot's reference point at a measurement instant is in that
  measurement, its shape (a ball or a box) containing the obstacle then;
* ``latency`` ``L`` (s): a measurement taken at ``t_m`` is available at ``t_m + L``;
* ``update_rate_hz`` or ``period`` ``T_u``: measurements at ``t_m = j T_u``;
* ``max_obstacle_radius`` ``r_max``: every obstacle fits in a ball of that radius;
* ``max_obstacle_speed`` ``V``: no point of an obstacle moves faster (Euclidean norm);
* ``replan_time`` ``tau`` (s, default one period): the replanner's time budget; a new tube
  switches in at ``t_m + L + tau``;
* ``horizon`` ``H`` (s, default two periods, at least one): how long after its switch a
  tube is certified against the sensed obstacles' reachable sets;
* ``shortest_horizon`` ``H_min`` (s, default one period, from one period to ``H``): when no
  plan is certified over ``H``, one certified over ``H_min`` is taken;
* ``max_obstacle_acceleration`` ``A`` (optional) and ``velocity_error`` ``E`` (default 0):
  no point of an obstacle accelerates faster than ``A``, and at a measurement every point
  moves within ``E`` of the reported velocity estimate; a sensed obstacle's reachable set
  then follows its estimate (:meth:`SensedObstacle.drift_box`) instead of growing at ``V``
  in every direction.

The table adds nothing to the design of the spec itself (its tube, its generated code and
its ``source_hash`` do not depend on it); :mod:`stt_codegen.design.sensed` reads it when it
replans. :class:`SensedObstacle` is what a sensor reports, :func:`envelope_violations`
checks a measurement against the envelope's hypotheses (the ones the proof uses).

This module is plain Python and numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..errors import SpecError, number_text

__all__ = ["EnvelopeViolation", "SensedObstacle", "Sensing", "envelope_violations",
           "on_sensing_dims", "sensing_from_table"]

#: Relative slack of the envelope checks (the arithmetic of positions and times).
ENVELOPE_SLACK = 1e-9


@dataclass(frozen=True)
class Sensing:
    """The sensing envelope of a spec's ``[sensing]`` table (docs/sensing.md).

    Attributes
    ----------
    range : float
        ``R``: every obstacle with a point within ``R`` of the robot's reference point at a
        measurement instant is in that measurement; state units (metres).
    latency : float
        ``L``: a measurement taken at ``t_m`` is available at ``t_m + L``, s.
    period : float
        ``T_u``: measurements at ``t_m = j T_u``, s (``1 / update_rate_hz``).
    max_obstacle_radius : float
        ``r_max``: every obstacle fits in a ball of this radius, state units.
    max_obstacle_speed : float
        ``V``: the largest speed of any point of an obstacle (Euclidean norm on
        :attr:`dims`), state units per second.
    replan_time : float
        ``tau``: the replanner's time budget, s; a tube planned from the measurement at
        ``t_m`` switches in at ``t_m + L + tau``.
    horizon : float
        ``H``: a replanned tube is certified against the sensed obstacles' reachable sets
        and the region no unseen obstacle can reach over ``[t_switch, t_switch + H]``, s;
        ``H >= T_u`` so that the next tube can switch in before this one's guarantee ends.
    dims : tuple of int
        The state dimensions obstacles are sensed in: the robot's (``[robot] dims``,
        default the first two).
    shortest_horizon : float
        ``H_min``, s, in ``[T_u, H]``: when no plan is certified over ``H``, the replanner
        takes one certified over ``[t_switch, t_switch + H_min]`` (the smaller reachable sets
        of the shorter span admit more tubes; ``H_min >= T_u`` keeps the certified spans
        overlapping while every replanning succeeds). Equal to ``H``: no shorter plan.
        ``None`` (the default of the constructor) is replaced by one period (``H`` if
        that is shorter).
    max_obstacle_acceleration : float or None
        ``A``: the largest acceleration of any point of an obstacle (Euclidean norm on
        :attr:`dims`), state units per second squared; ``None``: not bounded.
    velocity_error : float
        ``E``: at a measurement, every point of an obstacle moves within ``E`` of the
        obstacle's velocity estimate (Euclidean norm), state units per second; used with
        :attr:`max_obstacle_acceleration` only.

    Examples
    --------
    >>> from stt_codegen.spec.sensing import Sensing
    >>> s = Sensing(range=4.0, latency=0.1, period=0.5, max_obstacle_radius=0.4,
    ...             max_obstacle_speed=0.6, replan_time=0.5, horizon=1.0, dims=(0, 1))
    >>> s.update_rate_hz, s.switch_delay, s.unseen_reach(0.5)
    (2.0, 0.6, 0.3)
    """

    range: float
    latency: float
    period: float
    max_obstacle_radius: float
    max_obstacle_speed: float
    replan_time: float
    horizon: float
    dims: tuple[int, ...]
    max_obstacle_acceleration: float | None = None
    velocity_error: float = 0.0
    shortest_horizon: float | None = None

    def __post_init__(self) -> None:
        if self.shortest_horizon is None:
            object.__setattr__(self, "shortest_horizon", min(self.period, self.horizon))

    @property
    def update_rate_hz(self) -> float:
        """``1 / T_u``, Hz."""
        return 1.0 / self.period

    @property
    def switch_delay(self) -> float:
        """``L + tau``: from a measurement to the switch of the tube planned from it, s."""
        return self.latency + self.replan_time

    def unseen_reach(self, elapsed: float) -> float:
        """How far an obstacle unseen at a measurement may come within ``elapsed`` seconds
        of it: ``V elapsed``, state units."""
        return self.max_obstacle_speed * max(0.0, float(elapsed))


def sensing_from_table(table: Any, dims: tuple[int, ...], variant: Any,
                       reach: float = 0.0) -> Sensing | None:
    """The validated ``[sensing]`` table, with the rules that relate its fields.

    Parameters
    ----------
    table : SensingTable or None
        The schema's table (each value checked: positive, finite); ``None`` when omitted.
    dims : tuple of int
        The robot's dimensions (``[robot] dims`` or the default), where obstacles are sensed.
    variant : ControllerVariant
        The spec's controller variant: replanning is available where ``replans_sensed``.
    reach : float
        The robot's radius around its reference point (``[robot] radius``), state units.

    Returns
    -------
    Sensing or None
        ``None`` without the table.

    Raises
    ------
    SpecError
        ``sensing``: the variant does not replan; ``sensing.period``: both or neither of
        ``update_rate_hz`` and ``period``; ``sensing.horizon``: shorter than one period;
        ``sensing.shortest_horizon``: shorter than one period or longer than the horizon;
        ``sensing.range``: not more than ``V (L + tau + H)`` plus the robot's radius (an
        obstacle unseen at a measurement may close that distance before the tube planned
        from it stops being certified, and the body must still fit inside what is left);
        ``sensing.velocity_error``: given without ``max_obstacle_acceleration``, or more
        than ``2 V`` (an estimate that far from every velocity the speed allows says
        nothing).
    """
    if table is None:
        return None
    if not variant.replans_sensed:
        raise SpecError("sensing", f"replanning around sensed obstacles is available for "
                                   f"first-order plants and differential-drive bases only, "
                                   f"not for {variant.plant_words} (the {variant.name} "
                                   f"variant; docs/sensing.md)")
    if (table.update_rate_hz is None) == (table.period is None):
        raise SpecError("sensing.period", "give update_rate_hz or period (seconds), one of "
                                          "the two" + (", not both" if table.period is not None
                                                       else ""))
    period = float(table.period) if table.period is not None else 1.0 / table.update_rate_hz
    replan = period if table.replan_time is None else float(table.replan_time)
    horizon = 2.0 * period if table.horizon is None else float(table.horizon)
    if horizon < period * (1.0 - ENVELOPE_SLACK):
        raise SpecError("sensing.horizon", f"= {number_text(horizon)} s is shorter than one "
                                           f"update period ({number_text(period)} s): the "
                                           "next tube could not switch in before this one's "
                                           "guarantee ends")
    shortest = period if table.shortest_horizon is None else float(table.shortest_horizon)
    if not period * (1.0 - ENVELOPE_SLACK) <= shortest <= horizon * (1.0 + ENVELOPE_SLACK):
        raise SpecError("sensing.shortest_horizon", f"= {number_text(shortest)} s must lie "
                                                    f"between one update period "
                                                    f"({number_text(period)} s) and the "
                                                    f"horizon ({number_text(horizon)} s)")
    closing = table.max_obstacle_speed * (table.latency + replan + horizon)
    if not table.range > closing + reach:
        body = f" + the robot's radius {number_text(reach)}" if reach else ""
        raise SpecError("sensing.range", f"= {number_text(table.range)} is not more than "
                                         f"max_obstacle_speed x (latency + replan_time + "
                                         f"horizon){body} = {number_text(closing + reach)}: "
                                         "an obstacle unseen at a measurement could reach "
                                         "the robot before the tube planned from it stops "
                                         "being certified")
    acceleration = table.max_obstacle_acceleration
    error = table.velocity_error
    if error is not None and acceleration is None:
        raise SpecError("sensing.velocity_error", "is the error of the velocity estimate a "
                                                  "reachable set follows, which it does only "
                                                  "with max_obstacle_acceleration: give that "
                                                  "too, or leave velocity_error out")
    if error is not None and error > 2.0 * table.max_obstacle_speed:
        raise SpecError("sensing.velocity_error", f"= {number_text(error)} is more than twice "
                                                  f"max_obstacle_speed "
                                                  f"({number_text(table.max_obstacle_speed)}):"
                                                  " the estimate would say nothing")
    return Sensing(range=float(table.range), latency=float(table.latency), period=period,
                   max_obstacle_radius=float(table.max_obstacle_radius),
                   max_obstacle_speed=float(table.max_obstacle_speed), replan_time=replan,
                   horizon=horizon, dims=tuple(dims),
                   max_obstacle_acceleration=None if acceleration is None
                   else float(acceleration),
                   velocity_error=0.0 if error is None else float(error),
                   shortest_horizon=min(shortest, horizon))


def _finite(values: Any, name: str, length: int | None = None,
            positive: bool = False) -> tuple[float, ...]:
    """``values`` as a tuple of finite floats (positive ones with ``positive``)."""
    try:
        out = tuple(float(v) for v in np.atleast_1d(np.asarray(values, dtype=float)).ravel())
    except (TypeError, ValueError):
        raise SpecError(name, f"must be numbers, got {values!r}") from None
    if not out or (length is not None and len(out) != length):
        raise SpecError(name, f"must have {length if length is not None else 'some'} "
                              f"entries, got {len(out)}")
    for v in out:
        if not math.isfinite(v):
            raise SpecError(name, f"must be finite, got {v!r}")
        if positive and not v > 0.0:
            raise SpecError(name, f"must be positive, got {v!r}")
    return out


@dataclass(frozen=True)
class SensedObstacle:
    """One obstacle as a sensor reports it: a ball or a box, seen at ``seen_at``.

    The reported shape must contain the obstacle at ``seen_at`` (the envelope's hypothesis;
    docs/sensing.md). Build one with :meth:`ball` or :meth:`box`, which check the values.

    Attributes
    ----------
    centre : tuple of float, shape (m,)
        The centre on the sensing dimensions (``Sensing.dims``), state units.
    half_size : tuple of float, shape (m,)
        A box's half side on each dimension, state units; for a ball, ``radius`` on every
        dimension (the box that holds it).
    radius : float or None
        A ball's radius, state units; ``None`` for a box.
    seen_at : float
        The measurement instant ``t_m``, s.
    velocity : tuple of float or None
        A velocity estimate, state units per second (checked against the envelope's
        speed; with the envelope's ``max_obstacle_acceleration`` the reachable set follows
        it, :meth:`drift_box`, docs/sensing.md); ``None``: none.
    label : int or None
        A track number, the same for the same obstacle in successive measurements (the
        envelope check follows it); ``None``: not tracked.

    Examples
    --------
    >>> from stt_codegen import SensedObstacle
    >>> person = SensedObstacle.ball((2.0, 1.5), 0.3, seen_at=1.0, velocity=(0.0, 0.5))
    >>> person.extent, person.half_size
    (0.3, (0.3, 0.3))
    >>> SensedObstacle.box((1.0, 1.0), (1.4, 2.0), seen_at=0.5).centre
    (1.2, 1.5)
    """

    centre: tuple[float, ...]
    half_size: tuple[float, ...]
    radius: float | None = None
    seen_at: float = 0.0
    velocity: tuple[float, ...] | None = None
    label: int | None = None

    @classmethod
    def ball(cls, centre: Sequence[float], radius: float, *, seen_at: float = 0.0,
             velocity: Sequence[float] | None = None,
             label: int | None = None) -> "SensedObstacle":
        """A ball of ``radius`` around ``centre``, seen at ``seen_at``.

        Parameters
        ----------
        centre : sequence of float, shape (m,)
            State units, on the sensing dimensions.
        radius : float
            Positive, state units.
        seen_at : float
            The measurement instant, s, finite.
        velocity : sequence of float, shape (m,), optional
            The velocity estimate, state units per second.
        label : int, optional
            The track number.

        Returns
        -------
        SensedObstacle

        Raises
        ------
        SpecError
            A value that is not finite, a radius that is not positive, a velocity of
            another length (field ``SensedObstacle.<name>``).
        """
        c = _finite(centre, "SensedObstacle.centre")
        (r,) = _finite(radius, "SensedObstacle.radius", 1, positive=True)
        return cls(c, (r,) * len(c), r, *_timing(seen_at, velocity, label, len(c)))

    @classmethod
    def box(cls, lower: Sequence[float], upper: Sequence[float], *, seen_at: float = 0.0,
            velocity: Sequence[float] | None = None,
            label: int | None = None) -> "SensedObstacle":
        """The box ``[lower, upper]``, seen at ``seen_at``.

        Parameters
        ----------
        lower, upper : sequence of float, shape (m,)
            Corners on the sensing dimensions, ``upper > lower``, state units.
        seen_at : float
            The measurement instant, s, finite.
        velocity : sequence of float, shape (m,), optional
            The velocity estimate, state units per second.
        label : int, optional
            The track number.

        Returns
        -------
        SensedObstacle

        Raises
        ------
        SpecError
            A value that is not finite, corners of different lengths or not increasing,
            a velocity of another length.
        """
        lo = _finite(lower, "SensedObstacle.lower")
        hi = _finite(upper, "SensedObstacle.upper", len(lo))
        half = tuple(0.5 * (b - a) for a, b in zip(lo, hi))
        if not all(h > 0.0 for h in half):
            raise SpecError("SensedObstacle.upper", "must exceed lower on every dimension")
        centre = tuple(0.5 * (a + b) for a, b in zip(lo, hi))
        return cls(centre, half, None, *_timing(seen_at, velocity, label, len(lo)))

    @property
    def extent(self) -> float:
        """The radius of the smallest ball around :attr:`centre` holding the shape (a ball's
        radius, a box's half diagonal), state units: what ``max_obstacle_radius`` bounds."""
        if self.radius is not None:
            return self.radius
        return float(math.sqrt(sum(h * h for h in self.half_size)))

    def distance(self, point: Sequence[float]) -> float:
        """The Euclidean distance from ``point`` (shape (m,)) to the shape (0 inside), state
        units."""
        p, c = np.asarray(point, dtype=float), np.asarray(self.centre)
        if self.radius is not None:
            return float(max(0.0, np.linalg.norm(p - c) - self.radius))
        gap = np.maximum(np.abs(p - c) - np.asarray(self.half_size), 0.0)
        return float(np.linalg.norm(gap))

    def reach_box(self, t: float, speed: float) -> tuple[np.ndarray, np.ndarray]:
        """A box holding every place the obstacle can be at ``t >= seen_at``: its shape
        grown by ``speed (t - seen_at)`` (a ball grown in every direction lies in the box
        of its radius plus that growth).

        Parameters
        ----------
        t : float
            Seconds, at or after :attr:`seen_at`.
        speed : float
            ``V``, state units per second.

        Returns
        -------
        lower, upper : ndarray, shape (m,)
            State units.
        """
        grow = speed * max(0.0, t - self.seen_at)
        c, h = np.asarray(self.centre), np.asarray(self.half_size) + grow
        return c - h, c + h

    def drift_box(self, t_from: float, t_to: float, acceleration: float,
                  velocity_error: float = 0.0) -> tuple[np.ndarray, np.ndarray] | None:
        """A box holding every place the obstacle can be at every ``t`` of
        ``[t_from, t_to]`` (both at or after :attr:`seen_at`) when its points accelerate
        at most ``A`` and move within ``E`` of :attr:`velocity` at :attr:`seen_at`.

        A point at ``q`` when seen is at ``t`` within ``E tau + A tau^2 / 2`` of
        ``q + v tau`` (``tau = t - seen_at``, ``v`` the estimate), so the shape lies in its
        box moved by ``v tau`` and grown by that. The box returned is the hull of the
        centres moved to ``t_from`` and ``t_to`` (the centre moves on that segment), grown
        by the shape's half size and the growth at ``t_to`` (the growth only increases).
        Intersect it with :meth:`reach_box` at ``t_to``: each holds the obstacle.

        Parameters
        ----------
        t_from, t_to : float
            Seconds, ``seen_at <= t_from <= t_to``.
        acceleration : float
            ``A``, state units per second squared.
        velocity_error : float
            ``E``, state units per second.

        Returns
        -------
        (lower, upper) of ndarray, shape (m,), or None
            State units; ``None`` for an obstacle without a velocity estimate.

        Examples
        --------
        >>> from stt_codegen import SensedObstacle
        >>> ob = SensedObstacle.ball((0.0, 0.0), 0.5, velocity=(1.0, 0.0))
        >>> lo, hi = ob.drift_box(1.0, 2.0, acceleration=0.5)
        >>> lo.tolist(), hi.tolist()
        [[-0.5, -1.5], [3.5, 1.5]]
        """
        if self.velocity is None:
            return None
        a = max(0.0, t_from - self.seen_at)
        b = max(a, t_to - self.seen_at)
        c, v = np.asarray(self.centre), np.asarray(self.velocity)
        grow = velocity_error * b + 0.5 * acceleration * b * b
        h = np.asarray(self.half_size) + grow
        return np.minimum(c + v * a, c + v * b) - h, np.maximum(c + v * a, c + v * b) + h


def _timing(seen_at: float, velocity: Sequence[float] | None, label: int | None,
            m: int) -> tuple[float, tuple[float, ...] | None, int | None]:
    """``seen_at``, ``velocity`` and ``label`` of a sensed obstacle, checked."""
    (t,) = _finite(seen_at, "SensedObstacle.seen_at", 1)
    v = None if velocity is None else _finite(velocity, "SensedObstacle.velocity", m)
    if label is not None and (isinstance(label, bool) or not isinstance(label, (int,
                                                                                np.integer))):
        raise SpecError("SensedObstacle.label", f"must be an integer, got {label!r}")
    return t, v, None if label is None else int(label)


@dataclass(frozen=True)
class EnvelopeViolation:
    """A measurement that breaks one of the envelope's hypotheses (docs/sensing.md).

    Attributes
    ----------
    index : int
        The obstacle's position in the measurement.
    label : int or None
        Its track number.
    kind : {"size", "speed", "displacement", "acceleration", "appeared"}
        Larger than ``max_obstacle_radius``; a velocity estimate faster than
        ``max_obstacle_speed``; a tracked obstacle that moved farther than the speed
        allows since its last measurement; with ``max_obstacle_acceleration``, a tracked
        obstacle farther from where its last estimate put it, or with an estimate further
        from the last one, than ``A`` and ``E`` allow; an obstacle first seen closer than
        it could have come unseen (it was within range at the previous measurement and
        not in it).
    time : float
        The measurement instant, s.
    detail : str
        The numbers, in words.
    """

    index: int
    label: int | None
    kind: str
    time: float
    detail: str


def on_sensing_dims(items: Sequence[Any], kind: type, attribute: str, sensing: Sensing,
                    field: str) -> tuple:
    """``items``, each checked to be a ``kind`` whose ``attribute`` has one entry per
    sensing dimension: the one check of the obstacles given to the replanner
    (:class:`SensedObstacle`, ``centre``) and to the closed loop (``WalkingObstacle``,
    ``start``).

    Parameters
    ----------
    items : sequence
    kind : type
    attribute : str
        The coordinates' attribute of ``kind``.
    sensing : Sensing
        Its ``dims``.
    field : str
        The name of the sequence in errors (``field[j]``, ``field[j].attribute``).

    Returns
    -------
    tuple
        ``items``.

    Raises
    ------
    SpecError
        An item of another type, or with another number of coordinates.
    """
    out = tuple(items)
    m = len(sensing.dims)
    for j, item in enumerate(out):
        if not isinstance(item, kind):
            raise SpecError(f"{field}[{j}]", f"must be a {kind.__name__}, not "
                                             f"{type(item).__name__}")
        size = len(getattr(item, attribute))
        if size != m:
            raise SpecError(f"{field}[{j}].{attribute}",
                            f"must have {m} entries (one per sensing dimension, dims "
                            f"{list(sensing.dims)}), got {size}")
    return out


def envelope_violations(sensing: Sensing, sensed: Sequence[SensedObstacle],
                        position: Sequence[float],
                        earlier: tuple[float, Sequence[float],
                                       Sequence[SensedObstacle]] | None = None
                        ) -> list[EnvelopeViolation]:
    """The obstacles of one measurement that break the envelope's hypotheses.

    Each hypothesis the proof of docs/sensing.md uses is checked where a measurement can
    show it broken: the size (``extent <= r_max``), the velocity estimate
    (``|v| <= V``), and with the previous measurement at ``t_1`` from ``s_1``: a tracked
    obstacle (same ``label``) moved at most ``V (t - t_1)``; an obstacle not in the previous
    measurement (an untracked one: none of that measurement's obstacles within
    ``V (t - t_1)`` plus both sizes of it) is now no nearer to ``s_1`` than
    ``R - V (t - t_1)`` (else it was within range at ``t_1`` and unseen). With
    ``max_obstacle_acceleration`` ``A`` and ``velocity_error`` ``E``, a tracked obstacle
    with estimates ``v_1`` then ``v``: ``|c - (c_1 + v_1 dt)| <= E dt + A dt^2 / 2`` and
    ``|v - v_1| <= A dt + 2 E``. An obstacle that is never in range cannot be checked.

    Parameters
    ----------
    sensing : Sensing
        The envelope.
    sensed : sequence of SensedObstacle
        One measurement (all at the same ``seen_at``).
    position : sequence of float, shape (m,)
        The robot's reference point on ``sensing.dims`` at that instant, state units.
    earlier : (float, sequence of float, sequence of SensedObstacle), optional
        The previous measurement: its instant (s), the robot's point then, its obstacles.

    Returns
    -------
    list of EnvelopeViolation
        Empty when the measurement is consistent with the envelope.

    Examples
    --------
    A person tracked at 0.5 s intervals who moved 1 m (the envelope allows 0.3 m):

    >>> import stt_codegen as stt
    >>> from stt_codegen.spec.sensing import Sensing, envelope_violations
    >>> s = Sensing(range=4.0, latency=0.1, period=0.5, max_obstacle_radius=0.4,
    ...             max_obstacle_speed=0.6, replan_time=0.5, horizon=1.0, dims=(0, 1))
    >>> before = [stt.SensedObstacle.ball((3.0, 2.0), 0.3, seen_at=1.0, label=7)]
    >>> now = [stt.SensedObstacle.ball((3.0, 3.0), 0.3, seen_at=1.5, label=7)]
    >>> [v.kind for v in envelope_violations(s, now, (1.0, 2.0), (1.0, (0.9, 2.0), before))]
    ['displacement']
    """
    out: list[EnvelopeViolation] = []
    speed, slack = sensing.max_obstacle_speed, ENVELOPE_SLACK
    for j, ob in enumerate(sensed):
        def report(kind: str, detail: str) -> None:
            out.append(EnvelopeViolation(j, ob.label, kind, ob.seen_at, detail))
        if ob.extent > sensing.max_obstacle_radius * (1.0 + slack):
            report("size", f"extent {number_text(ob.extent, 6)} > max_obstacle_radius "
                           f"{number_text(sensing.max_obstacle_radius)}")
        if ob.velocity is not None:
            v = float(np.linalg.norm(ob.velocity))
            if v > speed * (1.0 + slack) + slack:
                report("speed", f"velocity estimate {number_text(v, 6)} > "
                                f"max_obstacle_speed {number_text(speed)}")
        if earlier is None:
            continue
        t1, s1, before = earlier
        step = speed * (ob.seen_at - t1)
        tracked = [b for b in before if ob.label is not None and b.label == ob.label]
        if tracked:
            moved = float(np.linalg.norm(np.subtract(ob.centre, tracked[0].centre)))
            if moved > step * (1.0 + slack) + slack:
                report("displacement", f"moved {number_text(moved, 6)} in "
                                       f"{number_text(ob.seen_at - t1, 6)} s, more than "
                                       f"max_obstacle_speed allows ({number_text(step, 6)})")
            if sensing.max_obstacle_acceleration is not None:
                for kind, detail in _drift_violations(sensing, tracked[0], ob):
                    report(kind, detail)
            continue
        could_be = [b for b in before if b.label is None or ob.label is None]
        if any(np.linalg.norm(np.subtract(ob.centre, b.centre))
               <= step + ob.extent + b.extent + slack for b in could_be):
            continue
        near = ob.distance(s1)
        if near < (sensing.range - step) * (1.0 - slack) - slack:
            report("appeared", f"first seen {number_text(near, 6)} from where the robot was "
                               f"at the previous measurement ({number_text(t1, 6)} s): "
                               f"within range R - V dt = {number_text(sensing.range - step, 6)}"
                               ", so it was in range then and not seen")
    return out


def _drift_violations(sensing: Sensing, before: SensedObstacle,
                      now: SensedObstacle) -> list[tuple[str, str]]:
    """What two measurements of one tracked obstacle show of the acceleration hypothesis:
    ``(kind, detail)`` pairs, kind ``"acceleration"``."""
    if before.velocity is None or now.velocity is None:
        return []
    accel, error, slack = sensing.max_obstacle_acceleration, sensing.velocity_error, \
        ENVELOPE_SLACK
    dt = now.seen_at - before.seen_at
    out = []
    expected = np.add(before.centre, np.multiply(before.velocity, dt))
    off = float(np.linalg.norm(np.subtract(now.centre, expected)))
    room = error * dt + 0.5 * accel * dt * dt
    if off > room * (1.0 + slack) + slack:
        out.append(("acceleration", f"{number_text(off, 6)} from where its estimate put it "
                                    f"{number_text(dt, 6)} s before, more than "
                                    f"velocity_error dt + max_obstacle_acceleration dt^2 / 2 "
                                    f"= {number_text(room, 6)}"))
    change = float(np.linalg.norm(np.subtract(now.velocity, before.velocity)))
    room = accel * dt + 2.0 * error
    if change > room * (1.0 + slack) + slack:
        out.append(("acceleration", f"velocity estimate changed by {number_text(change, 6)} "
                                    f"in {number_text(dt, 6)} s, more than "
                                    f"max_obstacle_acceleration dt + 2 velocity_error = "
                                    f"{number_text(room, 6)}"))
    return out
