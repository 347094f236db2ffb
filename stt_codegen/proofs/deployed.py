"""The deployed expressions as SymPy, and their equality with the paper's statements.

``stt-codegen verify`` proves the paper's lemmas on the expressions the generated code
evaluates: each is obtained by printing a piece of :mod:`stt_codegen.tube.pieces` (the
CasADi Functions the C and Python printers print) with the SymPy printer
(:func:`stt_codegen.codegen.emit.sympy_expressions`), with the spec's numbers as SymPy
symbols (``t_c``, ``m``, ``r``, ``k``, ``nu``, ...). The printed expressions carry the
branches, clamps and overflow-safe forms of the code; :func:`on_domain` reduces one to the
branch a lemma is about, deciding every comparison, ``Abs``, ``Min`` and ``Max`` by the sign
of a difference on a parametrised domain (a proof for every point of it), and dropping only
the clamps it is told are inactive there (stated in the check's detail).

Where the deployed form is written differently from the paper's (``log1p``, shifted
exponentials, ``2/(1 + e^y)`` for ``1 - tanh``, clamps), :func:`deployed_checks` proves the
two equal on the stated domain; the paper's forms used as right-hand sides are in
:mod:`.statements`, labelled as such.
"""

from __future__ import annotations

import functools
from typing import Mapping

import sympy as sp

from ..codegen.emit import sympy_expressions
from ..tube import pieces
from ..tube.parameters import E_MAX, GAMMA_D_MIN
from . import statements
from .check import Check

__all__ = [
    "DomainUndecided",
    "exact",
    "on_domain",
    "reach_branch",
    "reach_after",
    "reach_rate",
    "bump_window",
    "bump_outside",
    "smooth_max_half",
    "smooth_min_half",
    "open_bump_sum",
    "trigger",
    "trigger_clamped",
    "alpha_rate",
    "error_transform",
    "law",
    "deployed_checks",
    "proved_pieces",
    "T", "T_C", "X0", "TARGET", "M", "R", "K", "NU",
]

# Symbols of the deployed expressions (shared with the lemma checks).
T = sp.Symbol("t", real=True)
T_C = sp.Symbol("t_c", positive=True)
X0 = sp.Symbol("X", real=True)
TARGET = sp.Symbol("T", real=True)
M = sp.Symbol("m", real=True)
R = sp.Symbol("r", positive=True)
K = sp.Symbol("k", positive=True)
NU = sp.Symbol("nu", positive=True)
_W = sp.Symbol("w", nonnegative=True)
_D = sp.Symbol("d", nonnegative=True)
_V = sp.Symbol("v", positive=True)

#: The exponent clamp of the pieces (:data:`stt_codegen.tube.pieces.EXP_ARGUMENT_BOUND`).
EXP_CLAMP = sp.Rational(pieces.EXP_ARGUMENT_BOUND)


class DomainUndecided(ValueError):
    """A comparison, ``Abs``, ``sign``, ``Min`` or ``Max`` the domain does not decide."""


def exact(expr: sp.Expr) -> sp.Expr:
    """``expr`` with every ``Float`` replaced by the exact rational of its double.

    Parameters
    ----------
    expr : sympy.Expr
        A printed expression.

    Returns
    -------
    sympy.Expr
        The same expression without floating-point numbers.
    """
    return expr.xreplace({f: sp.Rational(float(f)) for f in expr.atoms(sp.Float)})


def _sign(diff: sp.Expr, params: Mapping[sp.Symbol, sp.Expr]) -> str:
    d = sp.simplify(sp.sympify(diff).subs(params))
    if d.is_positive:
        return "+"
    if d.is_zero:
        return "0"
    if d.is_negative:
        return "-"
    if d.is_nonnegative:
        return "+0"
    if d.is_nonpositive:
        return "-0"
    raise DomainUndecided(f"the sign of {diff} is not decided on the domain {dict(params)}")


