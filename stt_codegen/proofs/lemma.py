"""Lemma 3.3 pieces: smoothness and explicit rate bounds of the tube functions.

Lemma 3.3 of the paper states that ``gamma_s``, ``gamma_d`` and their time
derivatives are continuous and (used in the proof of Theorem 4.1) bounded. The
paper defers the proof to other papers. Here the pieces it rests on are proved
with SymPy for symbolic parameters:

* the reachability tube (4) joins its constant branch at ``t = t_c`` with every
  derivative vanishing from the left (:func:`check_reach_continuity`,
  :func:`check_reach_flat_all_orders`);
* the circumvent bump (7)-(8) is flat to every order at the edges of its window
  (:func:`check_bump_flatness`, :func:`check_bump_flat_all_orders`);
* explicit suprema of ``|rho_dot|`` and ``|b_dot|`` (:func:`reach_rate_bound`,
  :func:`bump_rate_bound`);
* the smooth max/min of (9)-(10) is C-infinity, 1-Lipschitz in the max norm
  (partials in [0, 1] summing to 1) and biased by at most ``ln(m)/nu``
  (:func:`check_smooth_max`).

Together with the bound on ``alpha`` and ``alpha_dot`` of
:mod:`stt_codegen.proofs.adaptive`, these give Lemma 3.3 by the chain rule.

The expressions are the deployed ones (:mod:`.deployed`: the pieces of
:mod:`stt_codegen.tube.pieces` printed by the SymPy printer, reduced to the branch the
lemma is about): the reach tube and its rate output, the bump and its rate output, ``F_nu``.
The smooth max is proved on the paper's statement, which ``deployed.smooth_max`` proves
equal to the deployed ``max~`` and ``min~``.
"""

from __future__ import annotations

from typing import Sequence

import mpmath
import numpy as np
import sympy as sp

from . import deployed
from .check import Check
from .deployed import K, M, NU as _NU, R, T, T_C, TARGET, X0
from .statements import smax

__all__ = [
    "check_reach_continuity",
    "check_reach_flat_all_orders",
    "check_bump_flatness",
    "check_bump_flat_all_orders",
    "reach_rate_constant",
    "reach_rate_form",
    "reach_rate_bound",
    "bump_rate_form",
    "bump_rate_bound",
    "check_smooth_max",
    "check_open_bump_sum",
    "lemma_checks",
    "T",
    "T_C",
    "X0",
    "TARGET",
    "M",
    "R",
    "K",
]

# Symbols shared with callers that pass an altered expression: T, T_C, X0, TARGET, M, R,
# K (those of the deployed expressions, :mod:`.deployed`).
_W = sp.Symbol("w", positive=True)
_H = sp.Symbol("h", positive=True)


def _is_zero(expr: sp.Expr) -> bool:
    return sp.simplify(expr) == 0


# ---------------------------------------------------------------------------
# (a) reachability tube at t = t_c
# ---------------------------------------------------------------------------


def _left_limits_at_tc(branch: sp.Expr, orders: int) -> list[sp.Expr]:
    """``lim_{t -> t_c^-} d^j branch/dt^j`` for ``j = 0..orders``.

    With ``t = t_c w/(1+w)`` and ``S = tanh(w)``, ``d/dt`` acts as
    ``D = ((1+w)^2/t_c)(d/dw + (1 - S^2) d/dS)``. When the branch is a
    polynomial in ``S`` with coefficients rational in ``w`` (true for eq. (4)
    and its usual variants), so is every derivative; expanding around
    ``S = 1``, every term with a factor ``(1 - S)`` tends to 0 (``1 - tanh w
    <= 2 e^{-2w}`` beats any rational growth), so the limit is
    ``lim_{w -> oo} f(w, 1)``, a limit of a rational function. Otherwise SymPy's
    ``limit`` is used on the expression in ``w``.
    """
    s = sp.Symbol("S", real=True)
    f = sp.simplify(branch.subs(T, T_C * _W / (1 + _W)))
    fs = sp.together(f.subs(sp.tanh(_W), s))
    num, den = sp.fraction(fs)
    polynomial = (
        num.is_polynomial(s)
        and not den.has(s)
        and not any(isinstance(a, sp.Function) and a.has(_W)
                    for a in sp.preorder_traversal(fs))
    )
    out: list[sp.Expr] = []
    for j in range(orders + 1):
        if j > 0:
            if polynomial:
                fs = sp.together((1 + _W) ** 2 / T_C
                                 * (sp.diff(fs, _W) + (1 - s**2) * sp.diff(fs, s)))
            else:
                f = (1 + _W) ** 2 / T_C * sp.diff(f, _W)
        if polynomial:
            out.append(sp.simplify(sp.limit(sp.cancel(fs.subs(s, 1)), _W, sp.oo)))
        else:
            out.append(sp.simplify(sp.limit(f, _W, sp.oo)))
    return out


