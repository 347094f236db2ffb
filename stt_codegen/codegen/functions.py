"""The CasADi Functions whose bodies are deployed, each emitted once, from the model's.

The generated API (C: ``<prefix>_tube``, ``_control``, ``_alpha_step``, ``_step``; Python:
``tube``, ``control``, ``alpha_step``, ``step``) is control flow around four bodies:

=================  ========================  ======================================
body               inputs                    outputs
=================  ========================  ======================================
``gamma_candidates`` t, alpha (2n)           rho_L - alpha_L, beta_L, rho_U + alpha_U, beta_U
``smooth_max_test`` a, b                     max(a, b), needed (scalars)
``smooth_max``     a, b                      max~(a, b) (eq. (10), only when needed)
``smooth_min_test`` a, b                     min(a, b), needed
``smooth_min``     a, b                      min~(a, b) (only when needed)
``gamma_rates``    t, alpha (2n)             gamma_L_dot, gamma_U_dot
``law``            x (n), gamma_L, gamma_U   u (n), inside (1) (law (13), clamped)
``alpha_conflict``  t, dt                    psi, theta (2n each) at t + dt (eq. (11))
``newton_start``   alpha, psi, theta, dt     a0, c, A, root (scalars)
``newton_root_start`` alpha, psi, c, A       a0 (scalar, only when ``root`` is 1)
``newton_iteration`` a, alpha, psi, c, A     a (scalar, one division)
=================  ========================  ======================================

``gamma`` (the tube of eq. (10)) = ``gamma_candidates``, then per dimension the test and,
where the smooth max/min can differ from the max/min, its correction;
``tube`` = ``gamma`` + ``gamma_rates``; ``control`` = ``gamma`` + ``law``; ``alpha_step``
= ``alpha_conflict``, then per component ``newton_start``, ``newton_root_start`` if
needed and ``NEWTON_ITERATIONS`` x ``newton_iteration`` in a loop; ``step`` = ``control``
+ ``alpha_step``. No body repeats another: the step's ``u`` and ``alpha_next`` are the
values of the model's ``controller_step`` bit for bit (the same operations on the same
values, cut at ``gamma`` and between the Newton pieces), and ``control`` is the step's
``u`` (``e`` clamped to
``[-E_MAX, E_MAX]``, ``gamma_d`` floored: finite outside the tube), not the model's
unclamped ``control``.
"""

from __future__ import annotations

import casadi as ca

from ..tube.model import (TubeModel, adaptive_tube, circumvent, conflict_distance,
                          controller_law, newton_iteration, newton_root_start, newton_start,
                          reach_tube, smooth_max, smooth_max_test, smooth_min, trigger)

#: Deployed body names, in generation order.
DEPLOYED = ("gamma_candidates", "smooth_max_test", "smooth_max", "smooth_min_test",
            "smooth_min", "gamma_rates", "law", "alpha_conflict", "newton_start",
            "newton_root_start", "newton_iteration")


def gamma_function(model: TubeModel) -> ca.Function:
    """``gamma(t, alpha) -> (gamma_L, gamma_U)``: the tube of eq. (10) at ``t``."""
    n = model.design.dimension
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 2 * n)
    gamma_l, gamma_u = adaptive_tube(model.design, t, alpha)
    return ca.Function("gamma", [t, alpha], [gamma_l, gamma_u], ["t", "alpha"],
                       ["gamma_L", "gamma_U"])


def gamma_candidates_function(model: TubeModel) -> ca.Function:
    """``gamma_candidates(t, alpha)``: the two arguments of each smooth max/min of eq. (10)."""
    n = model.design.dimension
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 2 * n)
    rho_l, rho_u = reach_tube(model.design, t)
    beta_l, beta_u = circumvent(model.design, t)
    return ca.Function("gamma_candidates", [t, alpha],
                       [rho_l - alpha[:n], beta_l, rho_u + alpha[n:], beta_u], ["t", "alpha"],
                       ["rho_L_minus_alpha", "beta_L", "rho_U_plus_alpha", "beta_U"])


