"""Numeric reference of the cascade law (docs/second-order.md) in numpy: the oracle.

Written from the equations, not from :mod:`.cascade`: the virtual velocity ``r`` is the
reference's own law (13) (:func:`stt_codegen.tube.reference.law_step` with gain ``k1``,
which also gives the next ``alpha``, by bisection); the velocity tube and the second
stage's transform are written out here.

Shapes: ``t`` is ``(N,)``; ``x1``, ``x2`` are ``(N, n)``; ``alpha`` is ``(N, 2n)``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from . import reference
from .parameters import E_MAX, GAMMA_D_MIN, TubeDesign
from .second_stage import SecondStage

__all__ = ["cascade_step", "predicted_state", "velocity_transform", "velocity_tube"]

Array = np.ndarray


def velocity_tube(stage: SecondStage, t) -> Array:
    """``rho2(t) = (rho2(0) - rho2(inf)) e^{-l t} + rho2(inf)`` for ``t >= 0`` (``rho2(0)``
    before), shape (N, n), velocity units.

    Parameters
    ----------
    stage : SecondStage
        The second stage: ``width_start`` ``rho2(0)``, ``width_floor`` ``rho2(inf)`` (shape
        (n,), velocity units) and ``decay`` ``l`` (1/s).
    t : float or array_like, shape (N,)
        Times, s.

    Returns
    -------
    ndarray, shape (N, n)
        ``rho2`` at each time.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    start, floor = np.array(stage.width_start), np.array(stage.width_floor)
    decay = reference.exp(-stage.decay * np.maximum(t, 0.0))
    return (start - floor)[None, :] * decay[:, None] + floor[None, :]


def velocity_transform(x2, r, rho2) -> tuple[Array, Array, Array]:
    """``e2 = (x2 - r) / rho2``, ``epsilon2 = ln((1 + e2)/(1 - e2))``, ``xi2 = 2 / (rho2 (1 -
    e2^2))`` (no clamps: the paper's transform on the tube ``(r - rho2, r + rho2)``).

    Parameters
    ----------
    x2 : array_like, shape (N, n)
        Velocity, velocity units.
    r : array_like, shape (N, n)
        Virtual velocity ``r`` (law (13) of the first stage), velocity units.
    rho2 : array_like, shape (N, n)
        Velocity tube half-width, velocity units.

    Returns
    -------
    e2, epsilon2, xi2 : ndarray, shape (N, n)
        NaN where ``|e2| >= 1`` (outside the velocity tube).
    """
    x2, r, rho2 = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (x2, r, rho2))
    e = (x2 - r) / rho2
    with np.errstate(invalid="ignore", divide="ignore"):
        epsilon = reference.log((1.0 + e) / (1.0 - e))
    return e, epsilon, 2.0 / (rho2 * (1.0 - e * e))


def cascade_step(design: TubeDesign, stage: SecondStage, x, t, dt,
                 alpha) -> tuple[Array, Array, Array, Array, Array, Array]:
    """One step of the deployed cascade, with the clamps of law (13) and the actuator's.

    Parameters
    ----------
    design : TubeDesign
        The position tube (``design.gain`` is replaced by ``stage.position_gain``) and the
        actuator bound ``design.input_bound`` on ``u`` (or ``None``).
    stage : SecondStage
    x : array_like, shape (N, 2n)
        The plant's state ``[x1; x2]``: positions (state units), then velocities (state
        units per second).
    t, dt : array_like, shape (N,)
        Seconds.
    alpha : array_like, shape (N, 2n)

    Returns
    -------
    u : ndarray, shape (N, n)
        ``-k2 xi2 epsilon2`` with ``e2`` clamped to ``[-E_MAX, E_MAX]`` and ``rho2`` floored
        at ``GAMMA_D_MIN`` (finite everywhere), then, with an actuator bound, each entry
        limited to ``[-input_bound_i, input_bound_i]``.
    alpha_next : ndarray, shape (N, 2n)
    r : ndarray, shape (N, n)
        The virtual velocity, law (13) with gain ``k1``.
    inside_position, inside_velocity : ndarray, shape (N,)
        1.0 where ``gamma_L < x1 < gamma_U``, resp. ``|x2 - r| < rho2``, in every dimension.
    within_bound : ndarray, shape (N,)
        1.0 where the actuator bound moved no entry of ``u`` (always, without a bound).
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    n = design.dimension
    x1, x2 = x[:, :n], x[:, n:]
    first = dataclasses.replace(design, gain=stage.position_gain, input_bound=None)
    r, alpha_next, inside_position = reference.law_step(first, x1, t, dt, alpha)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    rho2 = velocity_tube(stage, t)
    x2 = np.broadcast_to(x2, r.shape)
    z = x2 - r
    inside_velocity = np.all((z > -rho2) & (z < rho2), axis=1).astype(float)
    width = np.maximum(rho2, GAMMA_D_MIN)
    e = np.clip(z / width, -E_MAX, E_MAX)
    epsilon = reference.log((1.0 + e) / (1.0 - e))
    xi = 2.0 / (width * (1.0 - e * e))
    # the reference's own clamp (numpy.clip), not the model's saturate piece
    u, within = reference.saturate(design, -stage.velocity_gain * xi * epsilon)
    return u, alpha_next, r, inside_position, inside_velocity, within


def predicted_state(x, u_held, delay: float, mid_gain: float) -> Array:
    """The cascade's prediction over the delay (docs/second-order.md, eq. (P0'')): the
    double integrator ``x1_dot = x2``, ``x2_dot = g_mid u_held`` integrated exactly over
    ``delay`` from ``x = [x1, x2]``.

    Parameters
    ----------
    x : array_like, shape (N, 2n)
        Positions then velocities, read at ``t_k``.
    u_held : array_like, shape (N, n)
        The force acting until ``t_k + delay``.
    delay : float
        s.
    mid_gain : float
        The middle of the input gain range.

    Returns
    -------
    ndarray, shape (N, 2n)
        ``x_hat``.

    Examples
    --------
    >>> predicted_state([[0.0, 1.0]], [[1.0]], 0.5, 2.0).tolist()
    [[0.75, 2.0]]
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    u_held = np.atleast_2d(np.asarray(u_held, dtype=float))
    n = u_held.shape[1]
    acceleration = mid_gain * u_held
    x1 = x[:, :n] + delay * x[:, n:] + 0.5 * delay**2 * acceleration
    return np.hstack([x1, x[:, n:] + delay * acceleration])
