"""Symbolic model of the tube and its controller in CasADi.

:func:`build_model` turns a :class:`~stt_codegen.tube.parameters.TubeDesign` into CasADi SX
``Function``s with named inputs and outputs (see :data:`FUNCTION_NAMES`). Time
derivatives and Jacobians are exact (algorithmic differentiation of the SX graph).
The functions are the single source of every generated controller.

Numerical decisions (all documented in the README):

* smooth max ``max~(a, b) = max(a, b) + log1p(exp(-nu |a - b|)) / nu``, the paper's
  ``(1/nu) ln(e^{nu a} + e^{nu b})`` rewritten so it cannot overflow; with more than two
  arguments ``M + ln(sum_j exp(nu (a_j - M))) / nu`` with ``M = max_j a_j``;
* ``tanh(t / (t_c - t))`` is only evaluated for ``t < t_c`` (eq. (4)'s second branch
  holds after), with a denominator that stays finite in the branch not taken;
* the circumvent bump is only evaluated inside its window (eqs. (7)-(8));
* the implicit ``alpha`` step is backward Euler with :data:`~stt_codegen.tube.parameters.NEWTON_ITERATIONS`
  Newton iterations from a start point left of the root (see :func:`implicit_alpha_update`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from .parameters import (E_MAX, GAMMA_D_MIN, LOWER, NEWTON_ITERATIONS, NEWTON_TINY, UPPER,
                         TubeDesign)

#: The functions of a model, in order.
FUNCTION_NAMES = ("reach_tube", "circumvent", "tube", "adaptive_law", "error_transform",
                  "control", "alpha_step", "controller_step")


def smooth_max(values: list, nu: float):
    """Smooth maximum of SX scalars, the paper's ``max~`` (notation, section II).

    Parameters
    ----------
    values : list of casadi.SX, non-empty
    nu : float
        Sharpness ``nu``, 1/state units.

    Returns
    -------
    casadi.SX
        ``(1/nu) ln(sum_j exp(nu a_j))`` in a form that does not overflow; a single value
        is returned unchanged.
    """
    if len(values) == 1:
        return values[0]
    if len(values) == 2:
        a, b = values
        return ca.fmax(a, b) + ca.log1p(ca.exp(-nu * ca.fabs(a - b))) / nu
    top = values[0]
    for v in values[1:]:
        top = ca.fmax(top, v)
    total = 0
    for v in values:
        total = total + ca.exp(nu * (v - top))
    return top + ca.log(total) / nu


def smooth_min(values: list, nu: float):
    """Smooth minimum ``min~(a, b) = -max~(-a, -b)``; see :func:`smooth_max`."""
    return -smooth_max([-v for v in values], nu)


def tanh_progress(design: TubeDesign, t):
    """``s(t) = tanh(t / (t_c - t))`` for ``t < t_c``, 1 after (eq. (4))."""
    t_c = design.prescribed_time
    before = t < t_c
    gap = ca.if_else(before, t_c - t, 1.0)
    return ca.if_else(before, ca.tanh(t / gap), 1.0)


def reach_tube(design: TubeDesign, t) -> tuple:
    """``rho_L(t)``, ``rho_U(t)`` of eq. (4) as SX column vectors of length n."""
    s = tanh_progress(design, t)
    lower = [(tl - xl) * s + xl for xl, tl in zip(design.initial_lower, design.target_lower)]
    upper = [(tu - xu) * s + xu for xu, tu in zip(design.initial_upper, design.target_upper)]
    return ca.vertcat(*lower), ca.vertcat(*upper)


def bump(t, center: float, radius: float, sharpness: float):
    """``exp(-k (t-m)^2 / (r^2 - (t-m)^2))`` inside ``|t - m| < r``, 0 outside (eqs. (7)-(8))."""
    d = t - center
    inside = ca.fabs(d) < radius
    # (r - |d|)(r + |d|), not r^2 - d^2: rounded separately from the test |d| < r, the
    # latter can be exactly 0 at the window's edge in float32
    denom = ca.if_else(inside, (radius - ca.fabs(d)) * (radius + ca.fabs(d)), 1.0)
    return ca.if_else(inside, ca.exp(-sharpness * d**2 / denom), 0.0)


def circumvent(design: TubeDesign, t) -> tuple:
    """Holistic circumvent ``beta_L(t)``, ``beta_U(t)`` of eq. (9), SX vectors of length n."""
    lower, upper = [], []
    for i in range(design.dimension):
        for side, out, bound in ((LOWER, lower, design.state_lower[i]),
                                 (UPPER, upper, design.state_upper[i])):
            members = design.circumvents_on(i, side)
            if not members:
                out.append(ca.SX(bound))
                continue
            sign = 1.0 if side == LOWER else -1.0
            terms = [c.base + sign * c.height *
                     bump(t, c.center, c.radius, design.circumvent_sharpness) for c in members]
            out.append(smooth_max(terms, design.smoothness) if side == LOWER
                       else smooth_min(terms, design.smoothness))
    return ca.vertcat(*lower), ca.vertcat(*upper)


def conflict_distance(design: TubeDesign, t):
    """``psi = [beta_U - rho_L, rho_U - beta_L]`` of eq. (11), SX vector of length 2n."""
    rho_l, rho_u = reach_tube(design, t)
    beta_l, beta_u = circumvent(design, t)
    return ca.vertcat(beta_u - rho_l, rho_u - beta_l)


def trigger(design: TubeDesign, psi):
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) (sign approximated by tanh)."""
    return design.theta0 * (1.0 - ca.tanh(psi - design.mu))


