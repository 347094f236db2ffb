"""Error transform of section IV and the Lyapunov derivative of Theorem 4.1.

``e_i = (2 x_i - gamma_s_i)/gamma_d_i``, ``epsilon_i = ln((1+e_i)/(1-e_i))``,
``xi = diag(4/(gamma_d_i (1 - e_i^2)))``. The paper writes
``xi = 4 gamma_d^{-1} (I - e e^T)^{-1}``; read as an outer product this is not
the Jacobian of ``epsilon`` for ``n >= 2`` (docs/decisions.md, decision 2).

``e``, ``epsilon`` and ``xi`` are the deployed ones: :func:`.deployed.error_transform`
prints :func:`stt_codegen.tube.pieces.error_transform` (the expressions law (13) is built
from) with the SymPy printer, where its clamps are inactive; ``deployed.law`` proves them
equal to the formulas above and the deployed ``u`` equal to ``-k xi epsilon``.
"""

from __future__ import annotations

from typing import Callable

import sympy as sp

from .check import Check
from .deployed import error_transform

__all__ = [
    "xi_diagonal",
    "xi_outer_product",
    "check_epsilon_jacobian",
    "outer_product_difference",
    "check_lyapunov_derivative",
    "error_transform_checks",
]

XiBuilder = Callable[[sp.Matrix, sp.Matrix], sp.Matrix]


def xi_diagonal(e: sp.Matrix, gamma_d: sp.Matrix) -> sp.Matrix:
    """``xi = diag(4/(gamma_d_i (1 - e_i^2)))`` (the toolkit's reading of (13)).

    Parameters
    ----------
    e : sympy.Matrix, shape (n, 1)
        The normalized error.
    gamma_d : sympy.Matrix, shape (n, 1)
        The tube widths ``gamma_{i,U} - gamma_{i,L}``, state units.

    Returns
    -------
    sympy.Matrix, shape (n, n)
        The diagonal ``xi``, which equals ``d epsilon / d x``.
    """
    return sp.diag(*[4 / (gamma_d[i] * (1 - e[i] ** 2)) for i in range(len(e))])


def xi_outer_product(e: sp.Matrix, gamma_d: sp.Matrix) -> sp.Matrix:
    """``xi = 4 gamma_d^{-1} (I - e e^T)^{-1}`` with ``e e^T`` the outer product.

    Parameters
    ----------
    e : sympy.Matrix, shape (n, 1)
        The normalized error.
    gamma_d : sympy.Matrix, shape (n, 1)
        The tube widths ``gamma_{i,U} - gamma_{i,L}``, state units.

    Returns
    -------
    sympy.Matrix, shape (n, n)
        The paper's literal ``xi`` of section IV (not ``d epsilon / d x`` for ``n >= 2``).
    """
    n = len(e)
    return 4 * sp.diag(*[1 / g for g in gamma_d]) * (sp.eye(n) - e * e.T).inv()


def _time_dependent(n: int, t: sp.Symbol) -> tuple:
    """The deployed ``(e, epsilon, xi)`` with ``x_i``, ``gamma_s_i``, ``gamma_d_i`` functions
    of ``t``, and those functions ``(x, gamma_s, gamma_d)``."""
    e, eps, xi_d, x_s, gs_s, gd_s = error_transform(n)
    x = sp.Matrix([sp.Function(f"x{i + 1}", real=True)(t) for i in range(n)])
    gs = sp.Matrix([sp.Function(f"gamma_s{i + 1}", real=True)(t) for i in range(n)])
    gd = sp.Matrix([sp.Function(f"gamma_d{i + 1}", positive=True)(t) for i in range(n)])
    to_time = {**dict(zip(x_s, x)), **dict(zip(gs_s, gs)), **dict(zip(gd_s, gd))}
    return e.xreplace(to_time), eps.xreplace(to_time), xi_d.xreplace(to_time), x, gs, gd