def smooth_functions(model: TubeModel) -> list[ca.Function]:
    """``smooth_max_test``, ``smooth_max``, ``smooth_min_test``, ``smooth_min`` on scalars."""
    nu = model.design.smoothness
    a, b = ca.SX.sym("a"), ca.SX.sym("b")
    top, needed = smooth_max_test(a, b, nu)
    neg_top, neg_needed = smooth_max_test(-a, -b, nu)
    return [
        ca.Function("smooth_max_test", [a, b], [top, needed], ["a", "b"], ["max", "needed"]),
        ca.Function("smooth_max", [a, b], [smooth_max([a, b], nu)], ["a", "b"], ["max"]),
        ca.Function("smooth_min_test", [a, b], [-neg_top, neg_needed], ["a", "b"],
                    ["min", "needed"]),
        ca.Function("smooth_min", [a, b], [smooth_min([a, b], nu)], ["a", "b"], ["min"]),
    ]


def gamma_rates_function(model: TubeModel) -> ca.Function:
    """``gamma_rates(t, alpha) -> (gamma_L_dot, gamma_U_dot)``: the model's ``tube`` rates."""
    tube = model["tube"]
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", tube.size1_in(1))
    _, _, rate_l, rate_u = tube(t, alpha)
    return ca.Function("gamma_rates", [t, alpha], [rate_l, rate_u], ["t", "alpha"],
                       ["gamma_L_dot", "gamma_U_dot"])


def law_function(model: TubeModel) -> ca.Function:
    """``law(x, gamma_L, gamma_U) -> (u, inside)``: the deployed law (13) with its clamps."""
    n = model.design.dimension
    x = ca.SX.sym("x", n)
    gamma_l = ca.SX.sym("gamma_L", n)
    gamma_u = ca.SX.sym("gamma_U", n)
    u, inside = controller_law(model.design, x, gamma_l, gamma_u)
    return ca.Function("law", [x, gamma_l, gamma_u], [u, inside], ["x", "gamma_L", "gamma_U"],
                       ["u", "inside"])


def alpha_conflict_function(model: TubeModel) -> ca.Function:
    """``alpha_conflict(t, dt) -> (psi, theta)`` at ``t + dt`` (eq. (11))."""
    t = ca.SX.sym("t")
    dt = ca.SX.sym("dt")
    psi = conflict_distance(model.design, t + dt)
    return ca.Function("alpha_conflict", [t, dt], [psi, trigger(model.design, psi)],
                       ["t", "dt"], ["psi", "theta"])


def newton_functions(model: TubeModel) -> list[ca.Function]:
    """The scalar pieces of the implicit step: ``newton_start``, ``newton_root_start``,
    ``newton_iteration`` (see :func:`stt_codegen.tube.model.implicit_alpha_update`)."""
    alpha, psi, theta, dt, a, c, a_coef = (ca.SX.sym(name) for name in
                                           ("alpha", "psi", "theta", "dt", "a", "c", "A"))
    a0, c_out, a_out, root = newton_start(alpha, psi, theta, dt, model.design.kappa)
    return [
        ca.Function("newton_start", [alpha, psi, theta, dt], [a0, c_out, a_out, root],
                    ["alpha", "psi", "theta", "dt"], ["a0", "c", "A", "root"]),
        ca.Function("newton_root_start", [alpha, psi, c, a_coef],
                    [newton_root_start(alpha, psi, c, a_coef)], ["alpha", "psi", "c", "A"],
                    ["a0"]),
        ca.Function("newton_iteration", [a, alpha, psi, c, a_coef],
                    [newton_iteration(a, alpha, psi, c, a_coef)],
                    ["a", "alpha", "psi", "c", "A"], ["a_next"]),
    ]


def clamped_control(model: TubeModel) -> ca.Function:
    """``control(x, t, alpha) -> (u, inside)``: ``law`` applied to ``gamma`` (for tests)."""
    n = model.design.dimension
    x = ca.SX.sym("x", n)
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 2 * n)
    gamma_l, gamma_u = gamma_function(model)(t, alpha)
    u, inside = law_function(model)(x, gamma_l, gamma_u)
    return ca.Function("control", [x, t, alpha], [u, inside], ["x", "t", "alpha"],
                       ["u", "inside"])


def deployed_functions(model: TubeModel) -> list[ca.Function]:
    """The deployed SX Functions, in the order of :data:`DEPLOYED`."""
    return [gamma_candidates_function(model), *smooth_functions(model),
            gamma_rates_function(model), law_function(model),
            alpha_conflict_function(model), *newton_functions(model)]
