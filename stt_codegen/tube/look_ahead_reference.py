"""The numpy oracle of the look-ahead variant (docs/differential-drive.md), written from the
kinematics, not from :mod:`.look_ahead`.

The base at ``(x, y, theta)`` moving with ``(v, omega)`` moves the point ``p = (x, y) + l
h``, ``h = (cos theta, sin theta)``, with ``p_dot = v h + l omega h_perp``, ``h_perp =
(-sin theta, cos theta)``. Projecting a wanted ``p_dot = u`` on ``h`` and ``h_perp`` gives
``v = h . u`` and ``omega = (h_perp . u) / l``. Law (13) and the adaptive law are the
first-order oracle's (:func:`stt_codegen.tube.reference.law_status`).
"""

from __future__ import annotations

import numpy as np

from . import reference
from .parameters import STATUS_INPUT_CLAMPED, STATUS_OK, TubeDesign, step_status

__all__ = ["command", "look_ahead_status", "point", "predicted_pose"]


def point(states, axle_offset: float) -> np.ndarray:
    """The look-ahead points of base states.

    Parameters
    ----------
    states : array_like, shape (N, 3)
        ``(x, y, theta)``: m, m, rad.
    axle_offset : float
        ``l``, m.

    Returns
    -------
    ndarray, shape (N, 2)
        ``(x, y) + l (cos theta, sin theta)``, m.
    """
    s = np.atleast_2d(np.asarray(states, dtype=float))
    heading = np.stack([np.cos(s[:, 2]), np.sin(s[:, 2])], axis=1)
    return s[:, :2] + axle_offset * heading


def command(states, u_point, axle_offset: float) -> np.ndarray:
    """``(v, omega)`` that move the look-ahead points with velocities ``u_point``.

    Parameters
    ----------
    states : array_like, shape (N, 3)
    u_point : array_like, shape (N, 2)
        Wanted velocities of the points, m/s.
    axle_offset : float

    Returns
    -------
    ndarray, shape (N, 2)
        ``v`` (m/s) and ``omega`` (rad/s).
    """
    s = np.atleast_2d(np.asarray(states, dtype=float))
    u = np.atleast_2d(np.asarray(u_point, dtype=float))
    h = np.stack([np.cos(s[:, 2]), np.sin(s[:, 2])], axis=1)
    h_perp = np.stack([-h[:, 1], h[:, 0]], axis=1)
    return np.stack([np.sum(h * u, axis=1), np.sum(h_perp * u, axis=1) / axle_offset], axis=1)


def look_ahead_status(design: TubeDesign, axle_offset: float,
                      input_bound: tuple[float, float] | None, states, t, dt,
                      alpha, reverse_speed: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One step of the variant: ``(v, omega)``, ``alpha_next`` and the status code.

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube (without an ``input_bound`` of its own).
    axle_offset : float
        ``l``, m.
    input_bound : (float, float) or None
        ``(v_max, omega_max)``; the command is clamped to it.
    states : array_like, shape (N, 3)
    t, dt : float or array_like, shape (N,)
        s.
    alpha : array_like, shape (N, 4)
    reverse_speed : float, optional
        With ``input_bound``: ``v`` is clamped from below at ``-reverse_speed`` (m/s)
        rather than at ``-v_max``.

    Returns
    -------
    u : ndarray, shape (N, 2)
    alpha_next : ndarray, shape (N, 4)
    status : ndarray of int, shape (N,)
        The first order's law status at the point, ``STATUS_INPUT_CLAMPED`` where it is
        ``STATUS_OK`` and the clamp moved an entry; then ``STATUS_OFF_PERIOD`` in place of
        ``OK`` and ``INPUT_CLAMPED`` where ``dt`` is not the period
        (:func:`~stt_codegen.tube.parameters.step_status`).
    """
    u_point, alpha_next, status = reference.law_status(
        design, point(states, axle_offset), t, dt, alpha)
    u = command(states, u_point, axle_offset)
    if input_bound is not None:
        bound = np.asarray(input_bound, dtype=float)
        low = -bound if reverse_speed is None else np.array([-reverse_speed, -bound[1]])
        clamped = np.minimum(np.maximum(u, low), bound)
        moved = np.any(clamped != u, axis=1)
        u = clamped
        status = np.where((status == STATUS_OK) & moved, STATUS_INPUT_CLAMPED, status)
    return u, alpha_next, step_status(status, dt, design.rate_hz)


def predicted_pose(states, held, axle_offset: float, step: float) -> np.ndarray:
    """The oracle's prediction of a base's pose over a computation delay
    (docs/sampled-data.md, "Compensating a delay", eq. (P0')): the look-ahead point moved by
    ``step`` times the velocity the held ``(v, omega)`` gives it at the read heading, the
    heading kept.

    Parameters
    ----------
    states : array_like, shape (N, 3)
        ``(x, y, theta)``, m and rad.
    held : array_like, shape (N, 2)
        The ``(v, omega)`` acting at the read, m/s and rad/s.
    axle_offset : float
        ``l``, m.
    step : float
        ``delay g_mid``, s.

    Returns
    -------
    ndarray, shape (N, 3)
    """
    states = np.atleast_2d(np.asarray(states, dtype=float))
    held = np.atleast_2d(np.asarray(held, dtype=float))
    theta = states[:, 2]
    # the point's velocity: the rotation by theta of (v, l omega)
    forward, sideways = held[:, 0], axle_offset * held[:, 1]
    moved = np.stack([np.cos(theta) * forward - np.sin(theta) * sideways,
                      np.sin(theta) * forward + np.cos(theta) * sideways], axis=1)
    return np.column_stack([states[:, :2] + step * moved, theta])
