"""SymPy proofs of the cascade's second stage on the deployed expressions
(docs/second-order.md, "The argument").

The pieces :func:`stt_codegen.tube.cascade.velocity_transform`,
:func:`~stt_codegen.tube.cascade.velocity_law` and
:func:`~stt_codegen.tube.cascade.velocity_tube` are printed by the emitter's SymPy printer
(the instruction stream the C and Python printers print) and reduced to the branch that
holds where the clamps are inactive (``rho2 >= GAMMA_D_MIN``, ``|e2| <= E_MAX``) by
:func:`stt_codegen.proofs.deployed.on_domain`. On them:

* ``cascade.transform.n<n>``: ``e2 = (x2 - r)/rho2``, ``epsilon2 = ln((1+e2)/(1-e2))``,
  ``xi2 = 2/(rho2 (1 - e2^2))`` and ``u = -k2 xi2 epsilon2``;
* ``cascade.jacobian.n<n>``: ``d epsilon2/d x2 = xi2`` (diagonal), ``d epsilon2/d r = -xi2``;
* ``cascade.lyapunov_derivative.n<n>``: ``d/dt (epsilon2^T epsilon2 / 2) = epsilon2^T xi2
  (x2_dot - r_dot - rho2_dot e2)`` with ``x2``, ``r``, ``rho2`` functions of time;
* ``cascade.pushes_back``: ``xi2 > 0`` and ``u z <= 0`` for ``|e2| < 1``;
* ``cascade.velocity_tube``: ``rho2(0) = width_start``, ``rho2 >= rho2_inf`` for ``t >= 0``,
  ``|rho2_dot| <= l (rho2(0) - rho2_inf)``.

``cascade.sampled`` and ``cascade.input_bound``, which need a design, are
:mod:`stt_codegen.verification.cascade`'s.
"""

from __future__ import annotations

import functools

import sympy as sp

from ..codegen.emit import sympy_expressions
from ..tube import cascade
from ..tube.parameters import E_MAX, GAMMA_D_MIN
from .check import Check
from .deployed import on_domain

__all__ = ["cascade_checks", "check_jacobian", "check_lyapunov_derivative",
           "check_pushes_back", "check_transform", "check_velocity_tube"]

_CLAMPS = {sp.Rational(GAMMA_D_MIN): 1, sp.Rational(E_MAX): -1, -sp.Rational(E_MAX): 1}


def _symbols(n: int):
    x2 = sp.Matrix(sp.symbols(f"x2_1:{n + 1}", real=True))
    r = sp.Matrix(sp.symbols(f"r1:{n + 1}", real=True))
    rho2 = sp.Matrix(sp.symbols(f"rho2_1:{n + 1}", positive=True))
    return x2, r, rho2


@functools.lru_cache(maxsize=None)
def deployed_transform(n: int) -> tuple:
    """``(e2, epsilon2, xi2, u, k2, x2, r, rho2)``: the deployed expressions (Matrices) on
    the domain where the clamps are inactive, and their symbols."""
    x2, r, rho2 = _symbols(n)
    values = {"x2": list(x2), "r": list(r), "rho2": list(rho2)}
    e, eps, xi = (sp.Matrix([on_domain(v, {}, _CLAMPS) for v in out])
                  for out in sympy_expressions(cascade.velocity_transform(n), values))
    k2 = sp.Symbol("k2", positive=True)
    u, _ = sympy_expressions(cascade.velocity_law(n), {**values, "gain": [k2]})
    u = sp.Matrix([on_domain(v, {}, _CLAMPS) for v in u])
    return e, eps, xi, u, k2, x2, r, rho2


def _zero(expr) -> bool:
    return sp.simplify(sp.together(expr)) == 0


def check_transform(n: int) -> Check:
    """The deployed ``e2``, ``epsilon2``, ``xi2``, ``u`` equal the formulas of
    docs/second-order.md.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).

    Returns
    -------
    Check
        ``cascade.transform.n<n>``.
    """
    e, eps, xi, u, k2, x2, r, rho2 = deployed_transform(n)
    ok = True
    for i in range(n):
        paper_e = (x2[i] - r[i]) / rho2[i]
        paper_eps = sp.log((1 + paper_e) / (1 - paper_e))
        paper_xi = 2 / (rho2[i] * (1 - paper_e**2))
        ok = ok and _zero(e[i] - paper_e) and _zero(xi[i] - paper_xi)
        ok = ok and _zero(sp.expand_log(eps[i] - paper_eps, force=True))
        ok = ok and _zero(u[i] + k2 * xi[i] * eps[i])
    return Check(f"cascade.transform.n{n}", bool(ok),
                 "deployed e2 = (x2 - r)/rho2, epsilon2 = ln((1+e2)/(1-e2)), xi2 = 2/(rho2 "
                 "(1 - e2^2)), u = -k2 xi2 epsilon2 where the clamps are inactive"
                 if ok else "the deployed second stage differs from its formulas", {"n": n})