_RELATIONS = {
    sp.StrictLessThan: {"-": True, "+": False, "0": False, "+0": False},
    sp.LessThan: {"-": True, "0": True, "-0": True, "+": False},
    sp.StrictGreaterThan: {"+": True, "-": False, "0": False, "-0": False},
    sp.GreaterThan: {"+": True, "0": True, "+0": True, "-": False},
    sp.Equality: {"0": True, "+": False, "-": False},
    sp.Unequality: {"0": False, "+": True, "-": True},
}


def _decide(node: sp.Basic, params: Mapping[sp.Symbol, sp.Expr],
            inactive: Mapping[sp.Expr, int]):
    if isinstance(node, (sp.Min, sp.Max)):
        if len(node.args) != 2:
            raise DomainUndecided(f"{node}: only two-argument Min/Max are decided")
        a, b = node.args
        for c in inactive:
            if c in node.args:
                return b if a == c else a
        s = _sign(a - b, params)
        first = s in ("+", "0", "+0") if isinstance(node, sp.Max) else s in ("-", "0", "-0")
        return a if first else b
    if isinstance(node, sp.Abs):
        s = _sign(node.args[0], params)
        return node.args[0] if s in ("+", "0", "+0") else -node.args[0]
    if isinstance(node, sp.sign):
        s = _sign(node.args[0], params)
        if s not in ("+", "-", "0"):
            raise DomainUndecided(f"{node} is not decided on the domain {dict(params)}")
        return {"+": sp.Integer(1), "-": sp.Integer(-1), "0": sp.Integer(0)}[s]
    table = _RELATIONS[type(node)]
    # a clamp's own test (its derivative), possibly negated by SymPy's canonical form
    # (-x > -c is x < c): the other side is strictly inside
    sides = {**{-c: -side for c, side in inactive.items()}, **inactive}
    if node.rhs in sides or node.lhs in sides:
        inside = "+" if sides.get(node.rhs, -sides.get(node.lhs, 0)) > 0 else "-"
        return sp.true if table[inside] else sp.false
    s = _sign(node.lhs - node.rhs, params)
    if s not in table:
        raise DomainUndecided(f"{node} is not decided on the domain {dict(params)}")
    return sp.true if table[s] else sp.false


def on_domain(expr: sp.Expr, params: Mapping[sp.Symbol, sp.Expr] | None = None,
              inactive: Mapping[sp.Expr, int] | None = None) -> sp.Expr:
    """The branch of a printed expression that holds on a domain.

    Parameters
    ----------
    expr : sympy.Expr
        A printed piece output (``Piecewise``, comparisons, ``Abs``, ``Min``, ``Max``).
    params : mapping, optional
        The domain as a parametrisation of some symbols by others with sign assumptions
        (``{t: t_c w / (1 + w)}``, ``w >= 0``, is ``0 <= t < t_c``). Every comparison,
        ``Abs``, ``Min`` and ``Max`` is decided by the sign of a difference after this
        substitution, which SymPy must prove for all values of the parameters; the
        returned expression stays in the original symbols.
    inactive : mapping of sympy.Expr to int, optional
        Clamp constants ``c``, each with +1 for a lower clamp (the domain has ``x > c``)
        or -1 for an upper one (``x < c``): ``Min(c, x)`` and ``Max(c, x)`` become ``x``
        and a comparison of ``x`` with ``c`` (a clamp's derivative) is decided so; the
        domain is restricted to where the clamps do not act, which the caller states.

    Returns
    -------
    sympy.Expr
        Without ``Piecewise``, comparisons, ``Abs``, ``Min`` or ``Max``.

    Raises
    ------
    DomainUndecided
        Some branch is not decided on the domain.
    """
    params = dict(params or {})
    inactive = {sp.sympify(c): side for c, side in (inactive or {}).items()}
    expr = exact(expr)
    kinds = (sp.Min, sp.Max, sp.Abs, sp.sign, sp.Rel)
    for _ in range(50):
        nodes = [n for n in sp.postorder_traversal(expr) if isinstance(n, kinds)]
        if not nodes:
            break
        # innermost first: no undecided node below it
        node = next(n for n in nodes
                    if not any(isinstance(sub, kinds) for arg in n.args
                               for sub in sp.preorder_traversal(arg)))
        expr = expr.xreplace({node: _decide(node, params, inactive)})
    if expr.has(sp.Piecewise, sp.Min, sp.Max, sp.Abs, sp.sign) or any(
            isinstance(a, sp.Rel) for a in sp.preorder_traversal(expr)):
        raise DomainUndecided(f"branches left in {expr}")
    return expr