def check_reach_continuity(
    branch: sp.Expr | None = None,
    constant: sp.Expr | None = None,
    orders: int = 4,
) -> Check:
    """Left limits at ``t_c`` of the reachability tube (4) and its derivatives.

    Proves, for symbolic ``X`` (initial bound), ``T`` (target bound) and
    ``t_c > 0``, that ``lim_{t -> t_c^-} rho(t) = T`` (the constant branch) and
    ``lim_{t -> t_c^-} d^j rho / dt^j = 0`` for ``j = 1..orders`` (the
    derivatives of the constant branch). The limit is taken with the
    substitution ``w = t/(t_c - t)``, ``t = t_c w/(1+w)``, ``w -> +oo``.

    Parameters
    ----------
    branch : sympy expression, optional
        The ``t < t_c`` branch in the symbols :data:`T`, :data:`T_C`,
        :data:`X0`, :data:`TARGET`; default the deployed one
        (:func:`.deployed.reach_branch`, proved equal to eq. (4)).
    constant : sympy expression, optional
        The ``t >= t_c`` branch; default the deployed one (:func:`.deployed.reach_after`).
    orders : int
        Highest derivative order checked.

    Returns
    -------
    Check
        ``data["limits"]`` lists the left limit of each order (as strings).
    """
    if branch is None:
        branch = deployed.reach_branch()
    if constant is None:
        constant = deployed.reach_after()
    limits: list[str] = []
    for j, lim in enumerate(_left_limits_at_tc(branch, orders)):
        limits.append(str(lim))
        expected = constant if j == 0 else sp.diff(constant, T, j)
        if not _is_zero(lim - expected):
            return Check(
                "lemma3.3.reach.continuity",
                False,
                f"order {j}: lim t->t_c^- of d^{j}rho/dt^{j} of the branch {branch} is "
                f"{lim}, but the t >= t_c branch gives {expected}: rho is not "
                f"C^{j} at t_c",
                {"failed_order": j, "limit": str(lim), "expected": str(expected),
                 "limits": limits},
            )
    return Check(
        "lemma3.3.reach.continuity",
        True,
        f"lim t->t_c^- rho = {constant} and lim d^j rho/dt^j = 0 for j = 1..{orders} "
        f"(deployed progress_tanh + interpolate; symbolic X, T, t_c > 0; substitution "
        "w = t/(t_c - t) -> oo)",
        {"limits": limits, "orders": orders},
    )


def check_reach_flat_all_orders(orders: int = 4) -> Check:
    """Every derivative of ``tanh(t/(t_c - t))`` tends to 0 as ``t -> t_c^-``.

    Argument (checked symbolically). With ``w = t/(t_c - t)`` and
    ``S = tanh(w)``, ``d/dt = ((1+w)^2/t_c) d/dw`` and ``dS/dw = 1 - S^2``, so
    on polynomials in ``(w, S)`` the time derivative acts as
    ``D = ((1+w)^2/t_c) (d/dw + (1 - S^2) d/dS)``. Induction hypothesis:
    ``d^j tanh(w)/dt^j = (1 - S^2) P_j(w, S)`` with ``P_j`` a polynomial.
    Base: ``D S = (1 - S^2)(1+w)^2/t_c``. Step: ``D[(1-S^2) P] / (1-S^2)`` is
    checked to be a polynomial expression in ``P`` and its partials for an
    arbitrary function ``P``. Then ``|d^j tanh/dt^j| <= 4 e^{-2w} |P_j(w, S)|``
    with ``|S| <= 1``, which tends to 0 because ``lim w^N e^{-2w} = 0`` for every
    ``N`` (also checked). ``P_1..P_orders`` are computed explicitly.

    Parameters
    ----------
    orders : int, optional
        Number of polynomials ``P_1..P_orders`` computed explicitly.

    Returns
    -------
    Check
        ``lemma3.3.reach.flat_all_orders``; ``data`` lists the ``P_j``.
    """
    w, s = sp.symbols("w S", real=True)
    n_sym = sp.Symbol("N", integer=True, positive=True)

    def d(f: sp.Expr) -> sp.Expr:
        return (1 + w) ** 2 / T_C * (sp.diff(f, w) + (1 - s**2) * sp.diff(f, s))

    p = sp.Function("P")(w, s)
    step = sp.cancel(sp.expand(d((1 - s**2) * p)) / (1 - s**2))
    _, den = sp.fraction(sp.together(step))
    step_ok = not den.has(w) and not den.has(s)
    polys: list[str] = []
    f = s
    ok = step_ok
    for _ in range(orders):
        f = sp.expand(d(f))
        q, rem = sp.div(sp.Poly(f * T_C**orders, w, s), sp.Poly(1 - s**2, w, s))
        if not rem.is_zero:
            ok = False
        polys.append(str(sp.factor(q.as_expr() / T_C**orders)))
    tail = sp.limit(w**n_sym * sp.exp(-2 * w), w, sp.oo)
    ok = ok and tail == 0
    return Check(
        "lemma3.3.reach.flat_all_orders",
        ok,
        "d^j/dt^j tanh(t/(t_c-t)) = sech^2(w) P_j(w, tanh w) with P_j polynomial "
        f"(induction step {'verified' if step_ok else 'FAILED'}; P_1..P_{orders} "
        "explicit); |.| <= 4 e^{-2w} |P_j| -> 0 as w -> oo (lim w^N e^{-2w} = "
        f"{tail}), so rho is C-infinity at t_c with all derivatives 0",
        {"induction_step": str(step), "P": polys, "tail_limit": str(tail)},
    )