def check_jacobian(n: int) -> Check:
    """``d epsilon2 / d x2 = diag(xi2)`` and ``d epsilon2 / d r = -diag(xi2)``.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).

    Returns
    -------
    Check
        ``cascade.jacobian.n<n>``.
    """
    _, eps, xi, _, _, x2, r, rho2 = deployed_transform(n)
    jx = (eps.jacobian(x2) - sp.diag(*xi)).applyfunc(lambda v: sp.simplify(sp.together(v)))
    jr = (eps.jacobian(r) + sp.diag(*xi)).applyfunc(lambda v: sp.simplify(sp.together(v)))
    ok = jx.is_zero_matrix and jr.is_zero_matrix
    return Check(f"cascade.jacobian.n{n}", bool(ok),
                 "d epsilon2/d x2 = xi2 and d epsilon2/d r = -xi2 (diagonal), symbolic x2, r, "
                 "rho2 > 0" if ok else f"differences {jx.tolist()}, {jr.tolist()}", {"n": n})


def check_lyapunov_derivative(n: int, tube_rate: bool = True) -> Check:
    """``V2_dot = epsilon2^T xi2 (x2_dot - r_dot - rho2_dot e2)`` with time-dependent
    ``x2``, ``r``, ``rho2``.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).
    tube_rate : bool, optional
        ``False`` drops the term ``rho2_dot e2`` from the claim (a wrong identity, which
        the check must refuse: the tests use it).

    Returns
    -------
    Check
        ``cascade.lyapunov_derivative.n<n>``: passed when the numerator of the difference,
        over a common denominator, expands to 0.
    """
    e, eps, xi, _, _, x2, r, rho2 = deployed_transform(n)
    t = sp.Symbol("t", real=True)
    fx = [sp.Function(f"X{i + 1}", real=True)(t) for i in range(n)]
    fr = [sp.Function(f"R{i + 1}", real=True)(t) for i in range(n)]
    fp = [sp.Function(f"P{i + 1}", positive=True)(t) for i in range(n)]
    timed = {**dict(zip(x2, fx)), **dict(zip(r, fr)), **dict(zip(rho2, fp))}
    e_t, eps_t, xi_t = (m.xreplace(timed) for m in (e, eps, xi))
    v_dot = sp.diff((eps_t.T * eps_t)[0] / 2, t)
    claim = sum(eps_t[i] * xi_t[i] * (fx[i].diff(t) - fr[i].diff(t) - fp[i].diff(t) * e_t[i] * int(tube_rate))
                for i in range(n))
    # epsilon2, the rates and the functions of t become symbols (in that order, so that
    # each is found whole); the difference is then a rational function, zero exactly when
    # the numerator of its common-denominator form expands to 0.
    logs = {eps_t[i]: sp.Symbol(f"L{i + 1}") for i in range(n)}
    rates = {f.diff(t): sp.Symbol(f"d{f.func.__name__}", real=True) for f in fx + fr + fp}
    values = dict(zip(fx + fr + fp, list(x2) + list(r) + list(rho2)))
    diff = (v_dot - claim).xreplace(logs).xreplace(rates).xreplace(values)
    numerator, _ = sp.fraction(sp.together(diff))
    numerator = sp.expand(numerator)
    ok = numerator == 0
    diff = sp.factor(sp.cancel(diff)) if not ok else diff
    return Check(f"cascade.lyapunov_derivative.n{n}", bool(ok),
                 "d/dt (eps2^T eps2/2) = eps2^T xi2 (x2_dot - r_dot - rho2_dot e2) identically "
                 "(time-dependent x2, r, rho2 > 0)" if ok else f"difference {diff}", {"n": n})