def _equal(a: sp.Expr, b: sp.Expr) -> bool:
    """``a == b`` proved by SymPy (``simplify``, else logarithms combined after scaling by
    ``nu > 0``, else in exponentials)."""
    diff = sp.simplify(a - b)
    if diff == 0:
        return True
    if sp.simplify(sp.logcombine(sp.expand(diff * NU), force=True)) == 0:
        return True
    return sp.simplify(sp.expand_log(sp.logcombine(diff, force=True), force=True)
                       .rewrite(sp.exp)) == 0


# ---------------------------------------------------------------------------
# the pieces, printed
# ---------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _reach_printed() -> tuple[sp.Expr, sp.Expr]:
    """``rho`` and ``rho_dot`` of a tanh segment from ``X`` at 0 to ``T`` at ``t_c``."""
    (p,), (p_dot,) = sympy_expressions(pieces.progress("tanh"),
                                       {"t": [T], "start": [0], "end": [T_C]})
    (rho, _), (rho_dot, _) = sympy_expressions(pieces.interpolate(1), {
        "p": [p], "p_dot": [p_dot], "from": [X0, X0], "to": [TARGET, TARGET]})
    return rho, rho_dot


@functools.lru_cache(maxsize=None)
def reach_branch() -> sp.Expr:
    """Deployed reach tube (4) on ``0 <= t < t_c`` (``t = t_c w/(1+w)``, ``w >= 0``).

    Returns
    -------
    sympy.Expr
        ``rho`` in :data:`T`, :data:`T_C`, :data:`X0` (the start bound) and :data:`TARGET`,
        state units.

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    rho, _ = _reach_printed()
    return on_domain(rho, {T: T_C * _W / (1 + _W)})


@functools.lru_cache(maxsize=None)
def reach_after() -> sp.Expr:
    """Deployed reach tube on ``t >= t_c`` (``t = t_c + w``).

    Returns
    -------
    sympy.Expr
        ``rho`` in :data:`T`, :data:`T_C`, :data:`X0` and :data:`TARGET` (the target bound).

    Raises
    ------
    DomainUndecided
        As :func:`reach_branch`.
    """
    rho, _ = _reach_printed()
    return on_domain(rho, {T: T_C + _W})


@functools.lru_cache(maxsize=None)
def reach_rate() -> sp.Expr:
    """Deployed ``rho_dot`` output on ``0 <= t < t_c``.

    Returns
    -------
    sympy.Expr
        ``rho_dot`` in :data:`T`, :data:`T_C`, :data:`X0` and :data:`TARGET`, state units
        per second.

    Raises
    ------
    DomainUndecided
        As :func:`reach_branch`.
    """
    _, rho_dot = _reach_printed()
    return on_domain(rho_dot, {T: T_C * _W / (1 + _W)})


@functools.lru_cache(maxsize=None)
def _bump_printed() -> tuple[sp.Expr, sp.Expr]:
    (y,), (y_dot,) = sympy_expressions(pieces.bump(), {
        "t": [T], "start": [M - R], "end": [M + R], "center": [M], "radius": [R],
        "sharpness": [K], "height": [1]})
    return y, y_dot


@functools.lru_cache(maxsize=None)
def bump_window(side: int = 1, rate: bool = False) -> sp.Expr:
    """Deployed bump (7)-(8) (height 1, window ``(m - r, m + r)``) on the half
    ``t = m + side r v/(1+v)``, ``v > 0``, of its window (``0 < side (t - m) < r``), where
    the exponent clamp at -80 is inactive; with ``rate`` its ``y_dot`` output.

    Parameters
    ----------
    side : {1, -1}, optional
        The half after (1) or before (-1) the centre ``m``.
    rate : bool, optional
        The time derivative ``y_dot`` instead of ``y``.

    Returns
    -------
    sympy.Expr
        In :data:`T`, :data:`M`, :data:`R` and :data:`K`.

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    y, y_dot = _bump_printed()
    return on_domain(y_dot if rate else y, {T: M + side * R * _V / (1 + _V)}, {-EXP_CLAMP: 1})


