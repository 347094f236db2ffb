"""Symbolic model of the tube and its controller in CasADi.

:func:`build_model` turns a :class:`~stt_codegen.tube.parameters.TubeDesign` into CasADi SX
``Function``s with named inputs and outputs (see :data:`FUNCTION_NAMES`). Each is the
composition of the pieces of :mod:`stt_codegen.tube.pieces` (small Functions whose numbers
are inputs) with the design's numbers, over every reach segment and every circumvent, in
the order of the generated code's tables (:func:`design_tables`); the generated code
composes the same pieces the same way over ``const`` tables, evaluating only the active
segment and the open circumvents, so it computes exactly these Functions. Time
derivatives are exact (algorithmic differentiation of each piece, chain rule across them).

Numerical decisions (docs/codegen.md):

* smooth max of eq. (10) ``max~(a, b) = max(a, b) + log1p(exp(-nu |a - b|)) / nu``, the
  paper's ``(1/nu) ln(e^{nu a} + e^{nu b})`` rewritten so it cannot overflow, the exponent
  clamped at -80 (no underflow);
* eq. (9) combines the bumps on one bound by ``F_nu`` (:func:`~stt_codegen.tube.pieces.fnu_pieces`),
  to which a closed window contributes exactly 0;
* the reach tube is piecewise over ``design.segments``; ``tanh((t - start)/(end - t))``
  is only evaluated for ``t < end`` (eq. (4)'s second branch holds after);
* the circumvent bump is only evaluated inside its window (eqs. (7)-(8));
* the trigger of (11) is ``2 theta0 / (1 + exp(2 (psi - mu)))`` (= ``theta0 (1 - tanh(psi - mu))``);
* the implicit ``alpha`` step is backward Euler with :data:`~stt_codegen.tube.parameters.NEWTON_ITERATIONS`
  Newton iterations from a start point left of the root (see :func:`implicit_alpha_update`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from . import pieces as P
from .parameters import LOWER, NEWTON_ITERATIONS, TubeDesign

__all__ = ["FUNCTION_NAMES", "TubeModel", "adaptive_tube", "alpha_trajectory_function",
           "build_model", "conflict_and_trigger", "controller_law", "design_tables",
           "implicit_alpha_update", "segment_rows"]

#: The functions of a model, in order.
FUNCTION_NAMES = ("reach_tube", "circumvent", "tube", "adaptive_law", "error_transform",
                  "control", "alpha_step", "controller_step")


@dataclass(frozen=True)
class DesignTables:
    """The numbers of a design in the order of the generated code's tables.

    Attributes
    ----------
    segments : tuple of ReachSegment
        ``design.segments``, in time order.
    windows : tuple of (int, Circumvent)
        ``(bound, circumvent)`` sorted by window start (then design order); ``bound`` is
        ``i`` for the lower bound of dimension ``i``, ``n + i`` for its upper bound.
    bounds : tuple of float
        ``[X; X-bar]`` (2n).
    signs : tuple of float
        +1 for the n lower bounds, -1 for the n upper ones.
    """

    segments: tuple
    windows: tuple
    bounds: tuple
    signs: tuple

    def members(self, bound: int) -> tuple:
        """The circumvents on one bound, in table order."""
        return tuple(c for b, c in self.windows if b == bound)


def design_tables(design: TubeDesign) -> DesignTables:
    """The table order of a design's numbers (shared by the model and the generated code).

    Parameters
    ----------
    design : TubeDesign
        The tube.

    Returns
    -------
    DesignTables
        Its segments, circumvent windows, state-space bounds and signs, in table order.
    """
    n = design.dimension
    rows = []
    for index, c in enumerate(design.circumvents):
        bound = c.dimension if c.side == LOWER else n + c.dimension
        rows.append((c.start, index, bound, c))
    windows = tuple((bound, c) for _, _, bound, c in sorted(rows, key=lambda r: (r[0], r[1])))
    return DesignTables(tuple(design.segments), windows,
                        tuple(design.state_lower) + tuple(design.state_upper),
                        (1.0,) * n + (-1.0,) * n)


def segment_rows(design: TubeDesign, segment) -> tuple:
    """``(from, to)`` of a reach segment as 2n lists ``[lower; upper]``.

    Parameters
    ----------
    design : TubeDesign
        The tube the segment belongs to.
    segment : ReachSegment
        One reach segment.

    Returns
    -------
    from_row, to_row : list of float
        ``2n`` entries each, state units: the segment's start box and end box.
    """
    return (list(segment.lower_from) + list(segment.upper_from),
            list(segment.lower_to) + list(segment.upper_to))


def reach_tube_rates(design: TubeDesign, t) -> tuple:
    """``rho`` and ``rho_dot`` (2n SX vectors ``[L; U]``) of eq. (4), piecewise over the
    segments: the first segment whose ``end`` is after ``t`` (the last one after every end),
    plus the next segment's move where it has started (a blended corner)."""
    interpolate = P.interpolate(design.dimension)
    interpolate_value = P.interpolate(design.dimension, False)

    def on(segment):
        # the value from the value-only pieces (the step's), the rate from the full ones
        p, p_dot = P.progress(segment.profile)(t, segment.start, segment.end)
        lo, hi = segment_rows(design, segment)
        _, rate = interpolate(p, p_dot, ca.DM(lo), ca.DM(hi))
        p_value = P.progress(segment.profile, False)(t, segment.start, segment.end)
        return interpolate_value(p_value, ca.DM(lo), ca.DM(hi)), rate

    def blended(segment, following, here, here_dot):
        # a blended corner: where the next segment has started, its move is added
        if not following.start < segment.end:
            return here, here_dot
        p, p_dot = P.progress(following.profile)(t, following.start, following.end)
        lo, hi = segment_rows(design, following)
        _, rate = P.blend(design.dimension)(here, here_dot, p, p_dot, ca.DM(lo), ca.DM(hi))
        p_value = P.progress(following.profile, False)(t, following.start, following.end)
        value = P.blend(design.dimension, False)(here, p_value, ca.DM(lo), ca.DM(hi))
        started = following.start < t
        return ca.if_else(started, value, here), ca.if_else(started, rate, here_dot)

    segments = design.segments
    rho, rho_dot = on(segments[-1])
    for k in range(len(segments) - 2, -1, -1):
        here, here_dot = blended(segments[k], segments[k + 1], *on(segments[k]))
        sooner = t < segments[k].end
        rho, rho_dot = ca.if_else(sooner, here, rho), ca.if_else(sooner, here_dot, rho_dot)
    return rho, rho_dot


