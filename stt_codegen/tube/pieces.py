"""The tube and controller as small CasADi Functions whose numbers are inputs.

Every formula of the deployed controller is one of these SX ``Function``s; the spec's
numbers (tube parameters, one row per reach segment, one row per circumvent) are their
*inputs*, never constants of the graph, so the instruction stream of each piece depends on
the state dimension ``n`` only. :mod:`stt_codegen.tube.model` composes them over a design
(the numbers as constants, every segment and circumvent), and the generated code composes
them the same way over ``const`` tables, evaluating only the active segment and the open
circumvents. A closed circumvent contributes exactly 0 to eq. (9) (:func:`fnu_add` adds
``0``, :func:`bump` is ``0``), so skipping it gives the same bits.

=====================  ===========================================  ==========================
piece                  inputs                                       outputs
=====================  ===========================================  ==========================
``progress_tanh``      t, start, end                                p, p_dot (eq. (4));
                                                                    ``_value``: p only
``progress_smoothstep`` t, start, end                               p, p_dot (quintic)
``progress_cruise``    t, start, end                                p, p_dot (ramps, cruise)
``interpolate``        p, p_dot, from (2n), to (2n)                 rho, rho_dot (2n: [L; U]);
                                                                    ``_value``: rho only
``blend``              rho, rho_dot (2n), p, p_dot, from, to        rho + (to - from) p, its
                                                                    rate (blended corners
                                                                    only); ``_value``: rho
``bump``               t, start, end, center, radius, sharpness,    y = B b(t), y_dot
                       height                                       (eqs. (7)-(8));
                                                                    ``_value``: y only
``fnu_init``           top, nu                                      total, rate
``fnu_add``            total, rate, y, y_dot, top, nu               total, rate
``fnu_finish``         bound, sign, top, total, rate, nu            beta, beta_dot (eq. (9))
``fnu_single``         bound, sign, y, y_dot                        beta, beta_dot (one member)
``candidates``         rho (2n), alpha (2n)                         [rho_L - alpha_L;
                                                                    rho_U + alpha_U]
``candidate_rates``    rho_dot (2n), alpha_dot (2n)                 their rates
``smooth_max_test``    a, b, nu                                     max, needed
``smooth_max``         a, b, nu                                     max~ (eq. (10))
``smooth_min_test``    a, b, nu                                     min, needed
``smooth_min``         a, b, nu                                     min~
``smooth_max_rate``    a, b, a_dot, b_dot, nu                       d max~ / dt
``smooth_min_rate``    a, b, a_dot, b_dot, nu                       d min~ / dt
``conflict``           rho (2n), beta (2n), theta0, mu              psi, theta (eq. (11))
``alpha_rate``         alpha (2n), psi (2n), theta (2n), kappa      alpha_dot (eq. (11))
``later``              t, dt                                        t + dt
``newton_start``       alpha, psi, theta, dt, kappa                 a0, c, A, root
``newton_root_start``  alpha, psi, c, A                             a0
``newton_iteration``   a, alpha, psi, c, A                          a (one division)
``law``                x (n), gamma_L (n), gamma_U (n), gain        u (n), inside (law (13))
``saturate``           u (n), bound (n)                             u clamped to +-bound,
                                                                    within (designs with
                                                                    ``[actuator]`` only)
``error_transform``    x (n), gamma_L (n), gamma_U (n)              e, epsilon, xi (section IV;
                                                                    for verify, not emitted)
=====================  ===========================================  ==========================

Vectors of length 2n stack the lower bounds then the upper ones (``[L; U]``).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .parameters import (CRUISE, CRUISE_RAMP, E_MAX, GAMMA_D_MIN, GLIDE, GLIDE_RAMP, GLIDE_TURN,
                         NEWTON_TINY, SCURVE, SCURVE_TURN, SMOOTHSTEP, TANH)

__all__ = ["EXP_ARGUMENT_BOUND", "PROFILE_NAMES", "alpha_rate", "blend", "bump", "candidates",
           "conflict", "deployed_pieces", "error_transform", "error_transform_expression",
           "fnu_pieces", "interpolate", "later", "law", "law_expression",
           "newton_iteration_expression", "newton_root_start_expression",
           "newton_start_expression", "progress", "saturate_expression", "smooth_pieces",
           "trigger_expression"]

#: Bound on the argument of ``exp`` where it could be large (the smooth max's correction
#: and the trigger of (11)): ``exp(+-80)`` is a normal number in float32 and float64, so no
#: step raises an overflow or underflow flag or sets ``errno``.
EXP_ARGUMENT_BOUND = 80.0
#: The base of the skip test of :func:`smooth_max_needed` and ``2^54 e^-34`` (30.875...)
#: rounded up by more than 0.1 % (for its exactness proof).
SMOOTH_SKIP_BASE = 34.0
_SKIP_SCALE = 30.91

#: Profile codes of the segment table, in the order of ``PROFILE_NAMES``.
PROFILE_NAMES = (TANH, SMOOTHSTEP, CRUISE, SCURVE, GLIDE)


def _sym(*names: str):
    return [ca.SX.sym(name) for name in names]


def progress_expression(profile: str, t, start, end):
    """Profile ``p`` of a reach segment (SX): 0 before ``start``, 1 from ``end`` on.

    ``"tanh"``: ``tanh((t - start) / (end - t))`` (eq. (4); only evaluated for
    ``t < end``, with a denominator that stays finite in the branch not taken);
    ``"smoothstep"``: ``tau^3 (10 - 15 tau + 6 tau^2)``, ``tau`` clamped to ``[0, 1]``;
    ``"cruise"`` (:data:`~.parameters.CRUISE`, ramp share ``a``, peak rate
    ``v = 1 / (1 - a)``): ``v a r(tau / a)`` on the first ramp, ``v (tau - a/2)`` in the
    cruise, ``1 - v a r((1 - tau) / a)`` on the last ramp, with ``r(x) = x^3 - x^4 / 2``
    (the integral of the cubic smooth step ``x^2 (3 - 2 x)``); ``"scurve"``
    (:data:`~.parameters.SCURVE`, turn share ``q``, peak acceleration ``A = 4 / (1 - 2
    q)``): ``A tau^3 / (6 q)`` up to ``q``, ``A (tau^2 / 2 - q tau / 2 + q^2 / 6)`` up to
    ``1/2 - q``, ``1/2 - 2 w + A w^3 / (6 q)`` (``w = 1/2 - tau``) up to ``1/2``, and on the
    second half the same mirrored, ``1 - p(1 - tau)``; ``"glide"`` (:data:`~.parameters.GLIDE`,
    ramp share ``r``, turn share ``q``, peak rate ``V = 1 / (1 - r)``, peak acceleration ``A =
    V / (r - q)``), at ``u = min(tau, 1 - tau)``: ``A u^3 / (6 q)`` up to ``q``, ``A (u^2 / 2 -
    q u / 2 + q^2 / 6)`` up to ``r - q``, ``V r / 2 - V w + A w^3 / (6 q)`` (``w = r - u``) up
    to ``r``, ``V (u - r / 2)`` after; ``1 - p(1 - tau)`` on the second half.

    Raises
    ------
    ValueError
        Unknown profile.
    """
    if profile == TANH:
        before = t < end
        gap = ca.if_else(before, end - t, 1.0)
        elapsed = t - start
        return ca.if_else(before, ca.if_else(elapsed < 0.0, 0.0, ca.tanh(elapsed / gap)), 1.0)
    if profile not in (SMOOTHSTEP, CRUISE, SCURVE, GLIDE):
        raise ValueError(f"unknown reach segment profile {profile!r}")
    tau = ca.fmin(ca.fmax((t - start) / (end - start), 0.0), 1.0)
    if profile == SMOOTHSTEP:
        return tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)
    if profile == GLIDE:
        return _glide(tau)
    if profile == SCURVE:
        q = SCURVE_TURN
        peak, turn = 4.0 / (1.0 - 2.0 * q), 6.0 * q
        w, v, u = 0.5 - tau, tau - 0.5, 1.0 - tau

        def held(x):    # the piece of constant acceleration, at x from its end
            return peak * (0.5 * x * x - 0.5 * q * x + q * q / 6.0)

        return ca.if_else(tau <= q, peak * tau * tau * tau / turn,
                          ca.if_else(tau <= 0.5 - q, held(tau),
                          ca.if_else(tau <= 0.5, 0.5 - 2.0 * w + peak * w * w * w / turn,
                          ca.if_else(tau <= 0.5 + q, 0.5 + 2.0 * v - peak * v * v * v / turn,
                          ca.if_else(tau <= 1.0 - q, 1.0 - held(u),
                                     1.0 - peak * u * u * u / turn)))))
    a = CRUISE_RAMP
    v = 1.0 / (1.0 - a)

    def ramp(x):       # v a (x^3 - x^4 / 2): the part of the way a ramp covers
        return v * a * x * x * x * (1.0 - 0.5 * x)

    return ca.if_else(tau < a, ramp(tau / a),
                      ca.if_else(tau <= 1.0 - a, v * (tau - 0.5 * a),
                                 1.0 - ramp((1.0 - tau) / a)))


def _glide(tau):
    """The ``"glide"`` profile at ``tau`` in ``[0, 1]`` (:func:`progress_expression`), one
    branch per piece on ``tau`` (as the S-curve's), the second half ``1 - p(1 - tau)``."""
    r, q = GLIDE_RAMP, GLIDE_TURN
    top = 1.0 / (1.0 - r)
    peak, turn = top / (r - q), 6.0 * q

    def rising(u):
        return peak * u * u * u / turn

    def holding(u):
        return peak * (0.5 * u * u - 0.5 * q * u + q * q / 6.0)

    def easing(u):        # w = r - u from the ramp's end
        w = r - u
        return 0.5 * top * r - top * w + peak * w * w * w / turn

    def cruising(u):
        return top * (u - 0.5 * r)

    u = 1.0 - tau
    return ca.if_else(tau <= q, rising(tau),
                      ca.if_else(tau <= r - q, holding(tau),
                      ca.if_else(tau <= r, easing(tau),
                      ca.if_else(tau <= 0.5, cruising(tau),
                      ca.if_else(tau <= 1.0 - r, 1.0 - cruising(u),
                      ca.if_else(tau <= 1.0 - (r - q), 1.0 - easing(u),
                      ca.if_else(tau <= 1.0 - q, 1.0 - holding(u), 1.0 - rising(u))))))))


@lru_cache(maxsize=None)
def progress(profile: str, rates: bool = True) -> ca.Function:
    """``progress_<profile>(t, start, end) -> (p, p_dot)``; without rates
    ``progress_<profile>_value(t, start, end) -> p``.

    Parameters
    ----------
    profile : str
        One of :data:`PROFILE_NAMES`: ``"tanh"`` (``tanh((t - start) / (end - t))``, eq. (4)),
        ``"smoothstep"`` (quintic), ``"cruise"`` (smooth ramps around a constant rate) or
        ``"scurve"`` (jerk-limited); see :func:`progress_expression`.
    rates : bool
        Also return ``p_dot``, the derivative in ``t`` (1/s).

    Returns
    -------
    casadi.Function
        Scalar inputs ``t``, ``start``, ``end`` (s); ``p`` in ``[0, 1]``.

    Raises
    ------
    ValueError
        Unknown profile.
    """
    t, start, end = _sym("t", "start", "end")
    p = progress_expression(profile, t, start, end)
    if not rates:
        return ca.Function(f"progress_{profile}_value", [t, start, end], [p],
                           ["t", "start", "end"], ["p"])
    return ca.Function(f"progress_{profile}", [t, start, end], [p, ca.jacobian(p, t)],
                       ["t", "start", "end"], ["p", "p_dot"])


@lru_cache(maxsize=None)
def interpolate(n: int, rates: bool = True) -> ca.Function:
    """``interpolate(p, p_dot, from, to) -> (rho, rho_dot)``: ``(to - from) p + from``;
    without rates ``interpolate_value(p, from, to) -> rho``.

    Parameters
    ----------
    n : int
        State dimension; ``from``, ``to``, ``rho`` have ``2n`` entries ``[L; U]``.
    rates : bool
        Also take ``p_dot`` and return ``rho_dot`` (state units/s).

    Returns
    -------
    casadi.Function
        The reach tube ``rho`` of one segment (state units) from its progress ``p``.
    """
    p, p_dot = _sym("p", "p_dot")
    lo, hi = ca.SX.sym("from", 2 * n), ca.SX.sym("to", 2 * n)
    if not rates:
        return ca.Function("interpolate_value", [p, lo, hi], [(hi - lo) * p + lo],
                           ["p", "from", "to"], ["rho"])
    return ca.Function("interpolate", [p, p_dot, lo, hi], [(hi - lo) * p + lo, (hi - lo) * p_dot],
                       ["p", "p_dot", "from", "to"], ["rho", "rho_dot"])


@lru_cache(maxsize=None)
def blend(n: int, rates: bool = True) -> ca.Function:
    """``blend(rho, rho_dot, p, p_dot, from, to) -> (rho, rho_dot)``: ``rho + (to - from) p``,
    the next segment's move added where it starts before the active one ends (a blended
    corner, :attr:`~stt_codegen.tube.parameters.TubeDesign.blends_corners`); without rates
    ``blend_value(rho, p, from, to) -> rho``.

    Parameters
    ----------
    n : int
        State dimension; ``rho``, ``from``, ``to`` have ``2n`` entries ``[L; U]``.
    rates : bool
        Also take ``rho_dot`` and ``p_dot`` and return ``rho_dot + (to - from) p_dot``
        (state units/s).

    Returns
    -------
    casadi.Function
        The reach tube ``rho`` (eq. (4), state units) with the next segment's progress
        ``p`` added.
    """
    p, p_dot = _sym("p", "p_dot")
    rho, rho_dot = ca.SX.sym("rho", 2 * n), ca.SX.sym("rho_dot", 2 * n)
    lo, hi = ca.SX.sym("from", 2 * n), ca.SX.sym("to", 2 * n)
    if not rates:
        return ca.Function("blend_value", [rho, p, lo, hi], [rho + (hi - lo) * p],
                           ["rho", "p", "from", "to"], ["blended"])
    return ca.Function("blend", [rho, rho_dot, p, p_dot, lo, hi],
                       [rho + (hi - lo) * p, rho_dot + (hi - lo) * p_dot],
                       ["rho", "rho_dot", "p", "p_dot", "from", "to"],
                       ["blended", "blended_dot"])


@lru_cache(maxsize=None)
def bump(rates: bool = True) -> ca.Function:
    """``bump(t, start, end, center, radius, sharpness, height) -> (y, y_dot)``.

    ``y = B exp(-k d^2 / ((r - |d|)(r + |d|)))``, ``d = t - m``, inside the open window
    (``start < t < end`` and ``|d| < r``), exactly 0 outside (eqs. (7)-(8)); the exponent
    is clamped at -80 (no underflow near the edges, where ``y < 2e-35 B``). Without rates
    ``bump_value(...) -> y``.

    Parameters
    ----------
    rates : bool
        Also return ``y_dot`` (state units/s), the derivative in ``t``.

    Returns
    -------
    casadi.Function
        Scalar inputs: ``t``, ``start``, ``end``, ``center`` (``m``), ``radius`` (``r``) in
        s, ``sharpness`` (``k``), ``height`` (``B``, state units); output ``y``, state units.
    """
    t, start, end, center, radius, sharpness, height = _sym(
        "t", "start", "end", "center", "radius", "sharpness", "height")
    d = t - center
    inside = ca.logic_and(ca.logic_and(t > start, t < end), ca.fabs(d) < radius)
    # (r - |d|)(r + |d|), not r^2 - d^2: rounded separately from the test |d| < r, the
    # latter can be exactly 0 at the window's edge in float32
    denom = ca.if_else(inside, (radius - ca.fabs(d)) * (radius + ca.fabs(d)), 1.0)
    # the exponent clamped at -80: no underflow at the window's edges (y < 2e-35 B there)
    exponent = ca.fmax(-sharpness * d ** 2 / denom, -EXP_ARGUMENT_BOUND)
    y = ca.if_else(inside, height * ca.exp(exponent), 0.0)
    if not rates:
        return ca.Function("bump_value", [t, start, end, center, radius, sharpness, height], [y],
                           ["t", "start", "end", "center", "radius", "sharpness", "height"],
                           ["y"])
    return ca.Function("bump", [t, start, end, center, radius, sharpness, height],
                       [y, ca.jacobian(y, t)],
                       ["t", "start", "end", "center", "radius", "sharpness", "height"],
                       ["y", "y_dot"])


@lru_cache(maxsize=None)
def fnu_pieces() -> tuple:
    """``fnu_init``, ``fnu_add``, ``fnu_finish``, ``fnu_single``: eq. (9)'s ``F_nu``.

    ``F_nu(y) = (1/nu) ln(1 + sum_j (exp(nu y_j) - 1))`` as
    ``top + ln(total) / nu``, ``total = exp(-nu top) + sum_j (exp(nu (y_j - top)) -
    exp(-nu top))``, ``top = max(0, max_j y_j)`` (cannot overflow); a closed window
    (``y_j = 0``) adds exactly 0. ``rate = sum_j exp(nu (y_j - top)) y_j_dot`` gives
    ``F_dot = rate / total``. ``beta = bound + sign F``: ``sign`` is +1 on a lower bound
    (``beta_L = X + F``), -1 on an upper one (``beta_U = X-bar - F``).

    Returns
    -------
    init, add, finish, single : casadi.Function
        Scalar pieces: ``init(top, nu) -> (total, rate)``, ``add(total, rate, y, y_dot, top,
        nu) -> (total_next, rate_next)`` once per open circumvent, ``finish(bound, sign, top,
        total, rate, nu) -> (beta, beta_dot)``, and ``single(bound, sign, y, y_dot) -> (beta,
        beta_dot)`` for a bound with one circumvent (``beta = bound + sign y``).
    """
    top, nu, total, rate, y, y_dot, bound, sign = _sym(
        "top", "nu", "total", "rate", "y", "y_dot", "bound", "sign")
    # exponents clamped at -80 (no underflow; terms below e^-80 change F by < 2e-35 / nu);
    # a closed window's weight (y = 0) is the floor exactly, clamped alike
    floor = ca.exp(ca.fmax(nu * (0.0 - top), -EXP_ARGUMENT_BOUND))
    weight = ca.exp(ca.fmax(nu * (y - top), -EXP_ARGUMENT_BOUND))
    init = ca.Function("fnu_init", [top, nu], [floor, ca.SX(0.0)], ["top", "nu"],
                       ["total", "rate"])
    add = ca.Function("fnu_add", [total, rate, y, y_dot, top, nu],
                      [total + (weight - floor), rate + weight * y_dot],
                      ["total", "rate", "y", "y_dot", "top", "nu"], ["total_next", "rate_next"])
    finish = ca.Function("fnu_finish", [bound, sign, top, total, rate, nu],
                         [bound + sign * (top + ca.log(total) / nu), sign * (rate / total)],
                         ["bound", "sign", "top", "total", "rate", "nu"], ["beta", "beta_dot"])
    single = ca.Function("fnu_single", [bound, sign, y, y_dot], [bound + sign * y, sign * y_dot],
                         ["bound", "sign", "y", "y_dot"], ["beta", "beta_dot"])
    return init, add, finish, single


@lru_cache(maxsize=None)
def candidates(n: int) -> tuple:
    """``candidates(rho, alpha)`` and ``candidate_rates(rho_dot, alpha_dot)`` (2n each).

    Parameters
    ----------
    n : int
        State dimension; every input and output has ``2n`` entries ``[L; U]``.

    Returns
    -------
    candidates, candidate_rates : casadi.Function
        ``c = [rho_L - alpha_L; rho_U + alpha_U]``, the first arguments of eq. (10)'s smooth
        max and min, and its rate ``c_dot`` (state units, state units/s).
    """
    rho, alpha = ca.SX.sym("rho", 2 * n), ca.SX.sym("alpha", 2 * n)
    value = ca.vertcat(rho[:n] - alpha[:n], rho[n:] + alpha[n:])
    rho_dot, alpha_dot = ca.SX.sym("rho_dot", 2 * n), ca.SX.sym("alpha_dot", 2 * n)
    rate = ca.vertcat(rho_dot[:n] - alpha_dot[:n], rho_dot[n:] + alpha_dot[n:])
    return (ca.Function("candidates", [rho, alpha], [value], ["rho", "alpha"], ["c"]),
            ca.Function("candidate_rates", [rho_dot, alpha_dot], [rate],
                        ["rho_dot", "alpha_dot"], ["c_dot"]))


def smooth_max_expression(a, b, nu):
    """``max~(a, b) = max(a, b) + log1p(exp(-nu |a - b|)) / nu`` (notation, section II;
    the paper's ``(1/nu) ln(e^{nu a} + e^{nu b})`` in a form that does not overflow), the
    exponent clamped at ``-80`` (:data:`EXP_ARGUMENT_BOUND`: no underflow; the correction
    is then below ``4e-35 / nu``)."""
    d = ca.fmax(-nu * ca.fabs(a - b), -EXP_ARGUMENT_BOUND)
    return ca.fmax(a, b) + ca.log1p(ca.exp(d)) / nu


def smooth_max_needed(a, b, nu):
    """``(max(a, b), needed)``: ``needed`` is 0 where ``max~(a, b) == max(a, b)`` exactly.

    With ``D = min(nu |a - b|, 80)`` (the correction's ``exp`` receives ``-D``,
    :func:`smooth_max_expression`) and ``y = nu |max|``, ``needed`` is 0 when
    ``y (D - 33) >= 30.91``. As ``e^x >= 1 + x`` for every ``x``, ``e^-D <= e^-34 / (D -
    33)`` for ``D > 33``, so the correction
    ``log1p(e^-D) / nu < e^-34 / (nu (D - 33)) <= |max| e^-34 / 30.91 < |max| 2^-54``
    (``30.91 > 2^54 e^-34 (1 + 10^-3)``; for ``D <= 33`` the test fails). The correction
    is then below half an ulp of the max (``|max| 2^-54`` in float64, far below it in
    float32; the 0.1 % margin covers the rounding of the test's and the correction's few
    operations), so ``max~(a, b) == max(a, b)`` exactly.
    """
    top = ca.fmax(a, b)
    exponent = ca.fmin(nu * ca.fabs(a - b), EXP_ARGUMENT_BOUND)
    sharp = (nu * ca.fabs(top)) * (exponent - (SMOOTH_SKIP_BASE - 1.0)) >= _SKIP_SCALE
    return top, ca.logic_not(sharp)


@lru_cache(maxsize=None)
def smooth_pieces() -> tuple:
    """``smooth_max_test``, ``smooth_max``, ``smooth_min_test``, ``smooth_min``,
    ``smooth_max_rate``, ``smooth_min_rate`` (scalars; ``min~(a, b) = -max~(-a, -b)``).

    Returns
    -------
    tuple of casadi.Function
        Six scalar Functions, in the order above: ``smooth_max_test(a, b, nu) -> (max,
        needed)`` (``needed = 0`` when ``max(a, b)`` is exact to the last bit),
        ``smooth_max(a, b, nu) -> max~`` (eq. (10)), the same two for ``min~``, and
        ``smooth_max_rate``/``smooth_min_rate(a, b, a_dot, b_dot, nu)``, the rate by the
        chain rule.
    """
    a, b, nu, a_dot, b_dot = _sym("a", "b", "nu", "a_dot", "b_dot")
    top, needed = smooth_max_needed(a, b, nu)
    neg_top, neg_needed = smooth_max_needed(-a, -b, nu)
    value_max = smooth_max_expression(a, b, nu)
    value_min = -smooth_max_expression(-a, -b, nu)
    names = ["a", "b", "nu"]
    rate_names = ["a", "b", "a_dot", "b_dot", "nu"]

    def rate(value):
        grad = ca.jacobian(value, ca.vertcat(a, b))
        return grad[0] * a_dot + grad[1] * b_dot

    return (
        ca.Function("smooth_max_test", [a, b, nu], [top, needed], names, ["max", "needed"]),
        ca.Function("smooth_max", [a, b, nu], [value_max], names, ["max"]),
        ca.Function("smooth_min_test", [a, b, nu], [-neg_top, neg_needed], names,
                    ["min", "needed"]),
        ca.Function("smooth_min", [a, b, nu], [value_min], names, ["min"]),
        ca.Function("smooth_max_rate", [a, b, a_dot, b_dot, nu], [rate(value_max)], rate_names,
                    ["max_dot"]),
        ca.Function("smooth_min_rate", [a, b, a_dot, b_dot, nu], [rate(value_min)], rate_names,
                    ["min_dot"]),
    )


def trigger_expression(psi, theta0, mu):
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) as ``2 theta0 / (1 + exp(y))``,
    ``y = 2 (psi - mu)`` clamped to ``[-80, 80]`` (the same function: ``1 - tanh(y/2) =
    2 / (1 + e^y)``; one ``exp`` instead of ``tanh``; exact to the last bit, or below
    ``4e-35 theta0``, where clamped).

    Parameters
    ----------
    psi : casadi.SX
        The conflict ``psi`` of eq. (11), state units (any shape).
    theta0 : casadi.SX or float
        Height ``theta0`` of the trigger.
    mu : casadi.SX or float
        Offset ``mu`` of the trigger, state units.

    Returns
    -------
    casadi.SX
        ``theta``, the shape of ``psi``, in ``(0, 2 theta0)``.
    """
    y = ca.fmin(ca.fmax(2.0 * (psi - mu), -EXP_ARGUMENT_BOUND), EXP_ARGUMENT_BOUND)
    return (2.0 * theta0) / (1.0 + ca.exp(y))


@lru_cache(maxsize=None)
def conflict(n: int) -> ca.Function:
    """``conflict(rho, beta, theta0, mu) -> (psi, theta)``: ``psi = [beta_U - rho_L;
    rho_U - beta_L]`` and the trigger of eq. (11).

    Parameters
    ----------
    n : int
        State dimension; ``rho``, ``beta``, ``psi``, ``theta`` have ``2n`` entries ``[L; U]``.

    Returns
    -------
    casadi.Function
        Inputs ``rho`` (reach tube (4)), ``beta`` (circumvent (9)), state units, and the
        trigger's scalars ``theta0``, ``mu``.
    """
    rho, beta = ca.SX.sym("rho", 2 * n), ca.SX.sym("beta", 2 * n)
    theta0, mu = _sym("theta0", "mu")
    psi = ca.vertcat(beta[n:] - rho[:n], rho[n:] - beta[:n])
    return ca.Function("conflict", [rho, beta, theta0, mu],
                       [psi, trigger_expression(psi, theta0, mu)],
                       ["rho", "beta", "theta0", "mu"], ["psi", "theta"])


@lru_cache(maxsize=None)
def alpha_rate(n: int) -> ca.Function:
    """``alpha_rate(alpha, psi, theta, kappa) -> theta / (psi + alpha)^2 - kappa alpha``.

    Parameters
    ----------
    n : int
        State dimension; ``alpha``, ``psi``, ``theta`` and ``alpha_dot`` have ``2n`` entries.

    Returns
    -------
    casadi.Function
        The right-hand side of eq. (11), ``alpha_dot`` in state units/s.
    """
    alpha, psi, theta = (ca.SX.sym(name, 2 * n) for name in ("alpha", "psi", "theta"))
    kappa = ca.SX.sym("kappa")
    return ca.Function("alpha_rate", [alpha, psi, theta, kappa],
                       [theta / (psi + alpha) ** 2 - kappa * alpha],
                       ["alpha", "psi", "theta", "kappa"], ["alpha_dot"])


@lru_cache(maxsize=None)
def later() -> ca.Function:
    """``later(t, dt) -> t + dt``.

    Returns
    -------
    casadi.Function
        ``t_next = t + dt`` (s), a Function so that the generated code rounds it the same way.
    """
    t, dt = _sym("t", "dt")
    return ca.Function("later", [t, dt], [t + dt], ["t", "dt"], ["t_next"])


def newton_start_expression(alpha, psi, theta, dt, kappa) -> tuple:
    """``(a0, c, A, root)`` of the implicit step; see :func:`newton_pieces`.

    Parameters
    ----------
    alpha : casadi.SX
        ``alpha`` before the step, ``2n`` entries.
    psi : casadi.SX
        The conflict ``psi`` at the end of the step, ``2n`` entries.
    theta : casadi.SX
        The trigger ``theta`` at the end of the step, ``2n`` entries.
    dt : casadi.SX
        Step, s.
    kappa : casadi.SX
        Decay ``kappa`` of eq. (11), 1/s.

    Returns
    -------
    a0, c, A, root : casadi.SX
        The start ``alpha / c``, ``c = 1 + kappa dt``, ``A = dt theta``, and ``root``: 1
        where ``a0`` is not a safe Newton start (``psi + a0 <= 0`` or ``2 c z0^3 < A``), so
        :func:`newton_root_start_expression` gives the start instead.
    """
    c = 1.0 + kappa * dt
    a_coef = dt * theta
    a0 = alpha / c
    z0 = psi + a0
    fast = ca.logic_and(z0 > 0.0, 2.0 * c * (z0 * z0 * z0) >= a_coef)
    return a0, c, a_coef, ca.logic_not(fast)


def newton_root_start_expression(alpha, psi, c, a_coef):
    """``max(alpha / c, -psi + delta)``, ``delta = min((A / 2c)^(1/3), sqrt(A / 2Q))``,
    ``Q = max(-c psi - alpha, 0)``.

    Parameters
    ----------
    alpha : casadi.SX
        ``alpha`` before the step.
    psi : casadi.SX
        The conflict ``psi`` at the end of the step.
    c : casadi.SX
        ``1 + kappa dt``.
    a_coef : casadi.SX
        ``A = dt theta``.

    Returns
    -------
    casadi.SX
        A start at or right of the root of ``c a - alpha - A / (psi + a)^2``, with
        ``psi + a > 0``.
    """
    q = ca.fmax(-c * psi - alpha, 0.0)
    delta = ca.fmin((a_coef / (2.0 * c)) ** (1.0 / 3.0),
                    ca.sqrt(a_coef / (2.0 * ca.fmax(q, NEWTON_TINY))))
    return ca.fmax(alpha / c, -psi + delta)


def newton_iteration_expression(a, alpha, psi, c, a_coef):
    """``a - z (z^2 (c a - alpha) - A) / (c z^3 + 2 A)``, ``z = psi + a``: one Newton
    iteration on ``g(a) = c a - alpha - A / z^2`` with one division.

    Parameters
    ----------
    a : casadi.SX
        The current iterate.
    alpha : casadi.SX
        ``alpha`` before the step.
    psi : casadi.SX
        The conflict ``psi`` at the end of the step.
    c : casadi.SX
        ``1 + kappa dt``.
    a_coef : casadi.SX
        ``A = dt theta``.

    Returns
    -------
    casadi.SX
        The next iterate.
    """
    z = psi + a
    z2 = z * z
    return a - z * (z2 * (c * a - alpha) - a_coef) / (c * (z2 * z) + 2.0 * a_coef)


@lru_cache(maxsize=None)
def newton_pieces() -> tuple:
    """``newton_start``, ``newton_root_start``, ``newton_iteration`` (scalars).

    ``newton_start``: ``c = 1 + kappa dt``, ``A = dt theta``, ``a0 = alpha / c`` and
    ``root = 1`` unless ``z0 = psi + a0 > 0`` and ``2 c z0^3 >= A`` (then ``a0 >= -psi +
    (A / 2c)^(1/3) >= -psi + delta`` is the start ``newton_root_start`` would return,
    without its roots). Both starts have ``g <= 0`` (proof in docs/codegen.md), so the
    iterations increase monotonically to the root without leaving ``(-psi, inf)``.
    """
    alpha, psi, theta, dt, kappa, a, c, a_coef = _sym(
        "alpha", "psi", "theta", "dt", "kappa", "a", "c", "A")
    a0, c_out, a_out, root = newton_start_expression(alpha, psi, theta, dt, kappa)
    return (
        ca.Function("newton_start", [alpha, psi, theta, dt, kappa], [a0, c_out, a_out, root],
                    ["alpha", "psi", "theta", "dt", "kappa"], ["a0", "c", "A", "root"]),
        ca.Function("newton_root_start", [alpha, psi, c, a_coef],
                    [newton_root_start_expression(alpha, psi, c, a_coef)],
                    ["alpha", "psi", "c", "A"], ["a0"]),
        ca.Function("newton_iteration", [a, alpha, psi, c, a_coef],
                    [newton_iteration_expression(a, alpha, psi, c, a_coef)],
                    ["a", "alpha", "psi", "c", "A"], ["a_next"]),
    )


def _scaled_error(x, gamma_l, gamma_u) -> tuple:
    """``(gamma_d, width, e)``: ``width = max(gamma_d, GAMMA_D_MIN)``, ``e = (2 x - gamma_s)
    / width`` (``gamma_s = gamma_U + gamma_L``, ``gamma_d = gamma_U - gamma_L``)."""
    gamma_d = gamma_u - gamma_l
    width = ca.fmax(gamma_d, GAMMA_D_MIN)
    return gamma_d, width, (2.0 * x - (gamma_u + gamma_l)) / width


def _transform(e, width) -> tuple:
    """``(e_c, epsilon, xi)`` from the scaled error: ``e`` clamped to ``[-E_MAX, E_MAX]``."""
    e_c = ca.fmin(ca.fmax(e, -E_MAX), E_MAX)
    epsilon = ca.log((1.0 + e_c) / (1.0 - e_c))
    xi = 4.0 / (width * (1.0 - e_c ** 2))
    return e_c, epsilon, xi


def error_transform_expression(x, gamma_l, gamma_u) -> tuple:
    """Error transform of section IV with clamps: ``(e, epsilon, xi)`` (n-vectors, SX).

    ``e = (2 x - gamma_s) / gamma_d`` (``gamma_s = gamma_U + gamma_L``, ``gamma_d =
    gamma_U - gamma_L`` floored at ``GAMMA_D_MIN``) clamped to ``[-E_MAX, E_MAX]``,
    ``epsilon = ln((1 + e)/(1 - e))``, ``xi = 4 / (gamma_d (1 - e^2))`` (the diagonal of
    ``xi`` in law (13)), finite everywhere; the same construction as :func:`law_expression`.

    Parameters
    ----------
    x : casadi.SX, shape (n,)
        State, state units.
    gamma_l, gamma_u : casadi.SX, shape (n,)
        The adaptive tube ``gamma_L``, ``gamma_U`` of eq. (10), state units.

    Returns
    -------
    e, epsilon, xi : casadi.SX, shape (n,)
        Normalized error, transformed error, and ``xi`` (1 / state units).
    """
    _, width, e = _scaled_error(x, gamma_l, gamma_u)
    return _transform(e, width)


def law_expression(x, gamma_l, gamma_u, gain, n: int) -> tuple:
    """Deployed law (13) with clamps: ``(u, inside)``, ``u = -gain xi epsilon`` with the
    ``epsilon``, ``xi`` of :func:`error_transform_expression` (finite everywhere).

    Parameters
    ----------
    x : casadi.SX, shape (n,)
        State, state units.
    gamma_l, gamma_u : casadi.SX, shape (n,)
        The adaptive tube of eq. (10), state units.
    gain : casadi.SX or float
        The gain ``k`` of law (13).
    n : int
        State dimension.

    Returns
    -------
    u : casadi.SX, shape (n,)
        The input of law (13).
    inside : casadi.SX
        1 when ``gamma_L < x < gamma_U`` entry by entry, else 0.
    """
    _, width, e = _scaled_error(x, gamma_l, gamma_u)
    inside = 1.0
    for i in range(n):
        # gamma_L < x < gamma_U, two comparisons, exact (no rounding): on or outside the
        # bounds, or an empty tube, is not inside (docs/codegen.md, "Status OK"); a
        # product of 0/1 values (exact) costs fewer instructions than logic_and
        inside = inside * (x[i] > gamma_l[i]) * (x[i] < gamma_u[i])
    _, epsilon, xi = _transform(e, width)
    return -gain * xi * epsilon, inside


def saturate_expression(u, bound, n: int, lower=None) -> tuple:
    """The actuator clamp: ``(u_c, within)`` (SX), ``u_c = min(max(u, -bound), bound)``
    entry by entry and ``within = 1`` when no entry was moved (``-bound_i <= u_i <= bound_i``
    for every ``i``, exact comparisons; a product of 0/1 values, exact), else 0.

    For finite ``u`` the clamp is the projection on the box ``[-bound, bound]``: it moves
    no entry inside the box, so where law (13) stays within the bound it is the identity.
    The generated code checks ``u`` for finiteness before it is clamped.

    Parameters
    ----------
    u : casadi.SX, shape (n,)
        Input of law (13).
    bound : casadi.SX, shape (n,)
        The actuator bound ``[actuator] u_max``, positive, input units.
    n : int
        Input dimension.
    lower : casadi.SX, shape (n,), optional
        The lower ends in place of ``-bound`` (a differential-drive base's ``v >=
        -reverse_speed``), at most 0.

    Returns
    -------
    u_c : casadi.SX, shape (n,)
        The clamped input.
    within : casadi.SX
        1 when no entry was clamped, else 0.
    """
    within = 1.0
    for i in range(n):
        within = within * (u[i] >= (-bound[i] if lower is None else lower[i])) * (
            u[i] <= bound[i])
    return ca.fmin(ca.fmax(u, -bound if lower is None else lower), bound), within


@lru_cache(maxsize=None)
def saturate(n: int) -> ca.Function:
    """``saturate(u, bound) -> (u_c, within)``: :func:`saturate_expression`."""
    u, bound = ca.SX.sym("u", n), ca.SX.sym("bound", n)
    u_c, within = saturate_expression(u, bound, n)
    return ca.Function("saturate", [u, bound], [u_c, within], ["u", "bound"],
                       ["u_c", "within"])


@lru_cache(maxsize=None)
def saturate_between(n: int) -> ca.Function:
    """``saturate_between(u, lower, bound) -> (u_c, within)``: :func:`saturate_expression`
    with its own lower ends."""
    u, lower, bound = ca.SX.sym("u", n), ca.SX.sym("lower", n), ca.SX.sym("bound", n)
    u_c, within = saturate_expression(u, bound, n, lower)
    return ca.Function("saturate_between", [u, lower, bound], [u_c, within],
                       ["u", "lower", "bound"], ["u_c", "within"])


@lru_cache(maxsize=None)
def error_transform(n: int) -> ca.Function:
    """``error_transform(x, gamma_L, gamma_U) -> (e, epsilon, xi)``: the expressions
    :func:`law` is built from, as their own Function (for ``stt-codegen verify``; not
    emitted).

    Parameters
    ----------
    n : int
        State dimension (every input and output has ``n`` entries).

    Returns
    -------
    casadi.Function
        :func:`error_transform_expression` as a Function.
    """
    x, gamma_l, gamma_u = (ca.SX.sym(name, n) for name in ("x", "gamma_L", "gamma_U"))
    return ca.Function("error_transform", [x, gamma_l, gamma_u],
                       list(error_transform_expression(x, gamma_l, gamma_u)),
                       ["x", "gamma_L", "gamma_U"], ["e", "epsilon", "xi"])


@lru_cache(maxsize=None)
def law(n: int) -> ca.Function:
    """``law(x, gamma_L, gamma_U, gain) -> (u, inside)``.

    Parameters
    ----------
    n : int
        State dimension (``x``, ``gamma_L``, ``gamma_U``, ``u`` have ``n`` entries).

    Returns
    -------
    casadi.Function
        :func:`law_expression` as a Function.
    """
    x, gamma_l, gamma_u = (ca.SX.sym(name, n) for name in ("x", "gamma_L", "gamma_U"))
    gain = ca.SX.sym("gain")
    u, inside = law_expression(x, gamma_l, gamma_u, gain, n)
    return ca.Function("law", [x, gamma_l, gamma_u, gain], [u, inside],
                       ["x", "gamma_L", "gamma_U", "gain"], ["u", "inside"])


def deployed_pieces(n: int, profiles: tuple, single_bounds: bool = True,
                    multi_bounds: bool = True, saturated: bool = False,
                    blended: bool = False) -> list:
    """Every piece the generated code of a design of dimension ``n`` calls, in a fixed order.

    ``profiles``: the segment profiles it uses; ``single_bounds`` / ``multi_bounds``: whether
    some bound has exactly one / several circumvents (``bump`` is emitted with either, the
    ``F_nu`` pieces only with several, ``fnu_single`` only with one); ``saturated``: the
    design has an actuator bound (``saturate`` is emitted last, only then); ``blended``: some
    segment starts before the previous one ends (``blend`` is emitted after ``interpolate``,
    only then).

    Parameters
    ----------
    n : int
        State dimension.
    profiles : tuple of str
        The segment profiles the design uses (a subset of :data:`PROFILE_NAMES`).
    single_bounds : bool
        Some bound has exactly one circumvent.
    multi_bounds : bool
        Some bound has several circumvents.
    saturated : bool
        The design has an actuator bound.
    blended : bool
        The design blends corners (two segments move the tube at once somewhere).

    Returns
    -------
    list of casadi.Function
        The pieces, in emission order (the order of the generated files).
    """
    init, add, finish, single = fnu_pieces()
    cand, cand_rates = candidates(n)
    circumvents = ([bump(False), bump()] if single_bounds or multi_bounds else []) + (
        [init, add, finish] if multi_bounds else []) + ([single] if single_bounds else [])
    used = [p for p in PROFILE_NAMES if p in profiles]
    return [*(progress(p, False) for p in used), *(progress(p) for p in used),
            interpolate(n, False), interpolate(n),
            *([blend(n, False), blend(n)] if blended else []), *circumvents, cand, cand_rates,
            *smooth_pieces(), conflict(n), alpha_rate(n),
            later(), *newton_pieces(), law(n), *([saturate(n)] if saturated else [])]
