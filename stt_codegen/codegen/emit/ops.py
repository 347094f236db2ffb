"""Table of the CasADi SX operations known to the emitter.

Each entry maps a CasADi op code (``casadi.OP_*``, looked up by name at import time so
that an op missing from the installed CasADi is simply absent) to a language-neutral
op name, its arity and a cost category used by operation counts:

``"data"``
    moves a value without computing (input, output, constant, assign).
``"arithmetic"``
    IEEE basic operations and cheap exact ones (add, mul, div, neg, fabs, fmin, sign...).
``"logic"``
    comparisons, boolean operations and ``if_else_zero``; results are 1.0 or 0.0.
``"transcendental"``
    calls into the maths library: exp, log, trigonometric and hyperbolic functions,
    and also ``sqrt``, ``pow``, ``constpow``, ``hypot`` and ``erf`` (library calls whose
    cost is of the same order, rather than algebraically transcendental functions).

The table is an ordered tuple (checked against CasADi 3.8.2 by introspection); nothing
here iterates over a set or over a dict keyed by SX objects.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Tuple

import casadi

__all__ = ["CATEGORIES", "OPS", "OPS_BY_NAME", "casadi_op_name"]

DATA = "data"
ARITHMETIC = "arithmetic"
LOGIC = "logic"
TRANSCENDENTAL = "transcendental"
CATEGORIES: Tuple[str, ...] = (DATA, ARITHMETIC, LOGIC, TRANSCENDENTAL)


@dataclass(frozen=True)
class OpInfo:
    """One CasADi operation as the emitter sees it.

    Attributes
    ----------
    code : int
        CasADi op code (value of ``casadi.OP_*``).
    casadi_name : str
        Name of the CasADi constant, e.g. ``"OP_ADD"``.
    name : str
        Language-neutral op name used in instructions, e.g. ``"add"``.
    arity : int
        Number of register operands (0 for input/const, 1 for output).
    category : str
        One of :data:`CATEGORIES`.
    """

    code: int
    casadi_name: str
    name: str
    arity: int
    category: str


# (casadi constant, op name, arity, category); order is the order of this listing.
_TABLE: Tuple[Tuple[str, str, int, str], ...] = (
    ("OP_INPUT", "input", 0, DATA),
    ("OP_OUTPUT", "output", 1, DATA),
    ("OP_CONST", "const", 0, DATA),
    ("OP_ASSIGN", "assign", 1, DATA),
    ("OP_ADD", "add", 2, ARITHMETIC),
    ("OP_SUB", "sub", 2, ARITHMETIC),
    ("OP_MUL", "mul", 2, ARITHMETIC),
    ("OP_DIV", "div", 2, ARITHMETIC),
    ("OP_NEG", "neg", 1, ARITHMETIC),
    ("OP_SQ", "sq", 1, ARITHMETIC),
    ("OP_TWICE", "twice", 1, ARITHMETIC),
    ("OP_INV", "inv", 1, ARITHMETIC),
    ("OP_FABS", "fabs", 1, ARITHMETIC),
    ("OP_SIGN", "sign", 1, ARITHMETIC),
    ("OP_COPYSIGN", "copysign", 2, ARITHMETIC),
    ("OP_FMIN", "fmin", 2, ARITHMETIC),
    ("OP_FMAX", "fmax", 2, ARITHMETIC),
    ("OP_FLOOR", "floor", 1, ARITHMETIC),
    ("OP_CEIL", "ceil", 1, ARITHMETIC),
    ("OP_FMOD", "fmod", 2, ARITHMETIC),
    ("OP_REMAINDER", "remainder", 2, ARITHMETIC),
    ("OP_LT", "lt", 2, LOGIC),
    ("OP_LE", "le", 2, LOGIC),
    ("OP_EQ", "eq", 2, LOGIC),
    ("OP_NE", "ne", 2, LOGIC),
    ("OP_NOT", "not", 1, LOGIC),
    ("OP_AND", "and", 2, LOGIC),
    ("OP_OR", "or", 2, LOGIC),
    ("OP_IF_ELSE_ZERO", "if_else_zero", 2, LOGIC),
    ("OP_SQRT", "sqrt", 1, TRANSCENDENTAL),
    ("OP_POW", "pow", 2, TRANSCENDENTAL),
    ("OP_CONSTPOW", "constpow", 2, TRANSCENDENTAL),
    ("OP_EXP", "exp", 1, TRANSCENDENTAL),
    ("OP_EXPM1", "expm1", 1, TRANSCENDENTAL),
    ("OP_LOG", "log", 1, TRANSCENDENTAL),
    ("OP_LOG1P", "log1p", 1, TRANSCENDENTAL),
    ("OP_SIN", "sin", 1, TRANSCENDENTAL),
    ("OP_COS", "cos", 1, TRANSCENDENTAL),
    ("OP_TAN", "tan", 1, TRANSCENDENTAL),
    ("OP_ASIN", "asin", 1, TRANSCENDENTAL),
    ("OP_ACOS", "acos", 1, TRANSCENDENTAL),
    ("OP_ATAN", "atan", 1, TRANSCENDENTAL),
    ("OP_ATAN2", "atan2", 2, TRANSCENDENTAL),
    ("OP_SINH", "sinh", 1, TRANSCENDENTAL),
    ("OP_COSH", "cosh", 1, TRANSCENDENTAL),
    ("OP_TANH", "tanh", 1, TRANSCENDENTAL),
    ("OP_ASINH", "asinh", 1, TRANSCENDENTAL),
    ("OP_ACOSH", "acosh", 1, TRANSCENDENTAL),
    ("OP_ATANH", "atanh", 1, TRANSCENDENTAL),
    ("OP_ERF", "erf", 1, TRANSCENDENTAL),
    ("OP_HYPOT", "hypot", 2, TRANSCENDENTAL),
)


def _build_table() -> Dict[int, OpInfo]:
    table: Dict[int, OpInfo] = {}
    for casadi_name, name, arity, category in _TABLE:
        code = getattr(casadi, casadi_name, None)
        if isinstance(code, int):
            table[code] = OpInfo(code, casadi_name, name, arity, category)
    return table


#: Op code -> :class:`OpInfo`, for the ops that exist in the installed CasADi.
OPS: Dict[int, OpInfo] = _build_table()

#: Op name -> :class:`OpInfo`.
OPS_BY_NAME: Dict[str, OpInfo] = {info.name: info for info in OPS.values()}


def casadi_op_name(code: int) -> str:
    """Return the CasADi constant name (``"OP_..."``) of an op code, for messages.

    Parameters
    ----------
    code : int
        CasADi op code.

    Returns
    -------
    str
        E.g. ``"OP_ERFINV"``, or ``"op code <n>"`` when no ``casadi.OP_*`` has that value.
    """
    names = sorted(
        n for n in dir(casadi) if n.startswith("OP_") and getattr(casadi, n) == code
    )
    return names[0] if names else f"op code {code}"
