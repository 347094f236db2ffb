"""The paper's formulas as it states them: right-hand sides of the equality checks only.

Nothing here is deployed and no lemma is proved on these expressions alone:
:mod:`.deployed` prints the deployed pieces (:mod:`stt_codegen.tube.pieces`) with the SymPy
printer and proves each equal to the statement below on a stated domain (checks
``deployed.*``); the lemma checks then run on the deployed expressions, or on these
statements only where the deployed one has been proved equal to it. Plant (14) is not
here: its one definition is :mod:`stt_codegen.runtime.dynamics`.
"""

from __future__ import annotations

import sympy as sp

__all__ = [
    "reach_branch",
    "bump",
    "smax",
    "smin",
    "open_bump_sum",
    "trigger",
    "alpha_rate",
    "error_transform",
]


def reach_branch(t: sp.Expr, t_c: sp.Expr, x0: sp.Expr, target: sp.Expr) -> sp.Expr:
    """Branch ``t < t_c`` of the reachability tube, eq. (4) (paper's statement).

    ``(target - x0) * tanh(t / (t_c - t)) + x0``; for ``t >= t_c`` the tube is
    the constant ``target``.

    Parameters
    ----------
    t : sympy.Expr
        Time, s.
    t_c : sympy.Expr
        Prescribed time, s.
    x0 : sympy.Expr
        The start set's bound in one dimension (``X0`` bound of eq. (4)), state units.
    target : sympy.Expr
        The target's bound in the same dimension, state units.

    Returns
    -------
    sympy.Expr
        ``rho_{i,L}`` or ``rho_{i,U}`` of eq. (4) for ``t < t_c``, state units.
    """
    return (target - x0) * sp.tanh(t / (t_c - t)) + x0


def bump(t: sp.Expr, m: sp.Expr, r: sp.Expr, k: sp.Expr) -> sp.Expr:
    """Circumvent bump of eqs. (7)-(8) on its window ``|t - m| < r`` (paper's statement).

    ``exp(-k (t-m)^2 / (r^2 - (t-m)^2))``; it is 0 outside the window.

    Parameters
    ----------
    t : sympy.Expr
        Time, s.
    m : sympy.Expr
        The window's centre ``m^j``, s.
    r : sympy.Expr
        The window's half-width ``r^j``, s.
    k : sympy.Expr
        The sharpness ``k^j`` (dimensionless).

    Returns
    -------
    sympy.Expr
        The bump, in ``(0, 1]`` on the window (multiplied by ``B^j`` in eqs. (7)-(8)).
    """
    return sp.exp(-k * (t - m) ** 2 / (r**2 - (t - m) ** 2))


def smax(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth maximum of section II: ``(1/nu) ln(sum_j exp(nu a_j))`` (paper's statement).

    Parameters
    ----------
    nu : sympy.Expr
        Sharpness ``nu > 0``.
    *args : sympy.Expr
        The values ``a_1, ..., a_m``.

    Returns
    -------
    sympy.Expr
        The smooth maximum ``max-bar`` of eq. (10).
    """
    return sp.log(sp.Add(*[sp.exp(nu * a) for a in args])) / nu


def smin(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth minimum, ``-smax(-a_1, ..., -a_m)`` (paper's statement).

    Parameters
    ----------
    nu : sympy.Expr
        Sharpness ``nu > 0``.
    *args : sympy.Expr
        The values ``a_1, ..., a_m``.

    Returns
    -------
    sympy.Expr
        The smooth minimum ``min-bar`` of eq. (10).
    """
    return -smax(nu, *[-a for a in args])


def open_bump_sum(nu: sp.Expr, *ys: sp.Expr) -> sp.Expr:
    """``F_nu(y) = (1/nu) ln(1 + sum_j (exp(nu y_j) - 1))`` of eq. (9) (docs/design.md).

    Parameters
    ----------
    nu : sympy.Expr
        Sharpness ``nu > 0``.
    *ys : sympy.Expr
        The bumps ``y_j`` (each >= 0, 0 outside its window).

    Returns
    -------
    sympy.Expr
        ``F_nu(y)``, 0 where every ``y_j`` is 0.
    """
    return sp.log(1 + sum(sp.exp(nu * y) - 1 for y in ys)) / nu


def trigger(psi: sp.Expr, theta0: sp.Expr, mu: sp.Expr) -> sp.Expr:
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) (``sign`` read as ``tanh``).

    Parameters
    ----------
    psi : sympy.Expr
        The conflict distance ``psi_i^lambda`` of eq. (11), state units.
    theta0 : sympy.Expr
        The trigger's gain ``theta_o > 0``.
    mu : sympy.Expr
        The conflict tolerance ``mu > 0``, state units.

    Returns
    -------
    sympy.Expr
        ``theta_i^lambda``, in ``(0, 2 theta0)``.
    """
    return theta0 * (1 - sp.tanh(psi - mu))


def alpha_rate(alpha: sp.Expr, psi: sp.Expr, theta: sp.Expr, kappa: sp.Expr) -> sp.Expr:
    """Right-hand side of the adaptive law (11): ``theta / (psi + alpha)^2 - kappa alpha``.

    Parameters
    ----------
    alpha : sympy.Expr
        The update function ``alpha_i^lambda``, state units.
    psi : sympy.Expr
        The conflict distance ``psi_i^lambda``, state units.
    theta : sympy.Expr
        The trigger ``theta_i^lambda`` (:func:`trigger`).
    kappa : sympy.Expr
        The decay rate ``kappa > 0``, 1/s.

    Returns
    -------
    sympy.Expr
        ``alpha_dot``, state units per second.
    """
    return theta / (psi + alpha) ** 2 - kappa * alpha


def error_transform(x: sp.Matrix, gamma_s: sp.Matrix, gamma_d: sp.Matrix) -> tuple:
    """``(e, epsilon, xi)`` of section IV: ``e_i = (2 x_i - gamma_s_i)/gamma_d_i``,
    ``epsilon_i = ln((1+e_i)/(1-e_i))``, ``xi_i = 4/(gamma_d_i (1 - e_i^2))`` (the
    diagonal reading of ``xi`` in law (13); see :mod:`.transform`).

    Parameters
    ----------
    x : sympy.Matrix, shape (n, 1)
        The state, state units.
    gamma_s : sympy.Matrix, shape (n, 1)
        ``gamma_{i,U} + gamma_{i,L}`` (eq. (10)), state units.
    gamma_d : sympy.Matrix, shape (n, 1)
        ``gamma_{i,U} - gamma_{i,L}`` (the diagonal of ``gamma_d``), state units.

    Returns
    -------
    e : sympy.Matrix, shape (n, 1)
        The normalized error.
    epsilon : sympy.Matrix, shape (n, 1)
        The transformed error.
    xi : sympy.Matrix, shape (n, 1)
        The diagonal of ``xi``, 1/state units.
    """
    e = sp.Matrix([(2 * x[i] - gamma_s[i]) / gamma_d[i] for i in range(len(x))])
    eps = sp.Matrix([sp.log((1 + ei) / (1 - ei)) for ei in e])
    xi = sp.Matrix([4 / (gamma_d[i] * (1 - e[i] ** 2)) for i in range(len(x))])
    return e, eps, xi