def check_epsilon_jacobian(n: int, xi: XiBuilder | None = None) -> Check:
    """Prove ``d epsilon/d x = xi(x, t)`` for dimension ``n``.

    The structural argument for every ``n``: ``epsilon_i`` depends on ``x``
    only through ``x_i``, so the Jacobian is diagonal, and its ``i``-th entry is
    the scalar derivative ``d/dx ln((1+e)/(1-e)) = (2/gamma_d) 2/(1-e^2)``. Here
    the full ``n x n`` Jacobian is computed with symbols ``x_i``,
    ``gamma_s_i`` (real), ``gamma_d_i > 0`` and compared entry by entry.

    Parameters
    ----------
    n : int
        State dimension (1, 2, 3 are cheap).
    xi : callable, optional
        ``xi(e, gamma_d) -> Matrix``; default the deployed ``xi`` (the diagonal reading,
        :func:`xi_diagonal`). Pass :func:`xi_outer_product` to see the paper's literal
        reading fail.

    Returns
    -------
    Check
        ``theorem4.1.epsilon_jacobian.n<n>``: passed when every entry of the difference
        simplifies to 0.
    """
    _, eps, xi_d, x, gs, gd = error_transform(n)
    es = sp.Matrix(sp.symbols(f"e1:{n + 1}", real=True))
    # evaluate in e-coordinates: x_i = (gamma_d_i e_i + gamma_s_i)/2 (a bijection)
    back = {x[i]: (gd[i] * es[i] + gs[i]) / 2 for i in range(n)}
    jac = eps.jacobian(x).subs(back)
    xi_m = sp.diag(*xi_d).subs(back) if xi is None else xi(es, gd)
    diff = (jac - xi_m).applyfunc(lambda v: sp.factor(sp.cancel(sp.together(v))))
    name = f"theorem4.1.epsilon_jacobian.n{n}"
    if diff.is_zero_matrix:
        return Check(name, True,
                     f"d epsilon/dx = xi exactly for n = {n} (the deployed epsilon and xi; "
                     "entrywise, symbolic x, gamma_s, gamma_d > 0); off-diagonal entries 0",
                     {"n": n})
    bad = [(i, j) for i in range(n) for j in range(n) if diff[i, j] != 0]
    i, j = bad[0]
    return Check(name, False,
                 f"d epsilon/dx - xi is not 0 for n = {n}: entry ({i + 1},{j + 1}) = "
                 f"{diff[i, j]} (e_i = (2 x_i - gamma_s_i)/gamma_d_i)",
                 {"n": n, "nonzero_entries": [(a + 1, b + 1) for a, b in bad],
                  "difference": str(diff)})


def outer_product_difference(n: int = 2) -> Check:
    """Explicit ``xi_outer - d epsilon/dx`` in terms of ``e`` (passes when nonzero).

    By Sherman-Morrison, ``(I - e e^T)^{-1} = I + e e^T/(1 - |e|^2)``, so the
    outer-product reading equals ``4 gamma_d^{-1} (I + e e^T/(1 - |e|^2))``;
    the check reports the symbolic difference to the Jacobian with ``e_i`` as
    independent symbols in ``(-1, 1)``. For ``n = 1`` they agree.

    Parameters
    ----------
    n : int, optional
        State dimension.

    Returns
    -------
    Check
        ``theorem4.1.outer_product_reading.n<n>``: passed when the readings differ exactly
        for ``n >= 2`` and the Sherman-Morrison form holds.
    """
    es = sp.Matrix(sp.symbols(f"e1:{n + 1}", real=True))
    gd = sp.Matrix(sp.symbols(f"gamma_d1:{n + 1}", positive=True))
    diff = (xi_outer_product(es, gd) - xi_diagonal(es, gd)).applyfunc(
        lambda v: sp.factor(sp.simplify(v)))
    sm = 4 * sp.diag(*[1 / g for g in gd]) * (sp.eye(n) + es * es.T / (1 - (es.T * es)[0]))
    sm_ok = (xi_outer_product(es, gd) - sm).applyfunc(sp.simplify).is_zero_matrix
    differs = not diff.is_zero_matrix
    expected = n >= 2
    return Check(
        f"theorem4.1.outer_product_reading.n{n}",
        differs == expected and sm_ok,
        (f"4 gamma_d^-1 (I - e e^T)^-1 - d epsilon/dx = {diff.tolist()} "
         f"(n = {n}; Sherman-Morrison form verified): the outer-product reading is "
         + ("NOT the Jacobian" if differs else "the Jacobian")),
        {"n": n, "difference": str(diff.tolist()), "differs": differs},
    )


