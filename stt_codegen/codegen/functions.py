"""The CasADi Functions whose bodies are deployed, each emitted once, from the model's.

The generated API (C: ``<prefix>_tube``, ``_control``, ``_alpha_step``, ``_step``; Python:
``tube``, ``control``, ``alpha_step``, ``step``) is control flow around four bodies:

=================  ========================  ======================================
body               inputs                    outputs
=================  ========================  ======================================
``gamma``          t, alpha (2n)             gamma_L, gamma_U (eq. (10))
``gamma_rates``    t, alpha (2n)             gamma_L_dot, gamma_U_dot
``law``            x (n), gamma_L, gamma_U   u (n), inside (1) (law (13), clamped)
``alpha_step``     t, dt, alpha (2n)         alpha_next (2n) (implicit step of (11))
=================  ========================  ======================================

``tube`` = ``gamma`` + ``gamma_rates``; ``control`` = ``gamma`` + ``law``; ``step`` =
``gamma`` + ``law`` + ``alpha_step``. No body repeats another: the step's ``u`` and
``alpha_next`` are the values of the model's ``controller_step`` bit for bit (the same SX
graph, cut at ``gamma``), and ``control`` is the step's ``u`` (``e`` clamped to
``[-E_MAX, E_MAX]``, ``gamma_d`` floored: finite outside the tube), not the model's
unclamped ``control``.
"""

from __future__ import annotations

import casadi as ca

from ..tube.model import TubeModel, adaptive_tube, controller_law

#: Deployed body names, in generation order.
DEPLOYED = ("gamma", "gamma_rates", "law", "alpha_step")


def gamma_function(model: TubeModel) -> ca.Function:
    """``gamma(t, alpha) -> (gamma_L, gamma_U)``: the tube of eq. (10) at ``t``."""
    n = model.design.dimension
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 2 * n)
    gamma_l, gamma_u = adaptive_tube(model.design, t, alpha)
    return ca.Function("gamma", [t, alpha], [gamma_l, gamma_u], ["t", "alpha"],
                       ["gamma_L", "gamma_U"])


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
    return [gamma_function(model), gamma_rates_function(model), law_function(model),
            model["alpha_step"]]