# ---------------------------------------------------------------------------
# (b) circumvent bump at its window edges
# ---------------------------------------------------------------------------


def check_bump_flatness(expr: sp.Expr | None = None, orders: int = 4) -> Check:
    """One-sided limits of the bump (7)-(8) and its derivatives at ``m -+ r``.

    Proves, for symbolic ``m``, ``r > 0``, ``k > 0``, that the bump and its
    first ``orders`` time derivatives tend to 0 (the value of the zero branch
    outside the window) as ``t -> m - r`` from the right and ``t -> m + r``
    from the left.

    Parameters
    ----------
    expr : sympy expression, optional
        The in-window branch in :data:`T`, :data:`M`, :data:`R`, :data:`K`, used at both
        edges; default the deployed bump (:func:`.deployed.bump_window`, height 1) on
        each half of its window (where its exponent clamp at -80 is inactive).
    orders : int
        Highest derivative order checked.

    Returns
    -------
    Check
        ``lemma3.3.bump.flatness``; ``data["limits"]`` lists the two one-sided limits of
        each order; on FAIL, the order and edge where a limit is not 0.
    """
    f_left = deployed.bump_window(-1) if expr is None else expr
    f_right = deployed.bump_window(1) if expr is None else expr
    expr = f_right
    limits: list[tuple[str, str]] = []
    for j in range(orders + 1):
        if j > 0:
            f_left, f_right = sp.diff(f_left, T), sp.diff(f_right, T)
        left = sp.simplify(sp.limit(f_left.subs(T, M - R + _H), _H, 0, "+"))
        right = sp.simplify(sp.limit(f_right.subs(T, M + R - _H), _H, 0, "+"))
        limits.append([str(left), str(right)])
        for edge, lim in (("m - r (from inside)", left), ("m + r (from inside)", right)):
            if not _is_zero(lim):
                return Check(
                    "lemma3.3.bump.flatness",
                    False,
                    f"order {j}: d^{j}b/dt^{j} of {expr} tends to {lim} at t -> {edge}, "
                    f"but the bump is 0 outside its window: not C^{j} there",
                    {"failed_order": j, "edge": edge, "limit": str(lim),
                     "limits": limits},
                )
    return Check(
        "lemma3.3.bump.flatness",
        True,
        f"b and d^j b/dt^j (j = 1..{orders}) -> 0 at both window edges m -+ r from "
        "inside (the deployed bump on each half of its window; symbolic m, r > 0, k > 0): "
        "the piecewise bump is C^"
        f"{orders} (C-infinity by the induction of check_bump_flat_all_orders)",
        {"limits": limits, "orders": orders},
    )


