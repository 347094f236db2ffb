"""Symbolic model of the tube and its controller in CasADi.

:func:`build_model` turns a :class:`~stt_codegen.tube.parameters.TubeDesign` into CasADi SX
``Function``s with named inputs and outputs (see :data:`FUNCTION_NAMES`). Time
derivatives and Jacobians are exact (algorithmic differentiation of the SX graph).
The functions are the single source of every generated controller.

Numerical decisions (all documented in the README):

* smooth max of eq. (10) ``max~(a, b) = max(a, b) + log1p(exp(-nu |a - b|)) / nu``, the
  paper's ``(1/nu) ln(e^{nu a} + e^{nu b})`` rewritten so it cannot overflow;
* eq. (9) combines the bumps on one bound by ``F_nu`` (:func:`open_bump_sum`), to which a
  closed window contributes exactly 0;
* the reach tube is piecewise over ``design.segments``; ``tanh((t - start)/(end - t))``
  is only evaluated for ``t < end`` (eq. (4)'s second branch holds after), with a
  denominator that stays finite in the branch not taken;
* the circumvent bump is only evaluated inside its window (eqs. (7)-(8));
* the implicit ``alpha`` step is backward Euler with :data:`~stt_codegen.tube.parameters.NEWTON_ITERATIONS`
  Newton iterations from a start point left of the root (see :func:`implicit_alpha_update`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from .parameters import (E_MAX, GAMMA_D_MIN, LOWER, NEWTON_ITERATIONS, NEWTON_TINY,
                         SMOOTHSTEP, TANH, UPPER, ReachSegment, TubeDesign)

#: The functions of a model, in order.
FUNCTION_NAMES = ("reach_tube", "circumvent", "tube", "adaptive_law", "error_transform",
                  "control", "alpha_step", "controller_step")


#: Bound on the argument of ``exp`` where it could be large (the smooth max's correction
#: and the trigger of (11)): ``exp(+-80)`` is a normal number in float32 and float64, so no
#: step raises an overflow or underflow flag or sets ``errno``.
EXP_ARGUMENT_BOUND = 80.0


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
        is returned unchanged. With two values ``max(a, b) + log1p(exp(-nu |a - b|)) / nu``,
        the exponent clamped at ``-80`` (:data:`EXP_ARGUMENT_BOUND`: no underflow; the
        correction is then below ``4e-35 / nu``, see :func:`smooth_max_test`).
    """
    if len(values) == 1:
        return values[0]
    if len(values) == 2:
        a, b = values
        d = ca.fmax(-nu * ca.fabs(a - b), -EXP_ARGUMENT_BOUND)
        return ca.fmax(a, b) + ca.log1p(ca.exp(d)) / nu
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


def smooth_max_test(a, b, nu: float) -> tuple:
    """``(max(a, b), needed)``: whether :func:`smooth_max` of two values can differ from the max.

    ``needed`` is 0 when ``nu |a - b| >= 80`` and ``|max| >= 2^54 e^-80 / nu``: the
    correction ``log1p(e^-80) / nu < e^-80 / nu <= |max| 2^-54`` is then below half an ulp of
    the max in float64 and float32, so ``smooth_max([a, b]) == max(a, b)`` exactly, and the
    generated code skips its ``exp`` and ``log1p``.
    """
    top = ca.fmax(a, b)
    sharp = ca.logic_and(nu * ca.fabs(a - b) >= EXP_ARGUMENT_BOUND,
                         ca.fabs(top) >= 2.0 ** 54 * 1.81e-35 / nu)
    return top, ca.logic_not(sharp)


def segment_progress(segment: ReachSegment, t):
    """Profile ``p`` of one reach segment as SX: 0 before ``start``, 1 from ``end`` on.

    ``"tanh"``: ``tanh((t - start) / (end - t))`` (eq. (4); only evaluated for
    ``t < end``, with a denominator that stays finite in the branch not taken);
    ``"smoothstep"``: ``tau^3 (10 - 15 tau + 6 tau^2)`` with ``tau`` clamped to ``[0, 1]``.
    """
    start, end = segment.start, segment.end
    if segment.profile == TANH:
        before = t < end
        gap = ca.if_else(before, end - t, 1.0)
        elapsed = t - start if start != 0.0 else t
        return ca.if_else(before, ca.if_else(elapsed < 0.0, 0.0, ca.tanh(elapsed / gap)), 1.0)
    if segment.profile != SMOOTHSTEP:
        raise ValueError(f"unknown reach segment profile {segment.profile!r}")
    tau = ca.fmin(ca.fmax((t - start) / (end - start), 0.0), 1.0)
    return tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau)


