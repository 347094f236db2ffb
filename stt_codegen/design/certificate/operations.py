"""The arithmetic the sampled certificates' per-interval formulas are written in: plain
floats, or CasADi ``SX`` symbols.

A formula such as :func:`~.sampled_axis.axis_interval` takes ``ops=`` and is written with
``ops.fmin``, ``ops.fmax``, ``ops.select`` (of two values), ``ops.branch`` (of two
functions, of which floats call one only), ``ops.sqrt``, ``ops.atanh``, ``ops.cosh``,
``ops.cos``, ``ops.sin`` (and ``+ - * /``, ``abs``, ``**``, which both kinds of number
have). With :data:`FLOATS` (the default) it is evaluated at once on Python floats; with
:data:`SYMBOLS` it builds the same expression tree on ``SX`` symbols, which
:mod:`.cascade_step` and :mod:`.sampled_fold` fold into a loop (:mod:`.folded`) that
CasADi's virtual machine evaluates (no C compiler). The tree is the formula's own sequence
of IEEE operations, in the same order: CasADi's on-the-fly simplifications (``x - x ->
0``, ``x * 1 -> x``, ...) are switched off while it is built (:func:`exact_symbols`), so the
folded loop computes the same doubles as the Python formula, except that a selected zero
is ``+0`` (docs/second-order.md, "How the certificate is evaluated").
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import casadi

__all__ = ["FLOATS", "SYMBOLS", "exact_symbols"]


class _Floats:
    """Plain Python floats: ``select`` is a conditional expression (both values already
    computed), ``branch`` calls the side chosen only."""

    fmin = staticmethod(min)
    fmax = staticmethod(max)
    sqrt = staticmethod(math.sqrt)
    atanh = staticmethod(math.atanh)
    cosh = staticmethod(math.cosh)
    cos = staticmethod(math.cos)
    sin = staticmethod(math.sin)
    symbolic = False

    @staticmethod
    def select(condition, if_true, if_false):
        return if_true if condition else if_false

    @staticmethod
    def branch(condition, if_true, if_false):
        return if_true() if condition else if_false()

    @staticmethod
    def either(first, second):
        return first or second


class _Symbols:
    """CasADi ``SX``: ``select`` and ``branch`` are ``if_else`` (both sides evaluated, the
    other one's value, even ``nan`` or ``inf``, replaced by a zero that is added),
    ``fmin``/``fmax`` are IEEE's (equal to Python's ``min``/``max`` on numbers that are not
    ``nan``)."""

    fmin = staticmethod(casadi.fmin)
    fmax = staticmethod(casadi.fmax)
    sqrt = staticmethod(casadi.sqrt)
    atanh = staticmethod(casadi.atanh)
    cosh = staticmethod(casadi.cosh)
    cos = staticmethod(casadi.cos)
    sin = staticmethod(casadi.sin)
    symbolic = True

    @staticmethod
    def select(condition, if_true, if_false):
        if isinstance(condition, bool):             # decided while building
            return if_true if condition else if_false
        return casadi.if_else(condition, if_true, if_false)

    @staticmethod
    def branch(condition, if_true, if_false):
        if isinstance(condition, bool):             # decided while building
            return if_true() if condition else if_false()
        return casadi.if_else(condition, if_true(), if_false())

    @staticmethod
    def either(first, second):
        return casadi.logic_or(first, second)

    @staticmethod
    def pad(condition, value):
        """``value`` where ``condition`` holds, else 0 (one operation: added to a finite
        number, it leaves it as it is, or moves it to ``value = inf``)."""
        return casadi.SX.binary(casadi.OP_IF_ELSE_ZERO, condition, value)


#: Plain floats (the default of every formula).
FLOATS = _Floats()
#: CasADi ``SX`` symbols (build inside :func:`exact_symbols`).
SYMBOLS = _Symbols()


@contextmanager
def exact_symbols() -> Iterator[None]:
    """Build ``SX`` expressions without CasADi's on-the-fly simplifications (restored on
    exit), so that a tree holds exactly the operations written.

    Examples
    --------
    >>> import casadi
    >>> x = casadi.SX.sym("x")
    >>> with exact_symbols():
    ...     print(x - x)
    (x-x)
    """
    before = casadi.GlobalOptions.getSimplificationOnTheFly()
    casadi.GlobalOptions.setSimplificationOnTheFly(False)
    try:
        yield
    finally:
        casadi.GlobalOptions.setSimplificationOnTheFly(before)