def check_bump_flat_all_orders(orders: int = 4) -> Check:
    """Every derivative of the bump tends to 0 at its window edges.

    Argument (checked symbolically). With ``s = t - m`` and
    ``u = 1/(r^2 - s^2)`` (``u -> +oo`` at the edges),
    ``-k s^2/(r^2 - s^2) = k - k r^2 u`` so ``b = e^k e^{-k r^2 u}``, and
    ``du/ds = 2 s u^2``. Induction hypothesis:
    ``d^j b/dt^j = e^{-k r^2 u} Q_j(s, u)`` with ``Q_j`` a polynomial; the step
    ``d/ds[e^{-k r^2 u} Q] = e^{-k r^2 u} (Q_s + 2 s u^2 (Q_u - k r^2 Q))`` is
    verified for an arbitrary ``Q``. Since ``|s| <= r``,
    ``|Q_j(s, u)| <= C u^N`` for large ``u``, and ``u^N e^{-k r^2 u} -> 0``
    because ``k r^2 > 0`` (checked).

    Parameters
    ----------
    orders : int, optional
        Number of polynomials ``Q_1..Q_orders`` computed explicitly.

    Returns
    -------
    Check
        ``lemma3.3.bump.flat_all_orders``; ``data`` lists the ``Q_j``.
    """
    s, u = sp.symbols("s u", real=True)
    c = sp.Symbol("c", positive=True)  # c = k r^2
    n_sym = sp.Symbol("N", integer=True, positive=True)
    # identity -k s^2/(r^2 - s^2) = k - k r^2 u on u = 1/(r^2 - s^2)
    ident = sp.simplify(-K * s**2 / (R**2 - s**2) - (K - K * R**2 / (R**2 - s**2)))
    q = sp.Function("Q")(s, u)
    env = sp.exp(-K * R**2 * u)
    du_ds = 2 * s * u**2
    step = sp.simplify(
        (sp.diff(env * q, s) + sp.diff(env * q, u) * du_ds) / env
        - (sp.diff(q, s) + du_ds * (sp.diff(q, u) - K * R**2 * q))
    )
    polys: list[str] = []
    qj = sp.Integer(1)
    for _ in range(orders):
        qj = sp.expand(sp.diff(qj, s) + du_ds * (sp.diff(qj, u) - K * R**2 * qj))
        polys.append(str(sp.factor(qj)))
    tail = sp.limit(u**n_sym * sp.exp(-c * u), u, sp.oo)
    ok = ident == 0 and step == 0 and tail == 0
    return Check(
        "lemma3.3.bump.flat_all_orders",
        ok,
        "with u = 1/(r^2-(t-m)^2): b = e^k e^{-k r^2 u}, d^j b/dt^j = e^{-k r^2 u} "
        f"Q_j(t-m, u), Q_j polynomial (step {'verified' if step == 0 else 'FAILED'}); "
        f"u^N e^{{-k r^2 u}} -> {tail} as u -> oo, so every derivative vanishes at the "
        "window edges: the piecewise bump is C-infinity",
        {"Q": polys, "tail_limit": str(tail)},
    )


# ---------------------------------------------------------------------------
# (c) explicit rate bounds
# ---------------------------------------------------------------------------


def reach_rate_constant(digits: int = 30) -> tuple[float, float, float]:
    """Certified value of ``C = max_{w >= 0} sech^2(w) (1+w)^2``.

    ``d/dw [sech^2(w)(1+w)^2] = 2 sech^2(w) (1+w) (1 - (1+w) tanh w)``; the
    factor ``g(w) = (1+w) tanh(w) - 1`` is strictly increasing on ``w >= 0``
    with ``g(0) = -1``, ``g(1) > 0``: one stationary point ``w*``, a maximum,
    where ``tanh w* = 1/(1+w*)`` and so ``C = (1+w*)^2 - 1 = w*(2 + w*)``.
    ``w*`` is bracketed by interval arithmetic (mpmath ``iv``).

    Parameters
    ----------
    digits : int, optional
        Working precision of mpmath, decimal digits.

    Returns
    -------
    (w_star, C_lower, C_upper) : tuple of float
        ``C_upper`` is a rigorous upper bound (rounded up).

    Raises
    ------
    ArithmeticError
        The interval bracketing of ``w*`` failed.
    """
    iv = mpmath.iv

    def g_iv(x: mpmath.mpf) -> object:
        e2 = iv.exp(2 * iv.mpf(x))
        return (1 + iv.mpf(x)) * (e2 - 1) / (e2 + 1) - 1

    with mpmath.workdps(digits):
        w_star = mpmath.findroot(lambda w: (1 + w) * mpmath.tanh(w) - 1, 0.68)
        eps = mpmath.mpf(10) ** (-(digits - 10))
        lo, hi = w_star - eps, w_star + eps
        old = iv.dps
        iv.dps = digits
        try:
            if not (g_iv(lo).b < 0 < g_iv(hi).a):  # pragma: no cover - a bug
                raise ArithmeticError("bracketing of w* failed")
            c_lo = iv.mpf(lo) * (2 + iv.mpf(lo))
            c_hi = iv.mpf(hi) * (2 + iv.mpf(hi))
        finally:
            iv.dps = old
    return float(w_star), float(c_lo.a), float(np.nextafter(float(c_hi.b), np.inf))


