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
    """
    return (target - x0) * sp.tanh(t / (t_c - t)) + x0


def bump(t: sp.Expr, m: sp.Expr, r: sp.Expr, k: sp.Expr) -> sp.Expr:
    """Circumvent bump of eqs. (7)-(8) on its window ``|t - m| < r`` (paper's statement).

    ``exp(-k (t-m)^2 / (r^2 - (t-m)^2))``; it is 0 outside the window.
    """
    return sp.exp(-k * (t - m) ** 2 / (r**2 - (t - m) ** 2))


def smax(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth maximum of section II: ``(1/nu) ln(sum_j exp(nu a_j))`` (paper's statement)."""
    return sp.log(sp.Add(*[sp.exp(nu * a) for a in args])) / nu


def smin(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth minimum, ``-smax(-a_1, ..., -a_m)`` (paper's statement)."""
    return -smax(nu, *[-a for a in args])


def open_bump_sum(nu: sp.Expr, *ys: sp.Expr) -> sp.Expr:
    """``F_nu(y) = (1/nu) ln(1 + sum_j (exp(nu y_j) - 1))`` of eq. (9) (docs/design.md)."""
    return sp.log(1 + sum(sp.exp(nu * y) - 1 for y in ys)) / nu


def trigger(psi: sp.Expr, theta0: sp.Expr, mu: sp.Expr) -> sp.Expr:
    """``theta = theta0 (1 - tanh(psi - mu))`` of eq. (11) (``sign`` read as ``tanh``)."""
    return theta0 * (1 - sp.tanh(psi - mu))


def alpha_rate(alpha: sp.Expr, psi: sp.Expr, theta: sp.Expr, kappa: sp.Expr) -> sp.Expr:
    """Right-hand side of the adaptive law (11): ``theta / (psi + alpha)^2 - kappa alpha``."""
    return theta / (psi + alpha) ** 2 - kappa * alpha


def error_transform(x: sp.Matrix, gamma_s: sp.Matrix, gamma_d: sp.Matrix) -> tuple:
    """``(e, epsilon, xi)`` of section IV: ``e_i = (2 x_i - gamma_s_i)/gamma_d_i``,
    ``epsilon_i = ln((1+e_i)/(1-e_i))``, ``xi_i = 4/(gamma_d_i (1 - e_i^2))`` (the
    diagonal reading of ``xi`` in law (13); see :mod:`.transform`)."""
    e = sp.Matrix([(2 * x[i] - gamma_s[i]) / gamma_d[i] for i in range(len(x))])
    eps = sp.Matrix([sp.log((1 + ei) / (1 - ei)) for ei in e])
    xi = sp.Matrix([4 / (gamma_d[i] * (1 - e[i] ** 2)) for i in range(len(x))])
    return e, eps, xi
