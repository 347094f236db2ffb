"""The evasion: running from a sensed obstacle that pursues the robot (docs/sensing.md).

A tube certified against the sensed obstacles' reachable sets keeps the robot safe only
while a certified plan follows; a pursuer as fast as the robot, turning after it, can leave
the replanner no certified plan, and the robot then runs uncertified. The evasion keeps
the robot moving before that happens:

- :func:`chasing` tells a pursuer from an obstacle walking past by its track: a track whose
  velocity estimate changed between two measurements, as the envelope's adversary's would
  (turning after the robot at ``max_obstacle_acceleration`` towards ``max_obstacle_speed``)
  is taken for one from then on;
- :func:`pursuers` picks the fast ones among them approaching the robot, within
  :data:`EVADE_DISTANCE`;
- an evasion's temporary goals are ranked by :func:`evasion_clearance` (the robot running
  on past the goal, the pursuer turning after it), then by their distance to
  :func:`ring_ahead`, a point ahead on a ring about the state space's centre (going round
  keeps the robot out of the corners, where a pursuer traps it), the way the robot goes
  unless the pursuer is ahead on it.

All of it ranks goals; none of it is a bound. Every evasion's tube is designed and
certified as any escape's (:mod:`.sensed`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence

import numpy as np

from ..spec.loader import Spec
from ..spec.sensing import SensedObstacle, Sensing

__all__ = ["EVADE_ANGLE", "EVADE_CARRY", "EVADE_DISTANCE", "EVADE_DISTANCES", "EVADE_LEAD",
           "EVADE_LOOK_AHEAD", "EVADE_RING", "EVADE_SAFE", "EVADE_STEP", "EVADE_TIME",
           "EVADE_TURN_BACK", "PURSUIT_MATCH", "PURSUIT_STEPS", "chasing", "evasion_clearance",
           "pursuers", "ring_ahead", "turning"]

#: A pursuer (:func:`chasing`) whose shape comes within this distance of the robot's
#: reference point, state units, is run from.
EVADE_DISTANCE = 4.0
#: The angle (radians) within which a pursuer's velocity estimate points at the robot when
#: an evasion runs from it (a right angle: approaching at all).
EVADE_ANGLE = math.pi / 2.0
#: A track's velocity estimate that changed by more than this fraction of
#: ``max_obstacle_speed`` since the previous measurement, and to within it of the one
#: predicted as the envelope's adversary would turn it (:func:`chasing`): the track is
#: taken for a pursuer.
PURSUIT_MATCH = 0.05
#: The sub-steps of :func:`chasing`'s prediction between two measurements.
PURSUIT_STEPS = 10
#: Seconds over which an evasion's temporary goals are ranked against the pursuit.
EVADE_LOOK_AHEAD = 2.0
#: Distances (state units) of an evasion's temporary goals from where the robot will be at
#: the switch (or, going on with the move under way, where that move ends).
EVADE_DISTANCES = (0.5, 0.75, 1.0)
#: The evasion's ring about the state space's centre (on the first two sensing dimensions):
#: its radius, as a fraction of the smallest half side.
EVADE_RING = 0.6
#: The angle (radians) ahead of the robot on the ring its goals are drawn towards.
EVADE_LEAD = math.pi / 3.0
#: A robot carried on by the move under way more than this (state units) keeps going round
#: the ring the way it goes.
EVADE_CARRY = 0.1
#: A robot carried round the ring turns back when the nearest pursuer is ahead of it on
#: the way it goes: the sine of the angle about the centre from the robot to the pursuer,
#: signed by the way, above this (a half: the pursuer 30 to 150 degrees ahead).
EVADE_TURN_BACK = 0.5
#: An evasion's clearance counts up to this (state units), to the tenth: goals at least
#: this clear are ranked by their distance to the ring's point ahead.
EVADE_SAFE = 1.0
#: Seconds an evasion's move takes; the next measurement's evasion starts before it ends,
#: going on with it (:func:`~.sensed_blend.continuing`).
EVADE_TIME = 0.495
#: The time step of the pursuit an evasion is ranked against, s.
EVADE_STEP = 0.05


def _turned(v: np.ndarray, gap: np.ndarray, top: float, most: float) -> np.ndarray:
    """Velocity ``v`` turned towards ``top`` along ``gap`` by at most ``most``."""
    far = float(np.linalg.norm(gap))
    change = (gap / far * top if far > 0.0 else 0.0 * gap) - v
    size = float(np.linalg.norm(change))
    return v + (change if size <= most else change * (most / size))


def turning(ob: SensedObstacle, sensing: Sensing, t_to: float,
            aim: Callable[[float], np.ndarray], acceleration: float,
            step: float) -> Iterator[tuple[float, np.ndarray]]:
    """``ob`` turning after the robot: its centre at every ``step`` (s) from when it was
    seen until ``t_to`` (absolute, s), its velocity (its estimate at first) turning towards
    the one heading for ``aim(t)`` by at most ``acceleration`` (state units per second
    squared; ``math.inf``: at once) per second, at its estimated speed plus
    ``velocity_error`` but at most ``max_obstacle_speed``; ``(t, centre)`` pairs."""
    p = np.asarray(ob.centre, dtype=float)
    v = np.zeros_like(p) if ob.velocity is None else np.asarray(ob.velocity, dtype=float)
    speed = 0.0 if ob.velocity is None else float(np.linalg.norm(ob.velocity))
    top = min(sensing.max_obstacle_speed, speed + sensing.velocity_error)
    most = acceleration * step
    t = ob.seen_at
    while t <= t_to + 1e-9:
        yield t, p
        v = _turned(v, aim(t) - p, top, most)
        p = p + v * step
        t += step


def chasing(before: Sequence[SensedObstacle], known: tuple[int, ...],
            sensed: Sequence[SensedObstacle], s: np.ndarray,
            sensing: Sensing) -> tuple[int, ...]:
    """The labels of the tracks taken for pursuers, in increasing order: ``known`` and those
    of ``sensed`` whose velocity estimate changed since the same track in ``before`` (an
    earlier measurement) as the envelope's adversary would turn it after the robot's
    reference point ``s`` (at ``max_obstacle_acceleration``, at once without one, towards
    ``max_obstacle_speed``): by more than :data:`PURSUIT_MATCH` of that speed, and to
    within it of that prediction.

    An obstacle walking straight does not change its velocity, and is not taken, even at
    that speed right at the robot (a circle of Real-Time STT's generator walks at up to
    1.41 m/s, and one so taken was run from into a collision); one turning for its own
    reasons (back from a wall) is not, unless by chance."""
    out = list(known)
    previous = {ob.label: ob for ob in before
                if ob.label is not None and ob.velocity is not None}
    top = sensing.max_obstacle_speed
    turn = sensing.max_obstacle_acceleration
    for ob in sensed:
        prev = previous.get(ob.label)
        if (ob.label is None or ob.label in out or ob.velocity is None or prev is None
                or not ob.seen_at > prev.seen_at):
            continue
        step = (ob.seen_at - prev.seen_at) / PURSUIT_STEPS
        most = math.inf if turn is None else turn * step
        p, v = np.asarray(prev.centre, dtype=float), np.asarray(prev.velocity, dtype=float)
        for _ in range(PURSUIT_STEPS):
            v = _turned(v, s - p, top, most)
            p = p + v * step
        now = np.asarray(ob.velocity, dtype=float)
        tolerance = PURSUIT_MATCH * top
        if (float(np.linalg.norm(now - np.asarray(prev.velocity, dtype=float))) > tolerance
                and float(np.linalg.norm(now - v)) <= tolerance):
            out.append(ob.label)
    return tuple(sorted(out))


def pursuers(sensed: Sequence[SensedObstacle], s: np.ndarray,
             slowest: float) -> list[SensedObstacle]:
    """Those of ``sensed`` an evasion runs from: faster than ``slowest`` (state units per
    second), approaching the robot's reference point at ``s`` (within
    :data:`EVADE_ANGLE`), their shape within :data:`EVADE_DISTANCE` of it."""
    out = []
    for ob in sensed:
        if ob.velocity is None:
            continue
        v, towards = np.asarray(ob.velocity, dtype=float), s - np.asarray(ob.centre, dtype=float)
        far, speed = float(np.linalg.norm(towards)), float(np.linalg.norm(v))
        if (speed > slowest and far - ob.extent < EVADE_DISTANCE and float(v @ towards)
                > math.cos(EVADE_ANGLE) * speed * far + 1e-12 * far):
            out.append(ob)
    return out


def evasion_clearance(ob: SensedObstacle, s: np.ndarray, t_m: float, point: np.ndarray,
                      t_s: float, heading: np.ndarray, speed: float, lower: np.ndarray,
                      upper: np.ndarray, sensing: Sensing,
                      carry: tuple[np.ndarray, float] | None = None) -> float:
    """The least distance over :data:`EVADE_LOOK_AHEAD` after the switch ``t_s`` between
    the robot's reference point and ``ob`` turning after it (:func:`turning`, at the
    envelope's ``A``, at once without one), less ``ob``'s extent and ``velocity_error``
    times the time since it was seen; state units, negative inside.

    The robot goes from ``s`` at ``t_m`` to ``point`` at ``t_s``, is carried on by
    ``carry`` (a displacement, state units, over a duration, s: the move under way), and
    runs on along the unit ``heading`` at ``speed`` (state units per second) inside
    ``[lower, upper]`` (sliding along its walls).

    A ranking, not a bound: the robot does not stop at an evasion's goal, since the next
    measurement's evasion takes over before it arrives (the game of a pursuer and an
    evader, played a measurement at a time)."""
    def robot(t: float) -> np.ndarray:
        if t <= t_m:
            return s
        if t <= t_s:
            return s + (point - s) * (t - t_m) / (t_s - t_m)
        on = point if carry is None else point + carry[0] * min(1.0, (t - t_s) / carry[1])
        return np.clip(on + heading * speed * (t - t_s), lower, upper)

    turn = sensing.max_obstacle_acceleration
    return min((float(np.linalg.norm(robot(t) - p)) - ob.extent
                - sensing.velocity_error * (t - ob.seen_at)
                for t, p in turning(ob, sensing, t_s + EVADE_LOOK_AHEAD, robot,
                                    math.inf if turn is None else turn, EVADE_STEP)
                if t >= t_s - 1e-9), default=math.inf)


def ring_ahead(spec: Spec, dims: Sequence[int], origin: np.ndarray,
               chasers: Sequence[SensedObstacle], carry: np.ndarray) -> np.ndarray:
    """The point :data:`EVADE_LEAD` ahead of ``origin`` (on the sensing dimensions
    ``dims``) on the ring of radius :data:`EVADE_RING` times the state space's smallest
    half side about its centre: going round the way the robot is carried (``carry``,
    longer than :data:`EVADE_CARRY`) unless the nearest of ``chasers`` is ahead on that way
    (:data:`EVADE_TURN_BACK`), else the way that leaves it behind. On fewer than two
    sensing dimensions, the target's centre."""
    if len(dims) < 2:
        return np.asarray(spec.target_center, dtype=float)[list(dims)]
    lo = np.array([spec.state_space.lower[d] for d in dims], dtype=float)
    hi = np.array([spec.state_space.upper[d] for d in dims], dtype=float)
    c = (lo + hi) / 2.0
    radius = EVADE_RING * float(np.min(hi - lo)) / 2.0
    near = min(chasers, key=lambda ob: float(np.linalg.norm(np.asarray(ob.centre) - origin)))
    a = math.atan2(origin[1] - c[1], origin[0] - c[0])
    b = math.atan2(near.centre[1] - c[1], near.centre[0] - c[0])
    turn = float((origin[0] - c[0]) * carry[1] - (origin[1] - c[1]) * carry[0])
    behind = math.sin(a - b)        # > 0: the pursuer is behind going anticlockwise
    way = away = 1.0 if behind >= 0.0 else -1.0
    if float(np.linalg.norm(carry)) > EVADE_CARRY and abs(turn) > 1e-9:
        way = 1.0 if turn > 0.0 else -1.0
        if way * behind < -EVADE_TURN_BACK:
            way = away          # the pursuer is ahead on the way the robot goes
    out = c.copy()
    out[0] += radius * math.cos(a + way * EVADE_LEAD)
    out[1] += radius * math.sin(a + way * EVADE_LEAD)
    return out