def reach_rate_form() -> bool:
    """The symbolic part of :func:`reach_rate_bound`, for every ``X``, ``T``, ``t_c``.

    Proves that the deployed ``rho_dot`` output (:func:`.deployed.reach_rate`) is
    ``(T - X) sech^2(w) (1+w)^2 / t_c`` with ``w = t/(t_c - t)`` on ``0 <= t < t_c``, and
    the derivative of ``sech^2(w) (1+w)^2`` used by :func:`reach_rate_constant`.
    Independent of the design: :mod:`.proofs` caches it.

    Returns
    -------
    bool
        Whether both identities were proved.
    """
    deriv = deployed.reach_rate()   # the deployed rho_dot output, t < t_c
    claimed = (TARGET - X0) * sp.sech(_W) ** 2 * (1 + _W) ** 2 / T_C
    ident = sp.simplify((deriv.subs(T, T_C * _W / (1 + _W)) - claimed).rewrite(sp.exp))
    stat = sp.simplify(
        (sp.diff(sp.sech(_W) ** 2 * (1 + _W) ** 2, _W)
         - 2 * sp.sech(_W) ** 2 * (1 + _W) * (1 - (1 + _W) * sp.tanh(_W))).rewrite(sp.exp)
    )
    return bool(ident == 0 and stat == 0)


def reach_rate_bound(x0: float, target: float, t_c: float, form: bool | None = None) -> Check:
    """Explicit ``sup_t |rho_dot(t)|`` for one bound of the tube (4).

    ``rho_dot = (T - X) sech^2(w) (1+w)^2 / t_c`` with ``w = t/(t_c - t)``
    (verified symbolically on the deployed ``rho_dot`` output), 0 for ``t >= t_c``; so
    ``sup |rho_dot| = |T - X| C / t_c`` with ``C`` from
    :func:`reach_rate_constant`, attained at ``t* = t_c w*/(1+w*)``.

    Parameters
    ----------
    x0, target : float
        Initial-box bound and target-box bound of one dimension and side.
    t_c : float
        Prescribed time, > 0.
    form : bool, optional
        The result of :func:`reach_rate_form` when already known (the proof cache,
        :mod:`.proofs`); proved here when omitted.

    Returns
    -------
    Check
        ``lemma3.3.reach.rate_bound``; ``data["bound"]`` is the bound, state units per
        second; FAIL when ``t_c <= 0`` or the symbolic form is not proved.
    """
    if not t_c > 0:
        return Check("lemma3.3.reach.rate_bound", False, f"t_c = {t_c} is not > 0", {})
    proved = reach_rate_form() if form is None else form
    w_star, c_lo, c_hi = reach_rate_constant()
    bound = abs(target - x0) * c_hi / t_c
    t_star = t_c * w_star / (1 + w_star)
    # numeric cross-check on a dense grid
    tt = np.linspace(0.0, t_c, 200001)[:-1]
    ww = tt / (t_c - tt)
    with np.errstate(over="ignore"):
        sampled = float(np.max(np.abs(target - x0) / np.cosh(ww) ** 2 * (1 + ww) ** 2 / t_c))
    ok = proved and sampled <= bound * (1 + 1e-12)
    return Check(
        "lemma3.3.reach.rate_bound",
        ok,
        f"sup|rho_dot| = |T - X| C / t_c <= {bound:.12g} with C = w*(2+w*) in "
        f"[{c_lo:.15g}, {c_hi:.15g}], w* = {w_star:.12g} the root of (1+w) tanh w = 1, "
        f"attained at t* = {t_star:.12g}; dense-grid max {sampled:.12g}",
        {"bound": bound, "C_upper": c_hi, "w_star": w_star, "t_star": t_star,
         "sampled_max": sampled},
    )


def bump_rate_form() -> bool:
    """The symbolic part of :func:`bump_rate_bound`, for every ``m``, ``r > 0``, ``k > 0``.

    Proves that the deployed ``y_dot`` output on ``t > m`` (:func:`.deployed.bump_window`)
    is ``-(2k/r) z (1 - z^2)^-2 b`` with ``z = (t - m)/r``, that the stationarity
    condition of ``h`` is ``3 q^2 - 2(1 - k) q - 1 = 0`` in ``q = z^2``, and that ``q*``
    is its root. Independent of the design: :mod:`.proofs` caches it.

    Returns
    -------
    bool
        Whether the three identities were proved.
    """
    z = sp.Symbol("z", positive=True)
    q = sp.Symbol("q", positive=True)
    # the deployed bump and its deployed y_dot output on the half t > m of the window
    b_z = deployed.bump_window(1).subs(T, M + R * z)
    bdot = deployed.bump_window(1, rate=True).subs(T, M + R * z)
    form_ok = sp.simplify(bdot - (-2 * K / R) * z / (1 - z**2) ** 2 * b_z) == 0
    h = z / (1 - z**2) ** 2 * sp.exp(-K * z**2 / (1 - z**2))
    # z (1 - z^2)^2 d ln h/dz, a polynomial in z^2
    stat = sp.expand(sp.cancel(sp.diff(sp.log(h), z) * z * (1 - z**2) ** 2))
    poly_ok = sp.expand(stat + (3 * q**2 - 2 * (1 - K) * q - 1).subs(q, z**2)) == 0
    q_star = ((1 - K) + sp.sqrt((1 - K) ** 2 + 3)) / 3
    root_ok = sp.simplify((3 * q**2 - 2 * (1 - K) * q - 1).subs(q, q_star)) == 0
    return bool(form_ok and poly_ok and root_ok)