def adaptive_law(design: TubeDesign, t, alpha):
    """``alpha_dot = theta / (psi + alpha)^2 - kappa alpha``, eq. (11), SX vector of length 2n."""
    psi = conflict_distance(design, t)
    return trigger(design, psi) / (psi + alpha) ** 2 - design.kappa * alpha


def adaptive_tube(design: TubeDesign, t, alpha) -> tuple:
    """``gamma_L``, ``gamma_U`` of eq. (10), SX vectors of length n."""
    n = design.dimension
    rho_l, rho_u = reach_tube(design, t)
    beta_l, beta_u = circumvent(design, t)
    nu = design.smoothness
    gamma_l = ca.vertcat(*[smooth_max([rho_l[i] - alpha[i], beta_l[i]], nu) for i in range(n)])
    gamma_u = ca.vertcat(*[smooth_min([rho_u[i] + alpha[n + i], beta_u[i]], nu)
                           for i in range(n)])
    return gamma_l, gamma_u


def implicit_alpha_update(alpha, psi, theta, dt, kappa: float,
                          iterations: int = NEWTON_ITERATIONS):
    """Backward-Euler step of (11): solve ``a = alpha + dt (theta/(psi+a)^2 - kappa a)``.

    Component-wise (the Newton system is diagonal). The residual
    ``g(a) = (1 + kappa dt) a - alpha - dt theta / (psi + a)^2`` is increasing and concave
    on ``(-psi, inf)``, so Newton's method started at a point where ``g <= 0`` increases
    monotonically to the unique root without leaving the domain. The start
    ``max(alpha / c, -psi + delta)``, ``c = 1 + kappa dt``, with
    ``delta = min((A / 2c)^(1/3), sqrt(A / 2Q))``, ``A = dt theta``,
    ``Q = max(-c psi - alpha, 0)``, has ``g <= 0`` (proof in the README).

    Parameters
    ----------
    alpha, psi, theta : casadi.SX, shape (m, 1)
        Current ``alpha``; ``psi`` and ``theta`` at the end of the step.
    dt : casadi.SX scalar
        Step, seconds, positive.
    kappa : float
    iterations : int

    Returns
    -------
    casadi.SX, shape (m, 1)
    """
    c = 1.0 + kappa * dt
    a_coef = dt * theta
    q = ca.fmax(-c * psi - alpha, 0.0)
    delta = ca.fmin((a_coef / (2.0 * c)) ** (1.0 / 3.0),
                    ca.sqrt(a_coef / (2.0 * ca.fmax(q, NEWTON_TINY))))
    a = ca.fmax(alpha / c, -psi + delta)
    for _ in range(iterations):
        z = psi + a
        residual = c * a - alpha - a_coef / z**2
        slope = c + 2.0 * a_coef / z**3
        a = a - residual / slope
    return a