def reach_tube(design: TubeDesign, t) -> tuple:
    """``rho_L(t)``, ``rho_U(t)`` of eq. (4), SX vectors of length n."""
    n = design.dimension
    rho, _ = reach_tube_rates(design, t)
    return rho[:n], rho[n:]


def circumvent_rates(design: TubeDesign, t) -> tuple:
    """``beta`` and ``beta_dot`` (2n SX vectors ``[L; U]``) of eq. (9).

    Per bound with several circumvents: ``top = max(0, y_j)``, ``fnu_init``, ``fnu_add``
    over the circumvents in table order, ``fnu_finish``; with one: ``fnu_single``
    (``F = y``); a bound without circumvent is the state space's bound.
    """
    tables = design_tables(design)
    init, add, finish, single = P.fnu_pieces()
    nu = design.smoothness
    beta, beta_dot = [], []
    for b, (bound, sign) in enumerate(zip(tables.bounds, tables.signs)):
        members = tables.members(b)
        if not members:
            beta.append(ca.SX(bound))
            beta_dot.append(ca.SX(0.0))
            continue
        bumps = [(P.bump(False)(t, c.start, c.end, c.center, c.radius, c.sharpness, c.height),
                  P.bump()(t, c.start, c.end, c.center, c.radius, c.sharpness, c.height)[1])
                 for c in members]
        if len(members) == 1:
            value, value_dot = single(bound, sign, *bumps[0])
            beta.append(value)
            beta_dot.append(value_dot)
            continue
        top = ca.SX(0.0)
        for y, _ in bumps:
            top = ca.fmax(top, y)
        total, rate = init(top, nu)
        for y, y_dot in bumps:
            total, rate = add(total, rate, y, y_dot, top, nu)
        value, value_dot = finish(bound, sign, top, total, rate, nu)
        beta.append(value)
        beta_dot.append(value_dot)
    return ca.vertcat(*beta), ca.vertcat(*beta_dot)


def circumvent(design: TubeDesign, t) -> tuple:
    """Holistic circumvent ``beta_L(t)``, ``beta_U(t)`` of eq. (9), SX vectors of length n."""
    n = design.dimension
    beta, _ = circumvent_rates(design, t)
    return beta[:n], beta[n:]