def bump_rate_bound(k: float, r: float, height: float = 1.0,
                    form: bool | None = None) -> Check:
    """Explicit ``sup_t |d/dt (B b(t))|`` for the circumvent bump (7)-(8).

    With ``z = (t - m)/r``: ``b_dot = -(2k/r) h(z) sign(z)``,
    ``h(z) = |z| (1 - z^2)^{-2} exp(-k z^2/(1 - z^2))``. The stationarity
    condition ``d ln h/dz = 0`` reduces (symbolically) to
    ``3 q^2 - 2(1 - k) q - 1 = 0`` in ``q = z^2``, whose roots have product
    ``-1/3``: exactly one positive root
    ``q* = ((1-k) + sqrt((1-k)^2 + 3))/3``, and ``q* < 1`` iff ``k > 0``.
    ``ln h -> -oo`` at ``z -> 0`` and ``z -> 1``, so ``q*`` is the maximiser
    and ``sup |B b_dot| = B (2k/r) h(sqrt(q*))``.

    Parameters
    ----------
    k : float
        Sharpness ``k^j`` > 0.
    r : float
        Half-width of the window > 0.
    height : float
        Bump height ``B^j`` (1 gives ``sup |b_dot|``).
    form : bool, optional
        The result of :func:`bump_rate_form` when already known (the proof cache,
        :mod:`.proofs`); proved here when omitted.

    Returns
    -------
    Check
        ``lemma3.3.bump.rate_bound``; ``data`` holds the bound (``height`` units per
        second, ``r`` in s), ``z_star``, ``q_star`` and the dense-grid maximum; FAIL when
        ``k`` or ``r`` is not positive or the symbolic form is not proved.
    """
    if not (k > 0 and r > 0):
        return Check("lemma3.3.bump.rate_bound", False,
                     f"need k > 0 and r > 0, got k = {k}, r = {r}", {})
    proved = bump_rate_form() if form is None else form
    with mpmath.workdps(30):
        kk = mpmath.mpf(k)
        qs = ((1 - kk) + mpmath.sqrt((1 - kk) ** 2 + 3)) / 3
        zs = mpmath.sqrt(qs)
        hval = zs / (1 - qs) ** 2 * mpmath.exp(-kk * qs / (1 - qs))
        sup = float(height * 2 * kk / r * hval)
    sup_up = float(np.nextafter(sup, np.inf))
    zz = np.linspace(-1.0, 1.0, 400001)[1:-1]
    with np.errstate(over="ignore", under="ignore"):
        sampled = float(np.max(height * 2 * k / r * np.abs(zz) / (1 - zz**2) ** 2
                               * np.exp(-k * zz**2 / (1 - zz**2))))
    ok = proved and 0 < qs < 1 and sampled <= sup_up * (1 + 1e-9)
    return Check(
        "lemma3.3.bump.rate_bound",
        ok,
        f"sup|B b_dot| = B (2k/r) h(z*) = {sup_up:.12g} at |t - m| = z* r, "
        f"z* = sqrt(q*) = {float(zs):.12g}, q* = ((1-k) + sqrt((1-k)^2+3))/3 the only "
        f"positive root of 3q^2 - 2(1-k)q - 1; dense-grid max {sampled:.12g}",
        {"bound": sup_up, "z_star": float(zs), "q_star": float(qs), "sampled_max": sampled},
    )


# ---------------------------------------------------------------------------
# (d) smooth max / min
# ---------------------------------------------------------------------------


