"""The robot's size, ``[robot] radius``: the obstacles inflated and the state space shrunk by it.

The tube (eqs. (2)-(11)) and law (13) steer one point, the robot's *reference point*.
A real robot is a body around that point; ``[robot] radius = r`` says the body lies in the
disc (ball) of radius ``r`` around it, in the state dimensions ``dims`` (default the
first two, the planar position). The loader (:mod:`.loader`) then hands the design a
problem for the point alone (the configuration-space construction):

* every obstacle is inflated by ``r`` (:func:`inflate_bounds`, :func:`inflate_ball`,
  :func:`inflate_polytope`, :func:`inflate_moving`), so that the point outside the inflated set
  means the body outside the real one;
* the state space is shrunk by ``r`` on ``dims`` (:func:`shrink_bounds`), so that the point
  inside the shrunk space means the body inside the real one.

Inflating a box by ``r`` on each of ``dims`` is the Minkowski sum with the cube
``[-r, r]^dims``, which contains the ball of radius ``r``: the inflated box contains the
exact Minkowski sum with the ball (its corners are square instead of round), a sound
over-approximation (a point at distance ``< r`` from the box lies inside it). A ball
is inflated exactly, to radius ``+ r``; a polytope is inflated by the cube too (its vertices plus
the cube's corners, their hull). The real sets stay in :class:`Robot`.

This module is plain Python and numpy; boxes are any objects with ``lower``/``upper``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Any, Sequence

from ..errors import SpecError, number_text

__all__ = ["Robot", "inflate_ball", "inflate_bounds", "inflate_moving", "inflate_polytope",
           "robot_dims", "robot_json", "shrink_bounds"]


@dataclass(frozen=True)
class Robot:
    """The robot's size and the sets as the spec gave them (before inflating and shrinking).

    Attributes
    ----------
    radius : float
        ``robot.radius``: the body lies within this distance of the reference point on
        :attr:`dims`, state units (metres for a position).
    dims : tuple of int
        The state dimensions the body extends in (default the first two).
    state_space : Box
        The state space as given; ``Spec.state_space`` is it shrunk by :attr:`radius`.
    unsafe_sets : tuple of UnsafeSet
        The static ``[[obstacles]]`` as given; ``Spec.unsafe_sets`` are them inflated.
    moving_obstacles : tuple of MovingObstacle
        The moving obstacles as given; ``Spec.moving_obstacles`` are them inflated.
    offset : float
        The part of :attr:`radius` that is the reference point's distance from the body's
        centre (a differential drive's ``plant.axle_offset``), state units; 0 otherwise.
    """

    radius: float
    dims: tuple[int, ...]
    state_space: Any
    unsafe_sets: tuple[Any, ...] = ()
    moving_obstacles: tuple[Any, ...] = ()
    offset: float = 0.0


def robot_dims(given: Sequence[int] | None, n: int) -> tuple[int, ...]:
    """The dimensions of ``[robot] dims``: checked, or the first two (the first in 1-D).

    Parameters
    ----------
    given : list of int or None
        ``robot.dims`` as given (``None``: omitted).
    n : int
        The state dimension.

    Returns
    -------
    tuple of int
        The state dimensions the body extends in.

    Raises
    ------
    SpecError
        Field ``robot.dims``: an index outside ``0..n-1`` or a repeated one.
    """
    if given is None:
        return tuple(range(min(n, 2)))
    for d in given:
        if not d < n:
            raise SpecError("robot.dims", f"{d!r} is not a dimension index in 0..{n - 1}")
    if len(set(given)) != len(given):
        raise SpecError("robot.dims", "repeats a dimension")
    return tuple(given)


def shrink_bounds(lower: Sequence[float], upper: Sequence[float], dims: Sequence[int],
                  radius: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The state space ``[lower, upper]`` moved in by ``radius`` on ``dims``.

    Parameters
    ----------
    lower, upper : sequence of float, length n
        The state space's corners, state units.
    dims : sequence of int
        The robot's dimensions.
    radius : float
        The robot's radius, state units.

    Returns
    -------
    lower, upper : tuple of float, length n
        The shrunk state space's corners.

    Raises
    ------
    SpecError
        Field ``robot.radius``: the robot does not fit in the state space (a side of at
        most ``2 radius``).
    """
    lo, hi = list(lower), list(upper)
    for d in dims:
        lo[d], hi[d] = lower[d] + radius, upper[d] - radius
        if not lo[d] < hi[d]:
            raise SpecError("robot.radius", f"the robot (radius {number_text(radius)}) no "
                                            f"longer fits in the state space: dimension {d} is "
                                            f"[{number_text(lower[d])}, "
                                            f"{number_text(upper[d])}]")
    return tuple(lo), tuple(hi)


def inflate_bounds(lower: Sequence[float], upper: Sequence[float], dims: Sequence[int],
                robot: Sequence[int], radius: float
                ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A box given on ``dims`` inflated by ``radius`` on those of them in ``robot``.

    On a dimension the box is not given on, it spans the state space already; on one the
    robot does not extend in (a heading), it does not inflate.

    Parameters
    ----------
    lower, upper : sequence of float, length len(dims)
        The box's corners on ``dims``, state units.
    dims : sequence of int
        The state dimensions the box is given on.
    robot : sequence of int
        The robot's dimensions.
    radius : float
        The robot's radius, state units.

    Returns
    -------
    lower, upper : tuple of float, length len(dims)
        The inflated box's corners.
    """
    lo = tuple(a - radius if d in robot else a for a, d in zip(lower, dims))
    hi = tuple(b + radius if d in robot else b for b, d in zip(upper, dims))
    return lo, hi


def inflate_ball(ball: Any, dims: Sequence[int], robot: Sequence[int], radius: float) -> Any:
    """A ball given on ``dims``, inflated by ``radius`` when it shares a dimension with the
    robot (its Minkowski sum with the body's disc lies in the ball of radius ``+ radius``;
    equal to it when ``dims`` are the robot's).

    Parameters
    ----------
    ball : Ball
        The ball (:class:`~.shapes.Ball`), on ``dims``.
    dims : sequence of int
        The state dimensions the ball is given on.
    robot : sequence of int
        The robot's dimensions.
    radius : float
        The robot's radius, state units.

    Returns
    -------
    Ball
        The inflated ball (``ball`` itself when it shares no dimension with the robot).
    """
    if not set(dims) & set(robot):
        return ball
    return replace(ball, radius=ball.radius + radius)


def inflate_polytope(vertices: Sequence[Sequence[float]], dims: Sequence[int],
                  robot: Sequence[int], radius: float) -> list[list[float]]:
    """The vertices of a polytope given on ``dims`` inflated by the cube of half side
    ``radius`` on the robot's dimensions: each vertex plus each corner of the cube (their
    hull is the Minkowski sum with the cube, which contains the one with the ball).

    Parameters
    ----------
    vertices : sequence of sequence of float, shape (v, len(dims))
        The polytope's vertices, state units.
    dims : sequence of int
        The state dimensions the polytope is given on.
    robot : sequence of int
        The robot's dimensions.
    radius : float
        The robot's radius, state units.

    Returns
    -------
    list of list of float, shape (v * 2**s, len(dims))
        The moved vertices (``s`` the number of ``dims`` in ``robot``); their hull is the
        inflated polytope.
    """
    shared = [k for k, d in enumerate(dims) if d in robot]
    points = []
    for vertex in vertices:
        for signs in itertools.product((-1.0, 1.0), repeat=len(shared)):
            p = list(vertex)
            for k, s in zip(shared, signs):
                p[k] += s * radius
            points.append(p)
    return points


def inflate_moving(obstacle: Any, robot: Sequence[int], radius: float) -> Any:
    """A :class:`~.motion.MovingObstacle` with its half size inflated by ``radius`` on the
    robot's dimensions (its centre's motion unchanged).

    Parameters
    ----------
    obstacle : MovingObstacle
        The moving box as given.
    robot : sequence of int
        The robot's dimensions.
    radius : float
        The robot's radius, state units.

    Returns
    -------
    MovingObstacle
        The same motion, the box inflated.
    """
    half = tuple(h + radius if d in robot else h
                 for h, d in zip(obstacle.half_size, obstacle.dims))
    return replace(obstacle, half_size=half)


def robot_json(spec: Any) -> dict[str, Any]:
    """``robot`` of ``design --json``: the size, the state space as given and shrunk, and
    the inflated obstacle boxes the design avoids; ``{}`` for a spec without ``[robot]``.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    dict
        ``{"robot": {"radius", "dims", "state_space", "shrunk_state_space",
        "inflated_obstacles"}}`` (boxes as ``lower``/``upper`` lists of length ``n``, state
        units; each inflated box with its ``[[obstacles]]`` index ``obstacle``), or ``{}``.
    """
    robot = spec.robot
    if robot is None:
        return {}

    def box(b: Any) -> dict[str, list[float]]:
        return {"lower": list(b.lower), "upper": list(b.upper)}
    return {"robot": {
        "radius": robot.radius, "dims": list(robot.dims),
        "state_space": box(robot.state_space), "shrunk_state_space": box(spec.state_space),
        "inflated_obstacles": [{"obstacle": o.source, **box(o.box(spec.state_space))}
                            for o in spec.obstacles]}}