def check_lyapunov_derivative(n: int, xi: XiBuilder | None = None) -> Check:
    """Prove ``V_dot = epsilon^T xi (x_dot - (gamma_s_dot + gamma_d_dot e)/2)``.

    ``V = epsilon^T epsilon/2`` with ``x_i(t)``, ``gamma_s_i(t)``,
    ``gamma_d_i(t)`` undefined functions of time (proof of Theorem 4.1,
    step 2; ``gamma_d_dot`` acts elementwise, being diagonal).

    Parameters
    ----------
    n : int
        State dimension.
    xi : callable, optional
        As in :func:`check_epsilon_jacobian`.

    Returns
    -------
    Check
        ``theorem4.1.lyapunov_derivative.n<n>``: passed when the difference simplifies to 0.
    """
    t = sp.Symbol("t", real=True)
    e, eps, xi_d, x, gs, gd = _time_dependent(n, t)
    xi_m = sp.diag(*xi_d) if xi is None else xi(e, gd)
    v = (eps.T * eps)[0] / 2
    vdot = sp.diff(v, t)
    rhs = (eps.T * xi_m * (x.diff(t) - (gs.diff(t) + sp.matrix_multiply_elementwise(
        gd.diff(t), e)) / 2))[0]
    # Freeze time: derivatives and functions -> symbols, logs -> symbols L_i, then
    # x_i -> (gamma_d_i e_i + gamma_s_i)/2. The difference is linear in the L_i.
    logs = sp.symbols(f"L1:{n + 1}", real=True)
    es = sp.symbols(f"e1:{n + 1}", real=True)
    frozen: dict[sp.Expr, sp.Expr] = {}
    for i in range(n):
        for name_, f in (("xdot", x[i]), ("gsdot", gs[i]), ("gddot", gd[i])):
            frozen[f.diff(t)] = sp.Symbol(f"{name_}{i + 1}", real=True)
    diff = (vdot - rhs).subs(frozen).subs({eps[i]: logs[i] for i in range(n)})
    plain = {x[i]: sp.Symbol(f"x{i + 1}", real=True) for i in range(n)}
    plain.update({gs[i]: sp.Symbol(f"gamma_s{i + 1}", real=True) for i in range(n)})
    plain.update({gd[i]: sp.Symbol(f"gamma_d{i + 1}", positive=True) for i in range(n)})
    diff = diff.subs(plain)
    diff = diff.subs({plain[x[i]]: (plain[gd[i]] * es[i] + plain[gs[i]]) / 2
                      for i in range(n)})
    diff = sp.expand(diff)
    coeffs = {str(l_): sp.factor(sp.cancel(sp.together(diff.coeff(l_)))) for l_ in logs}
    rest = sp.cancel(sp.together(diff - sum(diff.coeff(l_) * l_ for l_ in logs)))
    if all(c == 0 for c in coeffs.values()) and rest == 0 and not diff.has(sp.log):
        diff = sp.Integer(0)
    else:
        diff = sum(c * sp.Symbol(f"eps{k[1:]}") for k, c in coeffs.items()) + rest
    name = f"theorem4.1.lyapunov_derivative.n{n}"
    if diff == 0:
        return Check(name, True,
                     f"d/dt (eps^T eps/2) = eps^T xi (x_dot - (gamma_s_dot + gamma_d_dot e)/2) "
                     f"identically for n = {n} (the deployed e, epsilon, xi; time-dependent "
                     "x, gamma_s, gamma_d)",
                     {"n": n})
    return Check(name, False,
                 f"V_dot - eps^T xi (x_dot - (gamma_s_dot + gamma_d_dot e)/2) = {diff} "
                 f"for n = {n} (frozen time: xdot_i, gsdot_i, gddot_i the rates, eps_i "
                 "the transformed errors)", {"n": n, "difference": str(diff)})


def error_transform_checks(max_n: int = 3) -> list[Check]:
    """Jacobian (n = 1..max_n), outer-product difference (n = 2), V_dot (n = 1..max_n).

    Parameters
    ----------
    max_n : int, optional
        Largest state dimension proved.

    Returns
    -------
    list of Check
        In that order.
    """
    out = [check_epsilon_jacobian(n) for n in range(1, max_n + 1)]
    out.append(outer_product_difference(2))
    out += [check_lyapunov_derivative(n) for n in range(1, max_n + 1)]
    return out