def conflict_and_trigger(design: TubeDesign, t) -> tuple:
    """``psi`` (eq. (11), ``[beta_U - rho_L; rho_U - beta_L]``) and ``theta`` at ``t``.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    t : casadi.SX
        Time, s.

    Returns
    -------
    psi, theta : casadi.SX, shape (2n,)
        Conflict (state units) and trigger of eq. (11).
    """
    rho, _ = reach_tube_rates(design, t)
    beta, _ = circumvent_rates(design, t)
    return P.conflict(design.dimension)(rho, beta, design.theta0, design.mu)


def conflict_distance(design: TubeDesign, t):
    """``psi = [beta_U - rho_L, rho_U - beta_L]`` of eq. (11), SX vector of length 2n."""
    return conflict_and_trigger(design, t)[0]


def trigger(design: TubeDesign, psi):
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) (sign approximated by tanh)."""
    return P.trigger_expression(psi, design.theta0, design.mu)


def adaptive_law(design: TubeDesign, t, alpha):
    """``alpha_dot = theta / (psi + alpha)^2 - kappa alpha``, eq. (11), SX vector of length 2n."""
    psi, theta = conflict_and_trigger(design, t)
    return P.alpha_rate(design.dimension)(alpha, psi, theta, design.kappa)


def adaptive_tube(design: TubeDesign, t, alpha) -> tuple:
    """``gamma_L``, ``gamma_U`` of eq. (10), SX vectors of length n.

    Parameters
    ----------
    design : TubeDesign
        The tube (its numbers become constants of the graph).
    t : casadi.SX
        Time, s.
    alpha : casadi.SX, shape (2n,)
        ``[alpha_L; alpha_U]`` of eq. (11), state units.

    Returns
    -------
    gamma_l, gamma_u : casadi.SX, shape (n,)
        The adaptive tube, state units.
    """
    n = design.dimension
    rho, _ = reach_tube_rates(design, t)
    beta, _ = circumvent_rates(design, t)
    cand = P.candidates(n)[0](rho, alpha)
    smooth_max, smooth_min = P.smooth_pieces()[1], P.smooth_pieces()[3]
    nu = design.smoothness
    gamma_l = ca.vertcat(*[smooth_max(cand[i], beta[i], nu) for i in range(n)])
    gamma_u = ca.vertcat(*[smooth_min(cand[n + i], beta[n + i], nu) for i in range(n)])
    return gamma_l, gamma_u


def adaptive_tube_rates(design: TubeDesign, t, alpha) -> tuple:
    """Total time derivatives ``gamma_L_dot``, ``gamma_U_dot`` (alpha moving by (11))."""
    n = design.dimension
    rho, rho_dot = reach_tube_rates(design, t)
    beta, beta_dot = circumvent_rates(design, t)
    psi, theta = P.conflict(n)(rho, beta, design.theta0, design.mu)
    alpha_dot = P.alpha_rate(n)(alpha, psi, theta, design.kappa)
    cand_fn, rates_fn = P.candidates(n)
    cand, cand_dot = cand_fn(rho, alpha), rates_fn(rho_dot, alpha_dot)
    max_rate, min_rate = P.smooth_pieces()[4], P.smooth_pieces()[5]
    nu = design.smoothness
    rate_l = ca.vertcat(*[max_rate(cand[i], beta[i], cand_dot[i], beta_dot[i], nu)
                          for i in range(n)])
    rate_u = ca.vertcat(*[min_rate(cand[n + i], beta[n + i], cand_dot[n + i], beta_dot[n + i],
                                   nu) for i in range(n)])
    return rate_l, rate_u


def implicit_alpha_update(alpha, psi, theta, dt, kappa: float,
                          iterations: int = NEWTON_ITERATIONS):
    """Backward-Euler step of (11): solve ``a = alpha + dt (theta/(psi+a)^2 - kappa a)``.

    Component-wise (the Newton system is diagonal). The residual
    ``g(a) = (1 + kappa dt) a - alpha - dt theta / (psi + a)^2`` is increasing and concave
    on ``(-psi, inf)``, so Newton's method started at a point where ``g <= 0`` increases
    monotonically to the unique root without leaving the domain. The start is
    ``alpha / c`` when it is far enough from the pole, else the root start; then
    ``iterations`` Newton iterations with one division each
    (:func:`stt_codegen.tube.pieces.newton_pieces`). The generated code runs the same
    pieces (the root start only when needed, the iterations in a loop that stops at a
    fixed point), so it computes exactly this in double precision; single precision may
    stop after the first iteration when a proven bound puts the root within one unit
    roundoff of it (:data:`stt_codegen.codegen.tolerance.NEWTON_STOP_SINGLE`).

    Parameters
    ----------
    alpha, psi, theta : casadi.SX, shape (m, 1)
        Current ``alpha``; ``psi`` and ``theta`` at the end of the step.
    dt : casadi.SX scalar
        Step, seconds, positive.
    kappa : float
        ``kappa`` of eq. (11), 1/s.
    iterations : int
        Newton iterations after the start.

    Returns
    -------
    casadi.SX, shape (m, 1)
        ``alpha`` after the step, state units.
    """
    a0, c, a_coef, root = P.newton_start_expression(alpha, psi, theta, dt, kappa)
    a = ca.if_else(root, P.newton_root_start_expression(alpha, psi, c, a_coef), a0)
    for _ in range(iterations):
        a = P.newton_iteration_expression(a, alpha, psi, c, a_coef)
    return a


def controller_law(design: TubeDesign, x, gamma_l, gamma_u) -> tuple:
    """Deployed law (13) with clamps: returns ``(u, inside)`` (see
    :mod:`stt_codegen.tube.parameters`).

    Parameters
    ----------
    design : TubeDesign
        The tube (its gain ``k``).
    x : casadi.SX, shape (n,)
        State, state units.
    gamma_l, gamma_u : casadi.SX, shape (n,)
        The adaptive tube of eq. (10), state units.

    Returns
    -------
    u : casadi.SX, shape (n,)
        The input of law (13).
    inside : casadi.SX
        1 when ``gamma_L < x < gamma_U`` entry by entry, else 0.
    """
    return P.law_expression(x, gamma_l, gamma_u, design.gain, design.dimension)


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
    """Build the CasADi SX functions of a design (the table in docs/codegen.md).

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

    rho, rho_dot = reach_tube_rates(design, t)
    fns["reach_tube"] = ca.Function(
        "reach_tube", [t], [rho[:n], rho[n:], rho_dot[:n], rho_dot[n:]],
        ["t"], ["rho_L", "rho_U", "rho_L_dot", "rho_U_dot"])

    beta, beta_dot = circumvent_rates(design, t)
    fns["circumvent"] = ca.Function(
        "circumvent", [t], [beta[:n], beta[n:], beta_dot[:n], beta_dot[n:]],
        ["t"], ["beta_L", "beta_U", "beta_L_dot", "beta_U_dot"])

    alpha_dot = adaptive_law(design, t, alpha)
    gamma_l, gamma_u = adaptive_tube(design, t, alpha)
    rate_l, rate_u = adaptive_tube_rates(design, t, alpha)
    fns["tube"] = ca.Function(
        "tube", [t, alpha], [gamma_l, gamma_u, rate_l, rate_u],
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

    psi_next, theta_next = conflict_and_trigger(design, P.later()(t, dt))
    alpha_next = implicit_alpha_update(alpha, psi_next, theta_next, dt, design.kappa)
    fns["alpha_step"] = ca.Function("alpha_step", [t, dt, alpha], [alpha_next],
                                    ["t", "dt", "alpha"], ["alpha_next"])

    u, inside = controller_law(design, x, gamma_l, gamma_u)
    if design.input_bound is None:
        fns["controller_step"] = ca.Function(
            "controller_step", [x, t, dt, alpha], [u, alpha_next, inside],
            ["x", "t", "dt", "alpha"], ["u", "alpha_next", "inside"])
    else:
        # the actuator clamp after law (13): a fourth output, within_bound (1.0 when no
        # entry of u was clamped)
        u, within = P.saturate_expression(u, ca.DM(design.input_bound), n)
        fns["controller_step"] = ca.Function(
            "controller_step", [x, t, dt, alpha], [u, alpha_next, inside, within],
            ["x", "t", "dt", "alpha"], ["u", "alpha_next", "inside", "within_bound"])
    return TubeModel(design, {name: fns[name] for name in FUNCTION_NAMES})


def alpha_trajectory_function(design: TubeDesign, steps: int) -> ca.Function:
    """``alpha`` along a grid of ``steps`` implicit steps, given ``psi`` on the grid.

    Used by the design search to integrate (11) exactly as the deployed controller does.

    Parameters
    ----------
    design : TubeDesign
        The tube (``theta0``, ``mu``, ``kappa``).
    steps : int
        Number of steps of the grid.

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
