"""SymPy forms of the paper's formulas, exactly as the toolkit implements them.

Every builder returns a SymPy expression; the checks in the sibling modules
take these (or a deliberately altered version, to show that a check can fail).
"""

from __future__ import annotations

import sympy as sp

__all__ = [
    "reach_branch",
    "bump",
    "smax",
    "smin",
    "omnidirectional_g",
    "single_integrator_g",
]


def reach_branch(t: sp.Expr, t_c: sp.Expr, x0: sp.Expr, target: sp.Expr) -> sp.Expr:
    """Branch ``t < t_c`` of the reachability tube, eq. (4).

    ``(target - x0) * tanh(t / (t_c - t)) + x0``; for ``t >= t_c`` the tube is
    the constant ``target``. ``x0`` is a bound of the initial box (2),
    ``target`` the matching bound of the target box (3).
    """
    return (target - x0) * sp.tanh(t / (t_c - t)) + x0


def bump(t: sp.Expr, m: sp.Expr, r: sp.Expr, k: sp.Expr) -> sp.Expr:
    """Circumvent bump of eqs. (7)-(8) on its window ``|t - m| < r``.

    ``exp(-k (t-m)^2 / (r^2 - (t-m)^2))``; it is 0 outside the window.
    """
    return sp.exp(-k * (t - m) ** 2 / (r**2 - (t - m) ** 2))


def smax(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth maximum used in eqs. (9)-(10): ``(1/nu) ln(sum_j exp(nu a_j))``."""
    return sp.log(sp.Add(*[sp.exp(nu * a) for a in args])) / nu


def smin(nu: sp.Expr, *args: sp.Expr) -> sp.Expr:
    """Smooth minimum, ``-smax(-a_1, ..., -a_m)``."""
    return -smax(nu, *[-a for a in args])


def omnidirectional_g(x3: sp.Expr) -> sp.Matrix:
    """Input matrix ``g(x) = R(x3)`` of the omnidirectional robot, eq. (14)."""
    c, s = sp.cos(x3), sp.sin(x3)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def single_integrator_g(n: int) -> sp.Matrix:
    """Input matrix ``g = I_n`` of the single integrator ``x_dot = u + w``."""
    return sp.eye(n)