def check_smooth_max(expr: sp.Expr | None = None, arity: int = 2) -> Check:
    """Smoothness, gradient and bias of the smooth max of eqs. (9)-(10).

    For ``smax(a_1..a_m) = (1/nu) ln(sum_j e^{nu a_j})`` (``nu > 0``) proves:
    the partials are the softmax weights ``e^{nu a_i}/sum_j e^{nu a_j}`` (in
    (0, 1)) and sum to 1; C-infinity (exp and log of a positive sum); for
    ``m = 2``, with ``a = b + d``, ``d >= 0`` (the form is symmetric), the bias
    ``smax - max = ln(1 + e^{-nu d})/nu`` is independent of ``b``, decreasing in
    ``d``, equals ``ln 2/nu`` at ``d = 0`` and tends to 0: ``0 <= smax - max
    <= ln(2)/nu`` (``ln(m)/nu`` for ``m`` arguments). The same holds for
    ``smin(a, b) = -smax(-a, -b)`` with ``-ln(2)/nu <= smin - min <= 0``. It
    also proves the overflow-free form ``max + log1p(e^{-nu |a-b|})/nu`` equal.

    Parameters
    ----------
    expr : sympy expression, optional
        Candidate smooth max in the symbols ``a_1..a_arity`` (real) and ``nu``
        (positive); default the form above.
    arity : int
        Number of arguments (>= 2) for the gradient checks.

    Returns
    -------
    Check
        ``lemma3.3.smooth_max``; ``data`` holds the expression and its bias.
    """
    args = sp.symbols(f"a_1:{arity + 1}", real=True)
    if expr is None:
        expr = smax(_NU, *args)
    failures: list[str] = []
    grads = [sp.diff(expr, a) for a in args]
    total = sp.simplify(sum(grads))
    if total != 1:
        failures.append(f"partials sum to {total}, not 1")
    denom = sum(sp.exp(_NU * a) for a in args)
    for a, g in zip(args, grads):
        if sp.simplify(g - sp.exp(_NU * a) / denom) != 0:
            failures.append(f"d/d{a} = {sp.simplify(g)} is not the softmax weight in (0, 1)")
            break
    equal = sp.simplify(expr.subs({a: args[0] for a in args}) - args[0]
                        - sp.log(arity) / _NU)
    if equal != 0:
        failures.append(f"at equal arguments smax - max = "
                        f"{sp.simplify(expr.subs({a: args[0] for a in args}) - args[0])}, "
                        f"not ln({arity})/nu")
    bias: sp.Expr = sp.log(arity) / _NU
    if arity == 2 and not failures:
        a1, a2 = args
        d = sp.Symbol("d", nonnegative=True)
        if sp.simplify(expr - expr.subs({a1: a2, a2: a1}, simultaneous=True)) != 0:
            failures.append("not symmetric in its arguments")
        bias = sp.simplify(sp.expand_log(expr.subs(a1, a2 + d) - (a2 + d), force=True))
        dbias = sp.simplify(sp.diff(bias, d))
        if bias.has(a2):
            failures.append(f"bias {bias} depends on the arguments' level")
        if sp.simplify(dbias + sp.exp(-_NU * d) / (1 + sp.exp(-_NU * d))) != 0:
            failures.append(f"d bias/d(a-b) = {dbias} not shown negative")
        lim = sp.limit(bias, d, sp.oo)
        if lim != 0:
            failures.append(f"bias tends to {lim}, not 0, as |a-b| -> oo")
        # the deployed max~ (max + log1p(exp(-nu|a-b|))/nu) on a_1 = a_2 + d
        stable = sp.simplify(sp.logcombine(
            expr.subs(a1, a2 + d) - deployed.smooth_max_half(1).subs(a1, a2 + d),
            force=True))
        if stable != 0:
            failures.append("the deployed overflow-free form max + log1p(exp(-nu|a-b|))/nu "
                            "differs")
    if failures:
        return Check("lemma3.3.smooth_max", False, "; ".join(failures),
                     {"expr": str(expr), "bias": str(bias)})
    return Check(
        "lemma3.3.smooth_max",
        True,
        f"partials = softmax weights in (0,1), sum 1 (m = {arity}); C-infinity; "
        + (f"bias smax - max = {bias} (a - b = d >= 0) decreasing from ln(2)/nu to 0: "
           "0 <= smax - max <= ln(2)/nu, -ln(2)/nu <= smin - min <= 0; equals "
           "the deployed max + log1p(exp(-nu|a-b|))/nu" if arity == 2 else
           f"smax - max = ln(sum_j e^(nu(a_j - max)))/nu in [0, ln({arity})/nu] "
           f"(the sum is in [1, {arity}]), ln({arity})/nu attained at equal arguments"),
        {"expr": str(expr), "bias": str(bias), "bias_max": "log(2)/nu"},
    )


