"""Single-precision pass over CasADi's C: float maths functions and float literals.

CasADi's ``casadi_real="float"`` alone still calls ``exp``/``log``/``tanh`` (the double
functions, with promotion) and prints double literals (``9.``, ``4.5e+00``). This pass
rewrites a C fragment so that it is float throughout:

* every call of a C99 ``<math.h>`` function of :data:`FLOAT_FUNCTIONS` becomes its
  ``f``-suffixed version (``exp(`` -> ``expf(``);
* every floating literal gets the ``f`` suffix (``9.`` -> ``9.f``,
  ``4.5000000000000000e+00`` -> ``4.5000000000000000e+00f``): the decimal is rounded
  once, directly to the nearest float;
* a register used as a truth value (``(a?b:0)``, ``(!a)``, ``(a&&b)``, ``(a||b)``) is
  compared with zero explicitly (``(a!=0?b:0)``, ``(a==0)``, ...): the same C semantics,
  NaN included, without clang's float-to-bool ``-Wfloat-conversion`` warning;
* afterwards, every identifier followed by ``(`` must be a float maths function, a
  CasADi helper (``casadi_*``) or a body (``body_*``), and no literal may be a double:
  anything else raises :class:`CodegenError` (nothing is silently left in double).

Integer literals (``0``, ``1``, ``-1`` in helpers and ``arg[0]? arg[0][0] : 0``) are
exact in float and stay as they are. The compile tests add ``-Wdouble-promotion
-Wfloat-conversion -Werror`` to prove no double arithmetic remains.
"""

from __future__ import annotations

import re

from .errors import CodegenError

#: C99 maths functions CasADi may call, each with a float version ``<name>f``.
FLOAT_FUNCTIONS = ("acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "cbrt",
                   "ceil", "copysign", "cos", "cosh", "erf", "exp", "expm1", "fabs",
                   "floor", "fmax", "fmin", "fmod", "hypot", "log", "log1p", "pow",
                   "remainder", "sin", "sinh", "sqrt", "tan", "tanh")

_CALL = re.compile(r"\b(" + "|".join(FLOAT_FUNCTIONS) + r")\(")
_FLOAT_LITERAL = re.compile(
    r"(?<![\w.])((?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
#: CasADi's tests of a register's truth (``(a?b:0)``, ``(!a)``, ``(a&&b)``, ``(a||b)``).
_TRUTH_TERNARY = re.compile(r"\((a\d+)\?")
_TRUTH_NOT = re.compile(r"\(!(a\d+)\)")
_TRUTH_LOGIC = re.compile(r"\((a\d+)(&&|\|\|)(a\d+)\)")
_ANY_CALL = re.compile(r"\b([A-Za-z_]\w*)\s*\(")
_KEYWORDS = frozenset({"sizeof", "if", "while", "for", "return", "defined"})
_FLOAT_CALLS = frozenset(name + "f" for name in FLOAT_FUNCTIONS)


def _code_only(text: str) -> str:
    """``text`` with comments blanked (so their words are not taken for code)."""
    return re.sub(r"/\*.*?\*/", lambda m: " " * len(m.group(0)), text, flags=re.DOTALL)


def to_single(c_text: str) -> str:
    """Rewrite a CasADi C fragment to float maths and float literals.

    Parameters
    ----------
    c_text : str
        C code using ``casadi_real`` (comments are left unchanged).

    Returns
    -------
    str

    Raises
    ------
    CodegenError
        If a call or literal remains that would compute in double.
    """
    out = []
    pos = 0
    for m in re.finditer(r"/\*.*?\*/", c_text, flags=re.DOTALL):
        out.append(_convert(c_text[pos:m.start()]))
        out.append(m.group(0))
        pos = m.end()
    out.append(_convert(c_text[pos:]))
    result = "".join(out)
    check_single(result)
    return result


def _convert(code: str) -> str:
    code = _CALL.sub(lambda m: m.group(1) + "f(", code)
    code = _TRUTH_TERNARY.sub(r"(\1!=0?", code)
    code = _TRUTH_NOT.sub(r"(\1==0)", code)
    code = _TRUTH_LOGIC.sub(r"(\1!=0\2\3!=0)", code)
    return _FLOAT_LITERAL.sub(lambda m: m.group(1) + "f", code)


def check_single(c_text: str) -> None:
    """Raise :class:`CodegenError` if ``c_text`` still calls a double function or has a
    double literal (comments ignored)."""
    code = _code_only(c_text)
    for m in _ANY_CALL.finditer(code):
        name = m.group(1)
        if not (name in _KEYWORDS or name in _FLOAT_CALLS
                or name.startswith(("casadi_", "body_"))):
            raise CodegenError(f"single precision: call of {name!r} is not a float function")
    for m in re.finditer(r"(?<![\w.])((?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)"
                         r"(?![\w.])", code):
        raise CodegenError(f"single precision: double literal {m.group(1)!r} left")