def reach_tube(design: TubeDesign, t) -> tuple:
    """``rho_L(t)``, ``rho_U(t)`` of eq. (4), piecewise over ``design.segments``, SX vectors of length n.

    On the first segment whose ``end`` is after ``t`` (the last one after every end):
    ``rho = from + (to - from) p``, ``p`` from :func:`segment_progress`.
    """
    def on(segment):
        s = segment_progress(segment, t)
        lower = [(b - a) * s + a for a, b in zip(segment.lower_from, segment.lower_to)]
        upper = [(b - a) * s + a for a, b in zip(segment.upper_from, segment.upper_to)]
        return ca.vertcat(*lower), ca.vertcat(*upper)

    rho_l, rho_u = on(design.segments[-1])
    for segment in reversed(design.segments[:-1]):
        here_l, here_u = on(segment)
        sooner = t < segment.end
        rho_l, rho_u = ca.if_else(sooner, here_l, rho_l), ca.if_else(sooner, here_u, rho_u)
    return rho_l, rho_u


def bump(t, center: float, radius: float, sharpness: float):
    """``exp(-k (t-m)^2 / (r^2 - (t-m)^2))`` inside ``|t - m| < r``, 0 outside (eqs. (7)-(8))."""
    d = t - center
    inside = ca.fabs(d) < radius
    # (r - |d|)(r + |d|), not r^2 - d^2: rounded separately from the test |d| < r, the
    # latter can be exactly 0 at the window's edge in float32
    denom = ca.if_else(inside, (radius - ca.fabs(d)) * (radius + ca.fabs(d)), 1.0)
    return ca.if_else(inside, ca.exp(-sharpness * d**2 / denom), 0.0)


def open_bump_sum(heights: list, nu: float):
    """``F_nu(y) = (1/nu) ln(1 + sum_j (exp(nu y_j) - 1))`` of eq. (9) (as decided), SX.

    Written ``M + (1/nu) ln(exp(-nu M) + sum_j (exp(nu (y_j - M)) - exp(-nu M)))``,
    ``M = max(0, max_j y_j)``, which cannot overflow; a closed window (``y_j = 0``) adds
    exactly 0; one argument is returned unchanged (``F = y``).

    Parameters
    ----------
    heights : list of casadi.SX, non-empty
        ``y_j = B^j b^j(t) >= 0``, state units.
    nu : float
        1/state units.
    """
    if len(heights) == 1:
        return heights[0]
    top = ca.SX(0.0)
    for y in heights:
        top = ca.fmax(top, y)
    floor = ca.exp(-nu * top)
    total = floor
    for y in heights:
        total = total + (ca.exp(nu * (y - top)) - floor)
    return top + ca.log(total) / nu


def circumvent(design: TubeDesign, t) -> tuple:
    """Holistic circumvent ``beta_L(t)``, ``beta_U(t)`` of eq. (9), SX vectors of length n.

    ``beta_L_i = X_i + F_nu(y)``, ``beta_U_i = X-bar_i - F_nu(y)``, ``y_j = B^j b^j(t)`` over
    the circumvents on that bound (:func:`open_bump_sum`).
    """
    lower, upper = [], []
    for i in range(design.dimension):
        for side, out, bound in ((LOWER, lower, design.state_lower[i]),
                                 (UPPER, upper, design.state_upper[i])):
            members = design.circumvents_on(i, side)
            if not members:
                out.append(ca.SX(bound))
                continue
            heights = [c.height * bump(t, c.center, c.radius, c.sharpness) for c in members]
            total = open_bump_sum(heights, design.smoothness)
            out.append(bound + total if side == LOWER else bound - total)
    return ca.vertcat(*lower), ca.vertcat(*upper)


def conflict_distance(design: TubeDesign, t):
    """``psi = [beta_U - rho_L, rho_U - beta_L]`` of eq. (11), SX vector of length 2n."""
    rho_l, rho_u = reach_tube(design, t)
    beta_l, beta_u = circumvent(design, t)
    return ca.vertcat(beta_u - rho_l, rho_u - beta_l)