@functools.lru_cache(maxsize=None)
def bump_outside(side: int = 1) -> sp.Expr:
    """Deployed bump on ``t = m + side (r + w)``, outside its window.

    Parameters
    ----------
    side : {1, -1}, optional
        After (1) or before (-1) the window.

    Returns
    -------
    sympy.Expr
        The bump there (0 once reduced), in :data:`T`, :data:`M`, :data:`R`, :data:`K`.

    Raises
    ------
    DomainUndecided
        As :func:`bump_window`.
    """
    y, _ = _bump_printed()
    return on_domain(y, {T: M + side * (R + _W)})


_A, _B = sp.symbols("a_1 a_2", real=True)


@functools.lru_cache(maxsize=None)
def _smooth_printed(index: int) -> sp.Expr:
    """Printed value of ``pieces.smooth_pieces()[index]`` (1: ``max~``, 3: ``min~``)."""
    (value,) = sympy_expressions(pieces.smooth_pieces()[index], {"a": [_A], "b": [_B],
                                                                "nu": [NU]})
    return value[0]


@functools.lru_cache(maxsize=None)
def smooth_max_half(side: int = 1) -> sp.Expr:
    """Deployed ``max~(a_1, a_2)`` on ``a_1 = a_2 + side d``, ``d >= 0``, clamp inactive.

    Parameters
    ----------
    side : {1, -1}, optional
        ``a_1 >= a_2`` (1) or ``a_1 <= a_2`` (-1).

    Returns
    -------
    sympy.Expr
        In ``a_1``, ``a_2`` and :data:`NU`.

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    return on_domain(_smooth_printed(1), {_A: _B + side * _D}, {-EXP_CLAMP: 1})


@functools.lru_cache(maxsize=None)
def smooth_min_half(side: int = 1) -> sp.Expr:
    """Deployed ``min~(a_1, a_2)`` on ``a_1 = a_2 + side d``, ``d >= 0``, clamp inactive.

    Parameters
    ----------
    side : {1, -1}, optional
        ``a_1 >= a_2`` (1) or ``a_1 <= a_2`` (-1).

    Returns
    -------
    sympy.Expr
        In ``a_1``, ``a_2`` and :data:`NU`.

    Raises
    ------
    DomainUndecided
        As :func:`smooth_max_half`.
    """
    return on_domain(_smooth_printed(3), {_A: _B + side * _D}, {-EXP_CLAMP: 1})


@functools.lru_cache(maxsize=None)
def _open_bump_printed(arity: int) -> tuple:
    """Printed ``F_nu`` over ``arity`` bumps, before reduction: ``(F, F_dot, ys, y_dots,
    top)``."""
    init, add, finish, _ = pieces.fnu_pieces()
    ys = sp.symbols(f"y_1:{arity + 1}", nonnegative=True)
    y_dots = sp.symbols(f"ydot_1:{arity + 1}", real=True)
    top = sp.Symbol("M", nonnegative=True)
    (total,), (rate,) = sympy_expressions(init, {"top": [top], "nu": [NU]})
    for y, y_dot in zip(ys, y_dots):
        (total,), (rate,) = sympy_expressions(add, {
            "total": [total], "rate": [rate], "y": [y], "y_dot": [y_dot], "top": [top],
            "nu": [NU]})
    (f,), (f_dot,) = sympy_expressions(finish, {
        "bound": [0], "sign": [1], "top": [top], "total": [total], "rate": [rate],
        "nu": [NU]})
    return f, f_dot, ys, y_dots, top


@functools.lru_cache(maxsize=None)
def open_bump_sum(arity: int = 3) -> tuple:
    """Deployed ``F_nu`` of eq. (9) over ``arity`` bumps: ``(F, F_dot, ys, y_dots, top)``.

    ``fnu_init``, ``fnu_add`` (once per bump) and ``fnu_finish`` (``bound = 0``,
    ``sign = 1``) composed as the generated code composes them, ``top >= 0`` symbolic,
    exponent clamps inactive.

    Parameters
    ----------
    arity : int, optional
        Number of bumps.

    Returns
    -------
    tuple
        ``F`` and ``F_dot`` (sympy.Expr), the bump symbols ``ys`` and their rates ``y_dots``
        (tuples of ``arity`` symbols) and the symbol ``top``.

    Raises
    ------
    DomainUndecided
        A branch of the printed pieces is not decided on the domain.
    """
    f, f_dot, ys, y_dots, top = _open_bump_printed(arity)
    clamp = {-EXP_CLAMP: 1}
    return on_domain(f, {}, clamp), on_domain(f_dot, {}, clamp), ys, y_dots, top


_PSI, _MU, _THETA0 = (sp.Symbol("psi", real=True), sp.Symbol("mu", positive=True),
                      sp.Symbol("theta0", positive=True))


def trigger_clamped() -> tuple[sp.Expr, tuple[sp.Symbol, sp.Symbol, sp.Symbol]]:
    """Deployed trigger ``theta`` of eq. (11) with its clamps, in ``(psi, theta0, mu)``.

    Returns
    -------
    theta : sympy.Expr
        The printed trigger, floats made exact (:func:`exact`).
    symbols : tuple of sympy.Symbol
        ``(psi, theta0, mu)``.
    """
    (_, theta) = sympy_expressions(pieces.conflict(1), {
        "rho": [0, 0], "beta": [0, _PSI], "theta0": [_THETA0], "mu": [_MU]})
    return exact(theta[0]), (_PSI, _THETA0, _MU)


@functools.lru_cache(maxsize=None)
def trigger() -> sp.Expr:
    """Deployed trigger of eq. (11) where its exponent clamps ``[-80, 80]`` are inactive.

    Returns
    -------
    sympy.Expr
        ``theta`` in ``(psi, theta0, mu)`` (the symbols of :func:`trigger_clamped`).

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    theta, _ = trigger_clamped()
    return on_domain(theta, {}, {-EXP_CLAMP: 1, EXP_CLAMP: -1})


