"""The cascade law for second-order plants as CasADi pieces, and its composition.

The second stage of docs/second-order.md, written like :mod:`.pieces` (small SX Functions
whose numbers are inputs) and composed over a design like :mod:`.model`:

=====================  ===========================================  ==========================
piece                  inputs                                       outputs
=====================  ===========================================  ==========================
``velocity_tube``      t, width_start (n), width_floor (n), decay   rho2 (n)
``velocity_law``       x2 (n), r (n), rho2 (n), gain                u (n), inside
``velocity_transform`` x2 (n), r (n), rho2 (n)                      e2, epsilon2, xi2 (for
                                                                    verify, not emitted)
=====================  ===========================================  ==========================

:func:`cascade_step` composes them with the first stage: the adaptive tube ``gamma`` of
eq. (10) and the implicit ``alpha`` step of :mod:`.model`, law (13) with gain ``k1`` as the
virtual velocity ``r``, then the second stage. No derivative of ``r`` appears anywhere
(the low-complexity construction of Bechlioulis and Rovithakis, Automatica 2014).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from . import pieces as P
from .model import adaptive_tube, conflict_and_trigger, implicit_alpha_update
from .parameters import E_MAX, GAMMA_D_MIN, TubeDesign
from .second_stage import SecondStage

__all__ = ["CASCADE_OUTPUTS", "cascade_predictor", "cascade_step", "velocity_law", "velocity_transform",
           "velocity_tube"]

#: The outputs of :func:`cascade_step`, in order (``within_bound`` follows them with an
#: actuator bound).
CASCADE_OUTPUTS = ("u", "alpha_next", "r", "inside_position", "inside_velocity")


def velocity_tube_expression(t, width_start, width_floor, decay):
    """``rho2(t) = (rho2(0) - rho2(inf)) exp(-l max(t, 0)) + rho2(inf)`` (SX), the exponent
    clamped at -80 (no underflow; the term is then below ``2e-35 rho2(0)``)."""
    exponent = ca.fmax(-decay * ca.fmax(t, 0.0), -P.EXP_ARGUMENT_BOUND)
    return (width_start - width_floor) * ca.exp(exponent) + width_floor


def velocity_transform_expression(x2, r, rho2) -> tuple:
    """``(e2, epsilon2, xi2)`` of the second stage (n-vectors, SX), with the clamps of law
    (13): ``e2 = (x2 - r) / rho2`` (``rho2`` floored at ``GAMMA_D_MIN``) clamped to
    ``[-E_MAX, E_MAX]``, ``epsilon2 = ln((1 + e2)/(1 - e2))``, ``xi2 = 2 / (rho2 (1 -
    e2^2))`` (section IV's transform on the tube ``(r - rho2, r + rho2)``, whose width is
    ``2 rho2``: ``4 / (2 rho2 (1 - e^2))``)."""
    width = ca.fmax(rho2, GAMMA_D_MIN)
    e = ca.fmin(ca.fmax((x2 - r) / width, -E_MAX), E_MAX)
    epsilon = ca.log((1.0 + e) / (1.0 - e))
    xi = 2.0 / (width * (1.0 - e * e))
    return e, epsilon, xi


def velocity_law_expression(x2, r, rho2, gain, n: int) -> tuple:
    """``(u, inside)``: ``u = -gain xi2 epsilon2`` and ``inside = 1`` when
    ``-rho2_i < x2_i - r_i < rho2_i`` for every ``i`` (a product of 0/1 values)."""
    inside = 1.0
    z = x2 - r
    for i in range(n):
        inside = inside * (z[i] > -rho2[i]) * (z[i] < rho2[i])
    _, epsilon, xi = velocity_transform_expression(x2, r, rho2)
    return -gain * xi * epsilon, inside


@lru_cache(maxsize=None)
def velocity_tube(n: int) -> ca.Function:
    """``velocity_tube(t, width_start, width_floor, decay) -> rho2``.

    Parameters
    ----------
    n : int
        Number of positions; ``width_start``, ``width_floor``, ``rho2`` have ``n`` entries.

    Returns
    -------
    casadi.Function
        The velocity tube ``rho2(t) = (rho2(0) - rho2(inf)) exp(-l max(t, 0)) + rho2(inf)``
        (velocity units), ``t`` in s, ``decay`` ``l`` in 1/s.
    """
    t, decay = ca.SX.sym("t"), ca.SX.sym("decay")
    start, floor = ca.SX.sym("width_start", n), ca.SX.sym("width_floor", n)
    return ca.Function("velocity_tube", [t, start, floor, decay],
                       [velocity_tube_expression(t, start, floor, decay)],
                       ["t", "width_start", "width_floor", "decay"], ["rho2"])


@lru_cache(maxsize=None)
def velocity_law(n: int) -> ca.Function:
    """``velocity_law(x2, r, rho2, gain) -> (u, inside)``.

    Parameters
    ----------
    n : int
        Number of positions; ``x2``, ``r``, ``rho2`` and ``u`` have ``n`` entries.

    Returns
    -------
    casadi.Function
        The second stage's law ``u = -gain xi2 epsilon2`` (the form of law (13) on the
        velocity tube ``(r - rho2, r + rho2)``) and ``inside``, 1 when ``|x2 - r| < rho2``
        entry by entry.
    """
    x2, r, rho2 = (ca.SX.sym(name, n) for name in ("x2", "r", "rho2"))
    gain = ca.SX.sym("gain")
    u, inside = velocity_law_expression(x2, r, rho2, gain, n)
    return ca.Function("velocity_law", [x2, r, rho2, gain], [u, inside],
                       ["x2", "r", "rho2", "gain"], ["u", "inside"])


@lru_cache(maxsize=None)
def velocity_transform(n: int) -> ca.Function:
    """``velocity_transform(x2, r, rho2) -> (e2, epsilon2, xi2)`` (for ``verify``).

    Parameters
    ----------
    n : int
        Number of positions; every input and output has ``n`` entries.

    Returns
    -------
    casadi.Function
        The second stage's normalized error ``e2``, transformed error ``epsilon2`` and
        ``xi2`` (1 / velocity units), with the clamps of the deployed law.
    """
    x2, r, rho2 = (ca.SX.sym(name, n) for name in ("x2", "r", "rho2"))
    return ca.Function("velocity_transform", [x2, r, rho2],
                       list(velocity_transform_expression(x2, r, rho2)),
                       ["x2", "r", "rho2"], ["e2", "epsilon2", "xi2"])


def cascade_step(design: TubeDesign, stage: SecondStage) -> ca.Function:
    """``cascade_step(x, t, dt, alpha) -> (u, alpha_next, r, inside_position,
    inside_velocity[, within_bound])``: one sampled step of the cascade
    (docs/second-order.md), with the first-order step's argument order.

    ``x = [x1; x2]`` is the plant's state: positions, then velocities. ``r`` is law (13) of
    :func:`stt_codegen.tube.pieces.law` with gain ``k1`` on the adaptive tube of eq. (10)
    at ``(t, alpha)``; ``u`` is :func:`velocity_law` with gain ``k2`` on ``rho2(t)``;
    ``alpha_next`` is the deployed implicit step of (11), exactly as in
    :func:`stt_codegen.tube.model.build_model`. With an actuator bound
    (``design.input_bound``: the bound on the physical input ``u``, one per input), ``u``
    is clamped to ``[-input_bound, input_bound]`` by
    :func:`stt_codegen.tube.pieces.saturate` (the first order's clamp) and a sixth output,
    ``within_bound``, is 1.0 when no entry was moved.

    Parameters
    ----------
    design : TubeDesign
        The position tube (its ``gain`` is not used: ``stage.position_gain`` is ``k1``)
        and the actuator bound ``input_bound`` (or ``None``).
    stage : SecondStage
        Of the same dimension.

    Returns
    -------
    casadi.Function
        Inputs ``x`` (2n: m, then m/s), ``t`` (s), ``dt`` (s), ``alpha`` (2n); outputs
        :data:`CASCADE_OUTPUTS`: ``u`` (n, input units), ``alpha_next`` (2n), ``r`` (n,
        m/s), ``inside_position`` and ``inside_velocity`` (1.0 or 0.0), and with an
        actuator bound ``within_bound`` (1.0 or 0.0).

    Raises
    ------
    ValueError
        ``stage`` and ``design`` of different dimensions.
    """
    n = design.dimension
    if stage.dimension != n:
        raise ValueError(f"second stage of dimension {stage.dimension} for a tube of "
                         f"dimension {n}")
    x = ca.SX.sym("x", 2 * n)
    x1, x2 = x[:n], x[n:]
    t, dt = ca.SX.sym("t"), ca.SX.sym("dt")
    alpha = ca.SX.sym("alpha", 2 * n)
    gamma_l, gamma_u = adaptive_tube(design, t, alpha)
    r, inside_position = P.law(n)(x1, gamma_l, gamma_u, stage.position_gain)
    rho2 = velocity_tube(n)(t, ca.DM(stage.width_start), ca.DM(stage.width_floor),
                            stage.decay)
    u, inside_velocity = velocity_law(n)(x2, r, rho2, stage.velocity_gain)
    outputs, names = [u], list(CASCADE_OUTPUTS)
    if design.input_bound is not None:
        u, within = P.saturate(n)(u, ca.DM(design.input_bound))
        outputs, names = [u], [*names, "within_bound"]
    psi_next, theta_next = conflict_and_trigger(design, P.later()(t, dt))
    alpha_next = implicit_alpha_update(alpha, psi_next, theta_next, dt, design.kappa)
    outputs += [alpha_next, r, inside_position, inside_velocity]
    if design.input_bound is not None:
        outputs.append(within)
    return ca.Function("cascade_step", [x, t, dt, alpha], outputs,
                       ["x", "t", "dt", "alpha"], names)


def cascade_predictor(design: TubeDesign, stage: SecondStage, delay: float,
                      mid_gain: float) -> ca.Function:
    """The state the cascade law is evaluated at with ``[controller] compensate_delay``:
    ``x = [x1; x2]`` read at ``t_k``, moved over the delay by the force ``u_held`` that acts
    until then, at the middle of the plant class's input gain (docs/second-order.md,
    "Compensating a delay", eq. (P0'')).

    Parameters
    ----------
    design : TubeDesign
        The position tube (its dimension ``n``).
    stage : SecondStage
        Not read (the prediction is the plant's, not the law's).
    delay : float
        ``[controller] delay``, s.
    mid_gain : float
        ``g_mid = (g_min + g_max) / 2`` of the second-order plant's input gain.

    Returns
    -------
    casadi.Function
        ``predict(x, u_held) -> x_hat``: ``x`` (2n: m, then m/s), ``u_held`` (n, force
        units, the command acting at ``t_k``); ``x_hat = [x1 + delay x2 + (delay^2 / 2)
        g_mid u_held; x2 + delay g_mid u_held]`` (2n).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("second-order-s1"))
    >>> predict = cascade_predictor(design.tube, design.stage, 0.5, 2.0)
    >>> x_hat = predict([0.0, 0.0, 1.0, 0.0], [0.0, 1.0]).full().ravel()
    >>> [float(v) for v in x_hat]
    [0.5, 0.25, 1.0, 1.0]
    """
    n = design.dimension
    x, u_held = ca.SX.sym("x", 2 * n), ca.SX.sym("u_held", n)
    push = float(delay * mid_gain) * u_held                 # the velocity's change
    x_hat = ca.vertcat(x[:n] + float(delay) * x[n:] + (0.5 * float(delay)) * push,
                       x[n:] + push)
    return ca.Function("predict", [x, u_held], [x_hat], ["x", "u_held"], ["x_hat"])