def trigger(design: TubeDesign, psi):
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) (sign approximated by tanh).

    Computed as ``2 theta0 / (1 + exp(y))``, ``y = 2 (psi - mu)`` clamped to
    ``[-80, 80]`` (:data:`EXP_ARGUMENT_BOUND`): the same function (``1 - tanh(y/2) =
    2 / (1 + e^y)``), one ``exp`` instead of ``tanh``, exact to the last bit or below
    ``4e-35 theta0`` where clamped.
    """
    y = ca.fmin(ca.fmax(2.0 * (psi - design.mu), -EXP_ARGUMENT_BOUND), EXP_ARGUMENT_BOUND)
    return (2.0 * design.theta0) / (1.0 + ca.exp(y))


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


def newton_start(alpha, psi, theta, dt, kappa: float) -> tuple:
    """Quantities of the implicit step and a start that needs no root: ``(a0, c, A, root)``.

    ``c = 1 + kappa dt``, ``A = dt theta``, ``a0 = alpha / c``. ``root`` is 1 when the
    start of :func:`newton_root_start` is needed, i.e. unless ``z0 = psi + a0 > 0`` and
    ``2 c z0^3 >= A``: then ``a0 >= -psi + (A / 2c)^(1/3) >= -psi + delta``, so ``a0`` is the
    start :func:`newton_root_start` would return, without its cube and square roots.
    Element-wise on SX of any shape.
    """
    c = 1.0 + kappa * dt
    a_coef = dt * theta
    a0 = alpha / c
    z0 = psi + a0
    fast = ca.logic_and(z0 > 0.0, 2.0 * c * (z0 * z0 * z0) >= a_coef)
    return a0, c, a_coef, ca.logic_not(fast)


def newton_root_start(alpha, psi, c, a_coef):
    """``max(alpha / c, -psi + delta)``, ``delta = min((A / 2c)^(1/3), sqrt(A / 2Q))``,
    ``Q = max(-c psi - alpha, 0)``: a start left of the root (``g <= 0``, proof in
    docs/codegen.md), used when ``alpha / c`` is too close to (or beyond) the pole."""
    q = ca.fmax(-c * psi - alpha, 0.0)
    delta = ca.fmin((a_coef / (2.0 * c)) ** (1.0 / 3.0),
                    ca.sqrt(a_coef / (2.0 * ca.fmax(q, NEWTON_TINY))))
    return ca.fmax(alpha / c, -psi + delta)


def newton_iteration(a, alpha, psi, c, a_coef):
    """One Newton iteration on ``g(a) = c a - alpha - A / (psi + a)^2``, one division.

    ``a - g / g'`` with ``g' = c + 2 A / z^3``, ``z = psi + a``, multiplied through by ``z^3``:
    ``a - z (z^2 (c a - alpha) - A) / (c z^3 + 2 A)``.
    """
    z = psi + a
    z2 = z * z
    return a - z * (z2 * (c * a - alpha) - a_coef) / (c * (z2 * z) + 2.0 * a_coef)


def implicit_alpha_update(alpha, psi, theta, dt, kappa: float,
                          iterations: int = NEWTON_ITERATIONS):
    """Backward-Euler step of (11): solve ``a = alpha + dt (theta/(psi+a)^2 - kappa a)``.

    Component-wise (the Newton system is diagonal). The residual
    ``g(a) = (1 + kappa dt) a - alpha - dt theta / (psi + a)^2`` is increasing and concave
    on ``(-psi, inf)``, so Newton's method started at a point where ``g <= 0`` increases
    monotonically to the unique root without leaving the domain. The start is
    ``alpha / c`` (:func:`newton_start`) when it is far enough from the pole, else
    :func:`newton_root_start`; then ``iterations`` of :func:`newton_iteration`. The
    generated code runs the same three pieces (the root start only when needed, the
    iterations in a loop), so it computes exactly this.

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
    a0, c, a_coef, root = newton_start(alpha, psi, theta, dt, kappa)
    a = ca.if_else(root, newton_root_start(alpha, psi, c, a_coef), a0)
    for _ in range(iterations):
        a = newton_iteration(a, alpha, psi, c, a_coef)
    return a


def controller_law(design: TubeDesign, x, gamma_l, gamma_u) -> tuple:
    """Deployed law (13) with clamps: returns ``(u, inside)`` (see :mod:`stt_codegen.tube.parameters`)."""
    gamma_d = gamma_u - gamma_l
    width = ca.fmax(gamma_d, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / width
    inside = 1.0
    for i in range(design.dimension):
        inside = ca.logic_and(inside, ca.logic_and(ca.fabs(e[i]) < 1.0, gamma_d[i] > 0.0))
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