@functools.lru_cache(maxsize=None)
def alpha_rate() -> tuple[sp.Expr, tuple[sp.Symbol, ...]]:
    """Deployed ``alpha_dot`` of eq. (11) in ``(alpha, psi, theta, kappa)``.

    Returns
    -------
    rate : sympy.Expr
        ``alpha_dot``, floats made exact.
    symbols : tuple of sympy.Symbol
        ``(alpha, psi, theta, kappa)``.
    """
    a, p, th = sp.symbols("alpha psi theta", real=True)
    kappa = sp.Symbol("kappa", positive=True)
    (rate,) = sympy_expressions(pieces.alpha_rate(1), {
        "alpha": [a, 0], "psi": [p, 1], "theta": [th, 0], "kappa": [kappa]})
    return exact(rate[0]), (a, p, th, kappa)


#: Clamps of the error transform: ``gamma_d`` floored at GAMMA_D_MIN, ``e`` in
#: ``[-E_MAX, E_MAX]``.
_TRANSFORM_CLAMPS = {sp.Rational(GAMMA_D_MIN): 1, sp.Rational(E_MAX): -1,
                     -sp.Rational(E_MAX): 1}


def _transform_symbols(n: int):
    x = sp.Matrix(sp.symbols(f"x1:{n + 1}", real=True))
    gs = sp.Matrix(sp.symbols(f"gamma_s1:{n + 1}", real=True))
    gd = sp.Matrix(sp.symbols(f"gamma_d1:{n + 1}", positive=True))
    return x, gs, gd