def check_pushes_back() -> Check:
    """``xi2 > 0`` and ``u (x2 - r) <= 0`` for ``|e2| < 1`` (n = 1; the stage is entry-wise).

    With ``e2 = (w - 1)/(w + 1)``, ``w > 0`` (a bijection onto ``(-1, 1)``),
    ``epsilon2 = ln(w)`` and ``1 - e2^2 = 4 w / (w + 1)^2``, so ``xi2 > 0``; ``epsilon2``
    has the sign of ``w - 1``, which is the sign of ``e2``, so ``u z = -k2 xi2 epsilon2
    rho2 e2 <= 0``.

    Returns
    -------
    Check
        ``cascade.pushes_back``; ``data`` holds ``xi2`` and ``epsilon2`` in ``w``.
    """
    e, eps, xi, u, k2, x2, r, rho2 = deployed_transform(1)
    w = sp.Symbol("w", positive=True)
    on = {x2[0]: r[0] + rho2[0] * (w - 1) / (w + 1)}
    xi_w = sp.factor(sp.simplify(xi[0].xreplace(on)))
    eps_w = sp.simplify(sp.expand_log(eps[0].xreplace(on), force=True))
    e_w = sp.simplify(e[0].xreplace(on))
    xi_positive = bool(xi_w.is_positive)
    eps_is_log_w = _zero(eps_w - sp.log(w))
    e_sign = _zero(e_w - (w - 1) / (w + 1))
    u_is = _zero(u[0].xreplace(on) + k2 * xi_w * eps_w)
    ok = xi_positive and eps_is_log_w and e_sign and u_is
    return Check("cascade.pushes_back", ok,
                 f"on |e2| < 1 (e2 = (w-1)/(w+1), w > 0): xi2 = {xi_w} > 0, epsilon2 = log(w) "
                 "has the sign of e2, so u (x2 - r) = -k2 xi2 epsilon2 rho2 e2 <= 0"
                 if ok else f"not shown: xi2 = {xi_w}, epsilon2 = {eps_w}, e2 = {e_w}",
                 {"xi2": str(xi_w), "epsilon2": str(eps_w)})


def check_velocity_tube() -> Check:
    """``rho2(0) = width_start``, ``rho2(t) >= width_floor`` and ``|rho2_dot| <= l
    (width_start - width_floor)`` for ``t >= 0``, on the deployed expression (the exponent
    clamp at -80 inactive: ``l t <= 80``; beyond, ``rho2`` is the floor plus
    ``(width_start - width_floor) e^-80``, also above the floor).

    Returns
    -------
    Check
        ``cascade.velocity_tube``; ``data`` holds the reduced ``rho2``.
    """
    t = sp.Symbol("t", nonnegative=True)
    floor, gap, decay = (sp.Symbol(s, positive=True) for s in ("rho2_inf", "g", "l"))
    (rho2,) = sympy_expressions(cascade.velocity_tube(1), {
        "t": [t], "width_start": [floor + gap], "width_floor": [floor], "decay": [decay]})
    s = sp.Symbol("s", nonnegative=True)       # s = l t <= 80: the clamp inactive
    expr = on_domain(rho2[0], {t: s / decay}, {-sp.Integer(80): 1})
    expr = sp.simplify(expr.xreplace({t: s / decay}))
    at_zero = sp.simplify(expr.xreplace({s: 0}) - (floor + gap)) == 0
    above = bool(sp.simplify(expr - floor).is_positive)
    rate = sp.simplify(sp.diff(expr, s) * decay)       # d rho2 / dt = l d rho2 / ds
    # exp(-s) = 1/(1 + v), v >= 0, is a bijection of s >= 0 onto (0, 1]
    v = sp.Symbol("v", nonnegative=True)
    rate_v = sp.factor(sp.simplify(rate.xreplace({sp.exp(-s): 1 / (1 + v)})))
    rate_bound = bool(sp.factor(decay * gap + rate_v).is_nonnegative) and bool(
        (-rate_v).is_nonnegative) and rate_v.has(v)
    ok = at_zero and above and rate_bound
    return Check("cascade.velocity_tube", ok,
                 f"rho2 = {expr} (s = l t): rho2(0) = width_start, rho2 > rho2_inf, "
                 "-l (rho2(0) - rho2_inf) <= rho2_dot <= 0" if ok
                 else f"not shown for rho2 = {expr}", {"rho2": str(expr)})


def cascade_checks(max_n: int = 2) -> list[Check]:
    """Every check of this module (``n = 1..max_n`` where the dimension matters).

    Parameters
    ----------
    max_n : int, optional
        Largest number of positions proved.

    Returns
    -------
    list of Check
        The transform, Jacobian and Lyapunov derivative for each ``n``, then
        ``cascade.pushes_back`` and ``cascade.velocity_tube`` (not ``cascade.sampled`` nor
        ``cascade.rate``, which need a design).
    """
    out = []
    for n in range(1, max_n + 1):
        out += [check_transform(n), check_jacobian(n), check_lyapunov_derivative(n)]
    return out + [check_pushes_back(), check_velocity_tube()]
