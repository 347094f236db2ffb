"""The look-ahead variant of law (13): a differential-drive base kept in the tube by a point.

A differential-drive base (axle midpoint ``(x, y)``, heading ``theta``; inputs forward
speed ``v`` and turn rate ``omega``) cannot move sideways, so law (13) cannot drive its
state. The point ``p = (x, y) + l (cos theta, sin theta)`` at ``l`` ahead of the axle can
be driven in every direction: ``p_dot = M(theta) (v, omega)`` with ``M(theta) = R(theta)
diag(1, l)``, invertible for ``l > 0``. The variant computes law (13) for ``p`` on the
designed tube, ``u_p``, and sends the base

    (v, omega) = M(theta)^-1 u_p = (cos theta u1 + sin theta u2,
                                    (-sin theta u1 + cos theta u2) / l),

so that ``p`` moves as system (1) with ``g = R W' R^T`` (identity for exact wheels;
docs/differential-drive.md gives the class for wheel errors and slip). The adaptive law
(11) and the tube are the first order's, unchanged.

The pieces here are CasADi SX Functions, the one source of the deployed maths (printed
to C and Python by the emitter); the numpy oracle is :mod:`.look_ahead_reference`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from . import pieces as P
from .model import build_model
from .parameters import TubeDesign

__all__ = ["LOOK_AHEAD_OUTPUTS", "LookAhead", "base_command", "look_ahead_point",
           "look_ahead_predictor",
           "look_ahead_step"]

#: Number of the base's states ``(x, y, theta)`` and of its inputs ``(v, omega)``.
BASE_STATES, BASE_INPUTS = 3, 2
#: Outputs of :func:`look_ahead_step`, in order (``within_bound`` with an input bound).
LOOK_AHEAD_OUTPUTS = ("u", "alpha_next", "inside", "within_bound")


@dataclass(frozen=True)
class LookAhead:
    """The numbers of the look-ahead variant beyond the tube.

    Attributes
    ----------
    axle_offset : float
        ``l``: the look-ahead point's distance ahead of the axle's midpoint, m, positive.
    input_bound : tuple of float or None
        ``(v_max, omega_max)``: the base's limits (m/s, rad/s); the command is clamped to
        them. ``None``: no limit.
    reverse_speed : float or None
        With ``input_bound``: ``v`` is clamped from below at ``-reverse_speed`` (m/s, in
        ``[0, v_max]``) in place of ``-v_max``. ``None``: at ``-v_max``.

    Raises
    ------
    ValueError
        ``axle_offset`` not positive and finite, a bound not positive and finite, or
        ``reverse_speed`` outside ``[0, v_max]`` or without ``input_bound``.
    """

    axle_offset: float
    input_bound: tuple[float, float] | None = None
    reverse_speed: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.axle_offset) and self.axle_offset > 0.0):
            raise ValueError(f"axle_offset must be positive and finite, got "
                             f"{self.axle_offset!r}")
        if self.input_bound is not None and not (
                len(self.input_bound) == BASE_INPUTS
                and all(math.isfinite(b) and b > 0.0 for b in self.input_bound)):
            raise ValueError(f"input_bound must be two positive numbers (v, omega), got "
                             f"{self.input_bound!r}")
        if self.reverse_speed is not None and not (
                self.input_bound is not None and 0.0 <= self.reverse_speed <= self.input_bound[0]):
            raise ValueError(f"reverse_speed must lie in [0, v_max] with an input_bound, got "
                             f"{self.reverse_speed!r}")

    def __repr__(self) -> str:
        # reverse_speed named only where given: the files of a base without it keep their
        # design hash
        given = "" if self.reverse_speed is None else f", reverse_speed={self.reverse_speed!r}"
        return (f"LookAhead(axle_offset={self.axle_offset!r}, "
                f"input_bound={self.input_bound!r}{given})")

    @property
    def input_lower(self) -> tuple[float, float] | None:
        """``(-reverse_speed, -omega_max)`` with a ``reverse_speed``, else ``None`` (the
        clamp's lower ends are ``-input_bound``)."""
        if self.reverse_speed is None:
            return None
        return (-self.reverse_speed, -self.input_bound[1])


@lru_cache(maxsize=None)
def look_ahead_point() -> ca.Function:
    """``look_ahead_point(state, axle_offset) -> (p, heading)``: the point the tube holds.

    Returns
    -------
    casadi.Function
        Inputs ``state`` (3: ``x``, ``y`` in m, ``theta`` in rad) and ``axle_offset``
        (``l``, m); outputs ``p`` (2, m), ``(x + l cos theta, y + l sin theta)``, and
        ``heading`` (2), ``(cos theta, sin theta)``, which :func:`base_command` takes (the
        step evaluates ``cos`` and ``sin`` once).
    """
    state, offset = ca.SX.sym("state", BASE_STATES), ca.SX.sym("axle_offset")
    heading = ca.vertcat(ca.cos(state[2]), ca.sin(state[2]))
    p = ca.vertcat(state[0] + offset * heading[0], state[1] + offset * heading[1])
    return ca.Function("look_ahead_point", [state, offset], [p, heading],
                       ["state", "axle_offset"], ["p", "heading"])


@lru_cache(maxsize=None)
def base_command() -> ca.Function:
    """``base_command(heading, u_point, axle_offset) -> u``: the base's inputs that move the
    look-ahead point with velocity ``u_point`` (exact wheels, no slip).

    Returns
    -------
    casadi.Function
        Inputs ``heading`` (2: ``cos theta``, ``sin theta``, from
        :func:`look_ahead_point`), ``u_point`` (2, m/s) and ``axle_offset`` (m); output
        ``u`` (2): ``v`` (m/s) and ``omega`` (rad/s), ``M(theta)^-1 u_point``.
    """
    heading = ca.SX.sym("heading", BASE_INPUTS)
    u_point, offset = ca.SX.sym("u_point", BASE_INPUTS), ca.SX.sym("axle_offset")
    c, s = heading[0], heading[1]
    u = ca.vertcat(c * u_point[0] + s * u_point[1], (c * u_point[1] - s * u_point[0]) / offset)
    return ca.Function("base_command", [heading, u_point, offset], [u],
                       ["heading", "u_point", "axle_offset"], ["u"])


def look_ahead_step(design: TubeDesign, look_ahead: LookAhead) -> ca.Function:
    """``look_ahead_step(x, t, dt, alpha) -> (u, alpha_next, inside[, within_bound])``: one
    sampled step of the look-ahead variant, with the first order's argument order.

    ``x`` is the base's state ``(x, y, theta)``; the point ``p`` of
    :func:`look_ahead_point` goes through the first-order ``controller_step`` of
    :func:`stt_codegen.tube.model.build_model` (law (13) on the adaptive tube of eq. (10)
    and the deployed implicit step of (11)), whose ``u`` :func:`base_command` turns into
    ``(v, omega)``. With ``look_ahead.input_bound`` the command is clamped by the first
    order's :func:`stt_codegen.tube.pieces.saturate_expression` (``v`` from below at
    ``-reverse_speed`` with one) and a fourth output,
    ``within_bound``, is 1.0 when no entry moved.

    Parameters
    ----------
    design : TubeDesign
        The tube of the look-ahead point (2 dimensions) and its gain; its own
        ``input_bound`` must be ``None`` (the base's bound is ``look_ahead``'s).
    look_ahead : LookAhead

    Returns
    -------
    casadi.Function
        Inputs ``x`` (3: m, m, rad), ``t`` (s), ``dt`` (s), ``alpha`` (4); outputs
        :data:`LOOK_AHEAD_OUTPUTS`: ``u`` (2: m/s, rad/s), ``alpha_next`` (4), ``inside``
        (1.0 when ``p`` is strictly inside the tube, else 0.0)[, ``within_bound``].

    Raises
    ------
    ValueError
        A tube that is not 2-dimensional, or one with its own ``input_bound``.
    """
    if design.dimension != BASE_INPUTS:
        raise ValueError(f"the look-ahead point's tube has 2 dimensions, got "
                         f"{design.dimension}")
    if design.input_bound is not None:
        raise ValueError("the look-ahead variant clamps (v, omega) with LookAhead.input_bound; "
                         "the tube's own input_bound must be None")
    x = ca.SX.sym("x", BASE_STATES)
    t, dt = ca.SX.sym("t"), ca.SX.sym("dt")
    alpha = ca.SX.sym("alpha", 2 * BASE_INPUTS)
    offset = ca.SX(look_ahead.axle_offset)
    p, heading = look_ahead_point()(x, offset)
    u_point, alpha_next, inside = build_model(design)["controller_step"](p, t, dt, alpha)
    u = base_command()(heading, u_point, offset)
    outputs, names = [u, alpha_next, inside], list(LOOK_AHEAD_OUTPUTS[:3])
    if look_ahead.input_bound is not None:
        lower = look_ahead.input_lower
        u, within = P.saturate_expression(u, ca.DM(list(look_ahead.input_bound)), BASE_INPUTS,
                                          None if lower is None else ca.DM(list(lower)))
        outputs, names = [u, alpha_next, inside, within], list(LOOK_AHEAD_OUTPUTS)
    return ca.Function("look_ahead_step", [x, t, dt, alpha], outputs,
                       ["x", "t", "dt", "alpha"], names)


def look_ahead_predictor(design: TubeDesign, look_ahead: LookAhead, delay: float,
                         mid_gain: float) -> ca.Function:
    """The base's state the look-ahead law is evaluated at with ``[controller]
    compensate_delay``: its position moved so that the look-ahead point moves by ``delay
    g_mid`` times the velocity the held ``(v, omega)`` gives it at the heading read at
    ``t_k``; the heading is kept (docs/sampled-data.md, "Compensating a delay", eq. (P0')).

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube (unused: the prediction is the base's).
    look_ahead : LookAhead
        The axle offset ``l``.
    delay : float
        ``[controller] delay``, s.
    mid_gain : float
        ``g_mid = (g_min + g_max) / 2`` of ``[assumptions] input_gain``.

    Returns
    -------
    casadi.Function
        ``predict(x, u_held) -> x_hat``: ``x`` (3: m, m, rad), ``u_held`` (2: the ``(v,
        omega)`` acting at ``t_k``, m/s, rad/s); ``x_hat = (x + s (cos theta v - sin theta l
        omega), y + s (sin theta v + cos theta l omega), theta)`` with ``s = delay g_mid``.

    Examples
    --------
    >>> predict = look_ahead_predictor(None, LookAhead(0.5), 0.02, 1.0)
    >>> [round(float(v), 12) for v in predict([1.0, 2.0, 0.0], [0.5, 1.0]).full().ravel()]
    [1.01, 2.01, 0.0]
    """
    x, u_held = ca.SX.sym("x", BASE_STATES), ca.SX.sym("u_held", BASE_INPUTS)
    c, s = ca.cos(x[2]), ca.sin(x[2])
    step = float(delay * mid_gain)
    turn = look_ahead.axle_offset * u_held[1]
    x_hat = ca.vertcat(x[0] + step * (c * u_held[0] - s * turn),
                       x[1] + step * (s * u_held[0] + c * turn), x[2])
    return ca.Function("predict", [x, u_held], [x_hat], ["x", "u_held"], ["x_hat"])