@functools.lru_cache(maxsize=None)
def _transform_printed(n: int) -> tuple:
    """Printed ``(e, epsilon, xi)`` of :func:`stt_codegen.tube.pieces.error_transform`."""
    x, gs, gd = _transform_symbols(n)
    return sympy_expressions(pieces.error_transform(n), {
        "x": list(x), "gamma_L": list((gs - gd) / 2), "gamma_U": list((gs + gd) / 2)})


@functools.lru_cache(maxsize=None)
def error_transform(n: int) -> tuple:
    """Deployed ``(e, epsilon, xi)`` of section IV, each an ``n``-vector, and the symbols.

    Printed from :func:`stt_codegen.tube.pieces.error_transform` (the expressions law (13)
    is built from) with ``gamma_L = (gamma_s - gamma_d)/2``, ``gamma_U = (gamma_s +
    gamma_d)/2``, on the domain ``gamma_d >= GAMMA_D_MIN``, ``|e| <= E_MAX`` where the
    clamps are inactive. Returns ``(e, epsilon, xi, x, gamma_s, gamma_d)`` as Matrices.

    Parameters
    ----------
    n : int
        State dimension.

    Returns
    -------
    e, epsilon, xi : sympy.Matrix, shape (n, 1)
        Normalized error, transformed error and the diagonal of ``xi``.
    x, gamma_s, gamma_d : sympy.Matrix, shape (n, 1)
        Their symbols: the state, ``gamma_U + gamma_L`` and ``gamma_U - gamma_L``.

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    x, gs, gd = _transform_symbols(n)
    printed = _transform_printed(n)
    clamps = _TRANSFORM_CLAMPS
    e, eps, xi = (sp.Matrix([on_domain(v, {}, clamps)
                             for v in out]) for out in printed)
    return e, eps, xi, x, gs, gd


@functools.lru_cache(maxsize=None)
def _law_printed(n: int) -> tuple:
    """Printed ``u`` of :func:`stt_codegen.tube.pieces.law` and the gain symbol."""
    x, gs, gd = _transform_symbols(n)
    gain = sp.Symbol("g", positive=True)
    (u, _) = sympy_expressions(pieces.law(n), {
        "x": list(x), "gamma_L": list((gs - gd) / 2), "gamma_U": list((gs + gd) / 2),
        "gain": [gain]})
    return u, gain


@functools.lru_cache(maxsize=None)
def law(n: int) -> tuple:
    """Deployed ``u`` of law (13) on the same domain as :func:`error_transform`, and the
    gain symbol: ``(u, gain)``.

    Parameters
    ----------
    n : int
        State dimension.

    Returns
    -------
    u : sympy.Matrix, shape (n, 1)
        ``-k xi epsilon``, input units, in the symbols of :func:`error_transform`.
    gain : sympy.Symbol
        The gain ``k`` of law (13) (printed as ``g``, positive).

    Raises
    ------
    DomainUndecided
        A branch of the printed piece is not decided on the domain.
    """
    u, gain = _law_printed(n)
    clamps = _TRANSFORM_CLAMPS
    return sp.Matrix([on_domain(v, {}, clamps) for v in u]), gain


def proved_pieces(max_n: int = 3) -> dict[str, object]:
    """Every piece the design-independent proofs print, as CasADi Functions.

    The proofs of :func:`deployed_checks`, :func:`stt_codegen.proofs.lemma.lemma_checks`,
    :func:`stt_codegen.proofs.transform.error_transform_checks` (``n = 1..max_n``) and the
    symbolic parts of the rate bounds and the adaptive law see the deployed code only
    through these pieces, printed by :func:`stt_codegen.codegen.emit.sympy_expressions`.
    Their serialization is part of the key of the proof cache
    (:mod:`stt_codegen.proofs.design_independent`): a changed piece misses the cache
    (``tests/test_verify_proofs.py`` checks that every piece printed while proving is
    listed here).

    Parameters
    ----------
    max_n : int
        Largest dimension of the error transform proved.

    Returns
    -------
    dict of str to casadi.Function
        Name -> piece (``error_transform.n1`` .. ``error_transform.n<max_n>`` among them).
    """
    init, add, finish, _ = pieces.fnu_pieces()
    smooth = pieces.smooth_pieces()
    return {"progress_tanh": pieces.progress("tanh"), "interpolate": pieces.interpolate(1),
            "bump": pieces.bump(), "smooth_max": smooth[1], "smooth_min": smooth[3],
            "fnu_init": init, "fnu_add": add, "fnu_finish": finish,
            "conflict": pieces.conflict(1), "alpha_rate": pieces.alpha_rate(1),
            "law.n2": pieces.law(2),
            **{f"error_transform.n{n}": pieces.error_transform(n)
               for n in range(1, max_n + 1)}}


# ---------------------------------------------------------------------------
# equality of the deployed forms with the paper's statements
# ---------------------------------------------------------------------------


def _check(name: str, ok: bool, deployed: object, paper: object, domain: str) -> Check:
    verdict = "equals" if ok else "DIFFERS from"
    return Check(name, bool(ok), f"deployed {deployed} {verdict} the paper's {paper} "
                 f"on {domain}", {"deployed": str(deployed), "paper": str(paper),
                                  "domain": domain})


def check_reach() -> Check:
    """Deployed ``rho`` (``progress_tanh`` + ``interpolate``) equals eq. (4) on both branches,
    and its ``rho_dot`` output is ``d rho/dt``."""
    branch, after = reach_branch(), reach_after()
    paper = statements.reach_branch(T, T_C, X0, TARGET)
    ok = (_equal(branch, paper) and _equal(after, TARGET)
          and _equal(reach_rate(), sp.diff(branch, T)))
    return _check("deployed.reach", ok, branch, paper,
                  "0 <= t < t_c (and = T for t >= t_c; rho_dot output = d rho/dt)")


def check_bump() -> Check:
    """Deployed bump equals eqs. (7)-(8) in its window (both halves, where the exponent
    clamp at -80 is inactive), is 0 outside, and its ``y_dot`` output is ``dy/dt``."""
    paper = statements.bump(T, M, R, K)
    halves = [bump_window(s) for s in (1, -1)]
    rates = [bump_window(s, rate=True) for s in (1, -1)]
    ok = (all(_equal(h, paper) for h in halves)
          and all(_equal(r_, sp.diff(h, T)) for r_, h in zip(rates, halves))
          and all(bump_outside(s) == 0 for s in (1, -1)))
    return _check("deployed.bump", ok, halves[0], paper,
                  "0 < |t - m| < r where k (t-m)^2/(r^2-(t-m)^2) < 80 (0 outside the window, "
                  "y_dot output = dy/dt; where the clamp acts both are in [0, e^-80])")


def check_smooth_max() -> Check:
    """Deployed ``max~`` and ``min~`` equal the paper's smooth max/min on both orders of
    their arguments (where the exponent clamp is inactive)."""
    paper_max = statements.smax(NU, _A, _B)
    paper_min = statements.smin(NU, _A, _B)
    ok = all(_equal(smooth_max_half(s), paper_max) and _equal(smooth_min_half(s), paper_min)
             for s in (1, -1))
    return _check("deployed.smooth_max", ok, smooth_max_half(1), paper_max,
                  "a_1 >= a_2 and a_1 <= a_2 where nu |a_1 - a_2| <= 80 (min~ likewise)")


def check_open_bump_sum(arity: int = 3) -> Check:
    """Deployed ``F_nu`` (shifted by ``top``) equals eq. (9)'s ``F_nu`` for every ``top``,
    and its rate output is ``dF/dt``."""
    f, f_dot, ys, y_dots, _ = open_bump_sum(arity)
    paper = statements.open_bump_sum(NU, *ys)
    same = sp.simplify(sp.expand_log(sp.exp(NU * f) - sp.exp(NU * paper), force=True)) == 0
    rate = sum(sp.diff(paper, y) * yd for y, yd in zip(ys, y_dots))
    rate_ok = sp.simplify(sp.expand_log(f_dot - rate, force=True)) == 0
    if not rate_ok:
        rate_ok = sp.simplify((f_dot - rate).rewrite(sp.exp)) == 0
    return _check("deployed.open_bump_sum", same and rate_ok, f, paper,
                  f"every top M >= 0, y_j >= 0 ({arity} bumps) where nu (y_j - M) >= -80 "
                  "(rate output = dF/dt)")


def check_trigger() -> Check:
    """Deployed trigger ``2 theta0 / (1 + e^{2 (psi - mu)})`` equals
    ``theta0 (1 - tanh(psi - mu))`` of eq. (11) where its clamp is inactive."""
    paper = statements.trigger(_PSI, _THETA0, _MU)
    deployed = trigger()
    ok = sp.simplify((deployed - paper).rewrite(sp.exp)) == 0
    return _check("deployed.trigger", ok, deployed, paper, "|psi - mu| <= 40")


def check_alpha_rate() -> Check:
    """Deployed ``alpha_dot`` equals the right-hand side of eq. (11)."""
    rate, (a, p, th, kappa) = alpha_rate()
    paper = statements.alpha_rate(a, p, th, kappa)
    return _check("deployed.alpha_rate", _equal(rate, paper), rate, paper, "psi + alpha != 0")


def check_law(n: int = 2) -> Check:
    """Deployed law (13) is ``-g xi epsilon`` with the deployed ``epsilon``, ``xi``, which
    equal the paper's error transform (section IV), where the clamps are inactive."""
    e, eps, xi, x, gs, gd = error_transform(n)
    u, gain = law(n)
    paper_e, paper_eps, paper_xi = statements.error_transform(x, gs, gd)
    ok = all(_equal(a, b) for a, b in zip(list(e) + list(eps) + list(xi),
                                          list(paper_e) + list(paper_eps) + list(paper_xi)))
    ok = ok and all(_equal(u[i], -gain * xi[i] * eps[i]) for i in range(n))
    return _check(f"deployed.law.n{n}", ok, list(u), "u = -g xi epsilon, " + str(list(paper_eps)),
                  f"gamma_d >= {GAMMA_D_MIN:g} and |e| <= E_MAX = 1 - 2^-20 (n = {n})")


def deployed_checks() -> list[Check]:
    """Every equality of a deployed piece with the paper's statement (names ``deployed.*``).

    A piece whose branches the domain does not decide (a changed piece) gives a failed
    check naming the undecided branch, not an exception.

    Returns
    -------
    list of Check
        ``deployed.reach``, ``deployed.bump``, ``deployed.smooth_max``,
        ``deployed.open_bump_sum``, ``deployed.trigger``, ``deployed.alpha_rate`` and
        ``deployed.law.n2``.
    """
    out = []
    for name, check in (("deployed.reach", check_reach), ("deployed.bump", check_bump),
                        ("deployed.smooth_max", check_smooth_max),
                        ("deployed.open_bump_sum", check_open_bump_sum),
                        ("deployed.trigger", check_trigger),
                        ("deployed.alpha_rate", check_alpha_rate),
                        ("deployed.law.n2", lambda: check_law(2))):
        try:
            out.append(check())
        except DomainUndecided as exc:
            out.append(Check(name, False, f"the deployed piece is not reduced to the "
                                          f"paper's branch: {exc}", {}))
    return out
