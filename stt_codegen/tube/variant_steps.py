"""The controller variants' deployed and oracle steps under one signature each (the roles
``casadi_step``, ``oracle_step`` and ``status`` of :mod:`stt_codegen.spec.variants`): thin adapters
where a variant's own entry takes its arguments otherwise. The cascade's entries
(:func:`stt_codegen.tube.cascade.cascade_step`,
:func:`stt_codegen.tube.cascade_reference.cascade_step`) and the look-ahead law's CasADi
step (:func:`stt_codegen.tube.look_ahead.look_ahead_step`) already have them."""

from __future__ import annotations

import casadi as ca
import numpy as np

from . import look_ahead_reference, reference
from .look_ahead import LookAhead
from .parameters import Status, TubeDesign, step_status

__all__ = ["cascade_status", "law13_casadi_step", "law13_oracle_step", "law13_predictor",
           "law13_status", "look_ahead_oracle_step"]


def law13_casadi_step(design: TubeDesign, stage: None) -> ca.Function:
    """Law (13)'s deployed step: the model's ``controller_step``
    (:func:`stt_codegen.tube.model.build_model`).

    Parameters
    ----------
    design : TubeDesign
    stage : None
        Law (13) on the plant's state takes no stage.

    Returns
    -------
    casadi.Function
        ``(x, t, dt, alpha) -> (u, alpha_next, inside[, within_bound])``.
    """
    from .model import build_model
    return build_model(design)["controller_step"]


def law13_oracle_step(design: TubeDesign, stage: None, x, t, dt,
                      alpha) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Law (13)'s step by the oracle, :func:`stt_codegen.tube.reference.controller_status`.

    Parameters
    ----------
    design : TubeDesign
    stage : None
    x : array_like, shape (N, n)
        States, state units.
    t, dt : array_like, shape (N,)
        Sampling instants and periods, s.
    alpha : array_like, shape (N, 2 n)

    Returns
    -------
    u : ndarray, shape (N, n)
    alpha_next : ndarray, shape (N, 2 n)
    status : ndarray of int, shape (N,)
    """
    return reference.controller_status(design, x, t, dt, alpha)


def look_ahead_oracle_step(design: TubeDesign, stage: LookAhead, x, t, dt,
                           alpha) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The look-ahead law's step by the oracle,
    :func:`stt_codegen.tube.look_ahead_reference.look_ahead_status`.

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube.
    stage : LookAhead
        The axle offset and the base's limits.
    x : array_like, shape (N, 3)
        The base's states ``(x, y, theta)``.
    t, dt : array_like, shape (N,)
    alpha : array_like, shape (N, 4)

    Returns
    -------
    u : ndarray, shape (N, 2)
        ``(v, omega)``.
    alpha_next : ndarray, shape (N, 4)
    status : ndarray of int, shape (N,)
    """
    return look_ahead_reference.look_ahead_status(design, stage.axle_offset,
                                                  stage.input_bound, x, t, dt, alpha,
                                                  stage.reverse_speed)


def _flag(value) -> bool:
    """A step's 1.0/0.0 output (a CasADi ``DM`` or a number) as a truth value."""
    return bool(float(np.ravel(np.asarray(value, dtype=float))[0]))


def law13_status(outputs, dt: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray, Status]:
    """The step of law (13) (or of the look-ahead law) from its CasADi outputs
    ``(u, alpha_next, inside[, within_bound])`` and the call's ``dt``: the step's status.

    Parameters
    ----------
    outputs : sequence
        The outputs of the variant's ``casadi_step`` Function.
    dt : float
        The ``dt`` the step was called with, s.
    rate_hz : float
        The design's rate, Hz.

    Returns
    -------
    u : ndarray, shape (n,)
    alpha_next : ndarray, shape (2 n,)
    status : Status
        ``OUTSIDE_TUBE`` if not inside, else ``OFF_PERIOD`` for a ``dt`` other than the
        period (:func:`~stt_codegen.tube.parameters.step_status`), else ``INPUT_CLAMPED``
        if the clamp moved the input, else ``OK``.
    """
    u, alpha_next, inside, *within = outputs
    status = (Status.OUTSIDE_TUBE if not _flag(inside) else
              Status.INPUT_CLAMPED if within and not _flag(within[0]) else Status.OK)
    return (np.array(u, dtype=float).ravel(), np.array(alpha_next, dtype=float).ravel(),
            step_status(status, dt, rate_hz))


def cascade_status(outputs, dt: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray, Status]:
    """The cascade's step from its CasADi outputs ``(u, alpha_next, r, inside_position,
    inside_velocity[, within_bound])`` and the call's ``dt``: the step's status.

    Parameters
    ----------
    outputs : sequence
        The outputs of :func:`stt_codegen.tube.cascade.cascade_step`'s Function.
    dt : float
        The ``dt`` the step was called with, s.
    rate_hz : float
        The design's rate, Hz.

    Returns
    -------
    u : ndarray, shape (n,)
    alpha_next : ndarray, shape (2 n,)
    status : Status
        ``OUTSIDE_TUBE`` outside the position tube, else ``OUTSIDE_VELOCITY_TUBE``
        outside the velocity tube, else ``OFF_PERIOD`` for a ``dt`` other than the period
        (:func:`~stt_codegen.tube.parameters.step_status`), else ``INPUT_CLAMPED`` if the
        clamp moved the input, else ``OK``.
    """
    u, alpha_next, _r, inside_position, inside_velocity, *within = outputs
    status = (Status.OUTSIDE_TUBE if not _flag(inside_position) else
              Status.OUTSIDE_VELOCITY_TUBE if not _flag(inside_velocity) else
              Status.INPUT_CLAMPED if within and not _flag(within[0]) else Status.OK)
    return (np.array(u, dtype=float).ravel(), np.array(alpha_next, dtype=float).ravel(),
            step_status(status, dt, rate_hz))


def law13_predictor(design: TubeDesign, stage: None, delay: float,
                    mid_gain: float) -> ca.Function:
    """The state law (13) is evaluated at with ``[controller] compensate_delay``: ``x`` read
    at ``t_k``, moved over the delay by the command that acts until then, at the middle of
    the declared input gain (docs/sampled-data.md, "Compensating a delay", eq. (P0)).

    Parameters
    ----------
    design : TubeDesign
        Its dimension ``n``.
    stage : None
        Law (13) on the plant's state takes no stage.
    delay : float
        ``[controller] delay``, s.
    mid_gain : float
        ``g_mid = (g_min + g_max) / 2`` of ``[assumptions] input_gain``.

    Returns
    -------
    casadi.Function
        ``predict(x, u_held) -> x_hat``: ``x`` (n, state units), ``u_held`` (n, the command
        acting at ``t_k``, input units); ``x_hat = x + (delay g_mid) u_held`` (n).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> tube = stt.design_tube(stt.load_spec("omnirobot-s1")).tube
    >>> predict = law13_predictor(tube, None, 1e-3, 0.5)
    >>> [float(v) for v in predict([1.0, 2.0, 0.0], [2.0, 0.0, -4.0]).full().ravel()]
    [1.001, 2.0, -0.002]
    """
    n = design.dimension
    x, u_held = ca.SX.sym("x", n), ca.SX.sym("u_held", n)
    return ca.Function("predict", [x, u_held], [x + float(delay * mid_gain) * u_held],
                       ["x", "u_held"], ["x_hat"])