def check_open_bump_sum(arity: int = 3) -> Check:
    """Properties of ``F_nu``, the combination of the bumps on one bound in eq. (9).

    ``F_nu(y) = (1/nu) ln(1 + sum_j (e^{nu y_j} - 1))`` (``docs/design.md``). Proves with
    SymPy: ``F = 0`` at ``y = 0``; a zero argument drops out (``F`` of ``m`` arguments
    with ``y_m = 0`` is ``F`` of the other ``m - 1``); with one argument ``F = y``; the
    partials are ``e^{nu (y_j - F)}`` (positive: ``F`` is non-decreasing and C-infinity,
    the log of a sum ``>= 1``); and the overflow-free form
    ``M + (1/nu) ln(e^{-nu M} + sum_j (e^{nu (y_j - M)} - e^{-nu M}))`` is equal. The
    bounds ``max(0, y) <= F <= max(0, y) + ln(m)/nu`` for ``y >= 0``: with
    ``S = sum_j e^{nu y_j} - (m - 1)`` one has ``e^{nu max} <= S <= m e^{nu max}``
    (each ``e^{nu y_j} >= 1``); checked numerically on a grid as well.

    Parameters
    ----------
    arity : int, optional
        Number of bumps ``y_j``.

    Returns
    -------
    Check
        ``design.open_bump_sum``.
    """
    ys = sp.symbols(f"y_1:{arity + 1}", nonnegative=True)
    big_m = sp.Symbol("M", nonnegative=True)

    def f(args):
        return sp.log(1 + sum(sp.exp(_NU * y) - 1 for y in args)) / _NU

    failures: list[str] = []
    full = f(ys)
    if sp.simplify(full.subs({y: 0 for y in ys})) != 0:
        failures.append("F(0) != 0")
    if sp.simplify(full.subs(ys[-1], 0) - f(ys[:-1])) != 0:
        failures.append("a zero argument does not drop out")
    if sp.simplify(f(ys[:1]) - ys[0]) != 0:
        failures.append("F(y) != y for one argument")
    for y in ys:
        if sp.simplify(sp.diff(full, y) - sp.exp(_NU * (y - full))) != 0:
            failures.append(f"dF/d{y} is not exp(nu ({y} - F))")
            break
    shifted, _, deployed_ys, _, top = deployed.open_bump_sum(arity)
    shifted = shifted.xreplace({top: big_m, **dict(zip(deployed_ys, ys))})
    if sp.simplify(sp.expand_log(sp.exp(_NU * shifted) - sp.exp(_NU * full), force=True)) != 0:
        failures.append("the deployed overflow-free form (fnu_init, fnu_add, fnu_finish) "
                        "differs")
    grid = np.linspace(0.0, 3.0, 7)
    worst = 0.0
    for nu in (0.5, 5.0, 50.0):
        for point in np.array(np.meshgrid(*[grid] * arity)).reshape(arity, -1).T:
            value = float(np.log(1.0 + np.sum(np.expm1(nu * point))) / nu)
            top = float(point.max())
            worst = max(worst, top - value, value - top - np.log(arity) / nu)
    if worst > 1e-12:
        failures.append(f"max(0, y) <= F <= max(0, y) + ln(m)/nu violated by {worst:.3g}")
    name = "design.open_bump_sum"
    if failures:
        return Check(name, False, "; ".join(failures), {})
    return Check(name, True, f"F_nu of eq. (9) ({arity} arguments): F(0) = 0, a closed window "
                 "(y_j = 0) drops out exactly, F = y for one argument, dF/dy_j = "
                 "exp(nu (y_j - F)) > 0 (non-decreasing, C-infinity), the deployed "
                 "overflow-free form (fnu_init, fnu_add, fnu_finish) is equal; max(0, y) <= F <= max(0, y) + ln(m)/nu (and on a grid)",
                 {"arity": arity})


# ---------------------------------------------------------------------------
# bundle
# ---------------------------------------------------------------------------


def lemma_checks(
    orders: int = 3,
    reach: Sequence[tuple[float, float, float]] = (),
    bumps: Sequence[tuple[float, float, float]] = (),
) -> list[Check]:
    """All Lemma 3.3 checks.

    Parameters
    ----------
    orders : int
        Highest derivative order for the explicit one-sided limits.
    reach : sequence of (x0, target, t_c)
        Tube bounds for which to report ``sup |rho_dot|``.
    bumps : sequence of (k, r, B)
        Circumvent bumps for which to report ``sup |B b_dot|``.

    Returns
    -------
    list of Check
        Continuity and flatness of the reach tube and the bump, the smooth max (2 and 3
        arguments), ``F_nu``, then one rate bound per entry of ``reach`` and ``bumps``.
    """
    out = [
        check_reach_continuity(orders=orders),
        check_reach_flat_all_orders(orders=orders),
        check_bump_flatness(orders=orders),
        check_bump_flat_all_orders(orders=orders),
        check_smooth_max(),
        check_smooth_max(arity=3),
        check_open_bump_sum(),
    ]
    out += [reach_rate_bound(*p) for p in reach]
    out += [bump_rate_bound(*p) for p in bumps]
    return out