def controller_law(design: TubeDesign, x, gamma_l, gamma_u) -> tuple:
    """Deployed law (13) with clamps: returns ``(u, inside)`` (see :mod:`stt_codegen.tube.parameters`)."""
    gamma_d = gamma_u - gamma_l
    width = ca.fmax(gamma_d, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / width
    inside = 1.0
    for i in range(design.dimension):
        inside = ca.logic_and(inside, ca.fabs(2.0 * x[i] - (gamma_u[i] + gamma_l[i])) < gamma_d[i])
    e_c = ca.fmin(ca.fmax(e, -E_MAX), E_MAX)
    epsilon = ca.log((1.0 + e_c) / (1.0 - e_c))
    xi = 4.0 / (width * (1.0 - e_c**2))
    return -design.gain * xi * epsilon, inside


@dataclass(frozen=True)
class TubeModel:
    """The CasADi functions of one designed tube.

    Attributes
    ----------
    design : TubeDesign
    functions : dict of str to casadi.Function
        Keyed and ordered as :data:`FUNCTION_NAMES`; inputs and outputs are named.
    """

    design: TubeDesign
    functions: dict

    def __getitem__(self, name: str) -> ca.Function:
        return self.functions[name]


def build_model(design: TubeDesign) -> TubeModel:
    """Build the CasADi SX functions of a design (see ``interfaces`` in the README).

    Parameters
    ----------
    design : TubeDesign

    Returns
    -------
    TubeModel
    """
    n = design.dimension
    t = ca.SX.sym("t")
    dt = ca.SX.sym("dt")
    x = ca.SX.sym("x", n)
    alpha = ca.SX.sym("alpha", 2 * n)
    fns: dict[str, ca.Function] = {}

    rho_l, rho_u = reach_tube(design, t)
    fns["reach_tube"] = ca.Function(
        "reach_tube", [t], [rho_l, rho_u, ca.jacobian(rho_l, t), ca.jacobian(rho_u, t)],
        ["t"], ["rho_L", "rho_U", "rho_L_dot", "rho_U_dot"])

    beta_l, beta_u = circumvent(design, t)
    fns["circumvent"] = ca.Function(
        "circumvent", [t], [beta_l, beta_u, ca.jacobian(beta_l, t), ca.jacobian(beta_u, t)],
        ["t"], ["beta_L", "beta_U", "beta_L_dot", "beta_U_dot"])

    alpha_dot = adaptive_law(design, t, alpha)
    gamma_l, gamma_u = adaptive_tube(design, t, alpha)

    def total_rate(expr):
        return ca.jacobian(expr, t) + ca.mtimes(ca.jacobian(expr, alpha), alpha_dot)

    fns["tube"] = ca.Function(
        "tube", [t, alpha], [gamma_l, gamma_u, total_rate(gamma_l), total_rate(gamma_u)],
        ["t", "alpha"], ["gamma_L", "gamma_U", "gamma_L_dot", "gamma_U_dot"])

    fns["adaptive_law"] = ca.Function(
        "adaptive_law", [t, alpha], [alpha_dot, ca.diag(ca.jacobian(alpha_dot, alpha))],
        ["t", "alpha"], ["alpha_dot", "alpha_dot_jacobian"])

    gamma_d = gamma_u - gamma_l
    e = (2.0 * x - (gamma_u + gamma_l)) / gamma_d
    epsilon = ca.log((1.0 + e) / (1.0 - e))
    xi = 4.0 / (gamma_d * (1.0 - e**2))
    eps_jac = ca.densify(ca.jacobian(epsilon, x))
    fns["error_transform"] = ca.Function(
        "error_transform", [x, t, alpha], [e, epsilon, xi, ca.reshape(eps_jac, n * n, 1)],
        ["x", "t", "alpha"], ["e", "epsilon", "xi", "epsilon_jacobian"])

    fns["control"] = ca.Function("control", [x, t, alpha], [-design.gain * xi * epsilon],
                                 ["x", "t", "alpha"], ["u"])

    psi_next = conflict_distance(design, t + dt)
    alpha_next = implicit_alpha_update(alpha, psi_next, trigger(design, psi_next), dt,
                                       design.kappa)
    fns["alpha_step"] = ca.Function("alpha_step", [t, dt, alpha], [alpha_next],
                                    ["t", "dt", "alpha"], ["alpha_next"])

    u, inside = controller_law(design, x, gamma_l, gamma_u)
    fns["controller_step"] = ca.Function(
        "controller_step", [x, t, dt, alpha], [u, alpha_next, inside],
        ["x", "t", "dt", "alpha"], ["u", "alpha_next", "inside"])
    return TubeModel(design, {name: fns[name] for name in FUNCTION_NAMES})


def alpha_trajectory_function(design: TubeDesign, steps: int) -> ca.Function:
    """``alpha`` along a grid of ``steps`` implicit steps, given ``psi`` on the grid.

    Used by the design search to integrate (11) exactly as the deployed controller does.

    Returns
    -------
    casadi.Function
        ``(alpha0 (2n), psi (2n x steps), dt) -> alpha (2n x steps)``: column ``k`` is
        ``alpha`` after ``k + 1`` steps, the ``k``-th step using ``psi[:, k]``.
    """
    m = 2 * design.dimension
    a = ca.SX.sym("alpha", m)
    psi = ca.SX.sym("psi", m)
    dt = ca.SX.sym("dt")
    update = ca.Function("alpha_update", [a, psi, dt],
                         [implicit_alpha_update(a, psi, trigger(design, psi), dt, design.kappa)])
    return update.mapaccum("alpha_trajectory", steps, [0], [0])
