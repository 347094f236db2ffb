"""Source text of the helper functions that generated Python code may need.

Each helper reproduces, for one operation, the IEEE 754 / C99 result that CasADi's
virtual machine computes (through the C library) where Python raises instead
(``ZeroDivisionError``, ``ValueError: math domain error``, ``OverflowError``) or
differs (``math.floor`` returning an int). The fast path is always the plain ``math``
call; the exception handlers only run on the special cases. Helpers are copied into
the generated module only if used, in the order of :data:`HELPERS`.
"""

from __future__ import annotations

from typing import Dict, Tuple

__all__ = ["HELPERS", "HELPER_DEPENDENCIES"]

# (name, source, names of helpers it calls); the order is the order of emission.
HELPERS: Tuple[Tuple[str, str, Tuple[str, ...]], ...] = (
    ("_div", '''\
def _div(x, y):
    """x / y with IEEE results for y == 0: +-inf, or nan for 0/0 and nan/0."""
    try:
        return x / y
    except ZeroDivisionError:
        if x != x or x == 0.0:
            return math.nan
        return math.copysign(math.inf, x) * math.copysign(1.0, y)
''', ()),
    ("_fmin", '''\
def _fmin(x, y):
    """C fmin as CasADi evaluates it: a NaN operand is ignored; on a tie, x."""
    if y != y:
        return x
    if x != x:
        return y
    return x if x <= y else y
''', ()),
    ("_fmax", '''\
def _fmax(x, y):
    """C fmax as CasADi evaluates it: a NaN operand is ignored; on a tie, x."""
    if y != y:
        return x
    if x != x:
        return y
    return x if x >= y else y
''', ()),
    ("_sign", '''\
def _sign(x):
    """CasADi sign: -1.0, 1.0, or x itself for +-0.0 and nan."""
    if x < 0.0:
        return -1.0
    if x > 0.0:
        return 1.0
    return x
''', ()),
    ("_floor", '''\
def _floor(x):
    """C floor: a float, sign of zero kept, inf and nan returned unchanged."""
    try:
        return math.copysign(float(math.floor(x)), x)
    except (OverflowError, ValueError):
        return x
''', ()),
    ("_ceil", '''\
def _ceil(x):
    """C ceil: a float, -0.0 for x in (-1, 0], inf and nan returned unchanged."""
    try:
        return math.copysign(float(math.ceil(x)), x)
    except (OverflowError, ValueError):
        return x
''', ()),
    ("_fmod", '''\
def _fmod(x, y):
    """C fmod: nan for y == 0 or infinite x."""
    try:
        return math.fmod(x, y)
    except ValueError:
        return math.nan
''', ()),
    ("_remainder", '''\
def _remainder(x, y):
    """C remainder: nan for y == 0 or infinite x."""
    try:
        return math.remainder(x, y)
    except ValueError:
        return math.nan
''', ()),
    ("_sqrt", '''\
def _sqrt(x):
    """C sqrt: nan for x < 0 (sqrt(-0.0) is -0.0)."""
    try:
        return math.sqrt(x)
    except ValueError:
        return math.nan
''', ()),
    ("_odd_integer", '''\
def _odd_integer(y):
    """True if y is a finite odd integer."""
    return math.isfinite(y) and math.fabs(math.fmod(y, 2.0)) == 1.0
''', ()),
    ("_pow", '''\
def _pow(x, y):
    """C pow: +-inf for 0 to a negative power and on overflow, nan for x < 0 to a
    non-integer power."""
    try:
        return math.pow(x, y)
    except ValueError:
        if x == 0.0:
            return math.copysign(math.inf, x) if _odd_integer(y) else math.inf
        return math.nan
    except OverflowError:
        if x < 0.0 and _odd_integer(y):
            return -math.inf
        return math.inf
''', ("_odd_integer",)),
    ("_exp", '''\
def _exp(x):
    """C exp: inf on overflow."""
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf
''', ()),
    ("_expm1", '''\
def _expm1(x):
    """C expm1: inf on overflow."""
    try:
        return math.expm1(x)
    except OverflowError:
        return math.inf
''', ()),
    ("_log", '''\
def _log(x):
    """C log: -inf for +-0.0, nan for x < 0."""
    try:
        return math.log(x)
    except ValueError:
        return -math.inf if x == 0.0 else math.nan
''', ()),
    ("_log1p", '''\
def _log1p(x):
    """C log1p: -inf for x == -1, nan for x < -1."""
    try:
        return math.log1p(x)
    except ValueError:
        return -math.inf if x == -1.0 else math.nan
''', ()),
    ("_sin", '''\
def _sin(x):
    """C sin: nan for infinite x."""
    try:
        return math.sin(x)
    except ValueError:
        return math.nan
''', ()),
    ("_cos", '''\
def _cos(x):
    """C cos: nan for infinite x."""
    try:
        return math.cos(x)
    except ValueError:
        return math.nan
''', ()),
    ("_tan", '''\
def _tan(x):
    """C tan: nan for infinite x."""
    try:
        return math.tan(x)
    except ValueError:
        return math.nan
''', ()),
    ("_asin", '''\
def _asin(x):
    """C asin: nan for |x| > 1."""
    try:
        return math.asin(x)
    except ValueError:
        return math.nan
''', ()),
    ("_acos", '''\
def _acos(x):
    """C acos: nan for |x| > 1."""
    try:
        return math.acos(x)
    except ValueError:
        return math.nan
''', ()),
    ("_sinh", '''\
def _sinh(x):
    """C sinh: +-inf on overflow."""
    try:
        return math.sinh(x)
    except OverflowError:
        return math.copysign(math.inf, x)
''', ()),
    ("_cosh", '''\
def _cosh(x):
    """C cosh: inf on overflow."""
    try:
        return math.cosh(x)
    except OverflowError:
        return math.inf
''', ()),
    ("_acosh", '''\
def _acosh(x):
    """C acosh: nan for x < 1."""
    try:
        return math.acosh(x)
    except ValueError:
        return math.nan
''', ()),
    ("_atanh", '''\
def _atanh(x):
    """C atanh: +-inf for x == +-1, nan for |x| > 1."""
    try:
        return math.atanh(x)
    except ValueError:
        return math.copysign(math.inf, x) if math.fabs(x) == 1.0 else math.nan
''', ()),
)

HELPER_SOURCE: Dict[str, str] = {name: src for name, src, _ in HELPERS}
HELPER_DEPENDENCIES: Dict[str, Tuple[str, ...]] = {name: deps for name, _, deps in HELPERS}
