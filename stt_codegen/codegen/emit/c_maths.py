"""Maths functions of the project's own that the C printer defines in the generated file.

Two, both single precision: ``stt_expf`` (op ``exp``) and ``stt_logf`` (op ``log``) of
:data:`stt_codegen.codegen.emit.c_printer.SINGLE`. On the Cortex-M4F newlib's ``expf``
costs about 70 instructions per call (its ``__ieee754_expf`` and the wrapper that checks
for overflow and sets ``errno``) and ``logf`` about 65; a single-precision step makes
about 8 ``exp`` and 3 to 8 ``log`` calls. ``stt_expf`` costs 43 (48 with the call) and is
within 0.89 ulp of the exact ``e^x``; ``stt_logf`` costs about 36 for ``x`` in
``[1/sqrt 2, sqrt 2]``, about 10 more plus 5 per factor of 2 outside, and is within 0.84
ulp of the exact ``ln x``.

``stt_expf`` (the fast path, for ``TINY <= |x| <= FAST_BOUND``, ``2^-28 <= |x| <= 80``;
``|x| < 2^-28``, zero included, returns ``1 + x``, as the C library does; any other ``x``,
infinities and NaN included, goes to the C library's ``expf``, so the function is
``expf`` everywhere):

1. ``k = round(x / ln 2)``, by adding and subtracting ``1.5 * 2^23`` (exact rounding to
   an integer for ``|x / ln 2| < 2^22``).
2. Cody-Waite reduction ``r = x - k ln2_hi - k ln2_lo``: ``ln2_hi`` has 16 significant
   bits, so ``k ln2_hi`` is exact for ``|k| <= 128`` and ``r_hi = x - k ln2_hi`` is exact
   (Sterbenz); ``r = r_hi - k ln2_lo`` is rounded and its rounding error
   ``r_err = (r_hi - r) - k ln2_lo`` is carried into the polynomial's tail.
3. ``e^r = 1 + r + r^2 q(r)`` on ``|r| <= 0.35`` (``ln 2 / 2 = 0.3466`` plus the
   rounding of step 1), ``q`` of degree 4 (coefficients :data:`EXP_COEFFICIENTS`, the
   minimax of the relative error of ``e^r`` by Lawson's iteration, rounded to float32:
   approximation error ``3.3e-9`` relative, 0.06 ulp), evaluated as
   ``1 + (r + (r_err + r^2 q(r)))``.
4. Scaling by ``2^k``, ``|k| <= 116``, as one exact multiplication by a tabled power of
   two (233 floats, 932 bytes of flash; every entry is a normal float): for ``|x| <= 80``
   the result (``>= e^-80 = 1.8e-35``) is a normal float, so the scaling is exact and
   raises no flag. No ``ldexpf`` (a library call with its own checks) and no type punning
   (MISRA C:2012 rules 19.2 and 21.15). Two smaller tables (``2^(k mod 8)`` and
   ``2^(8 floor(k / 8))``, 152 bytes) cost 7 more instructions per call.

For ``|x| < 2^-28`` the exact ``e^x`` is within ``2^-28 (1 + 2^-28)`` of 1, less than a
quarter of the spacing of the floats around 1, so ``1 + x`` rounds to the correctly
rounded result (1, or ``1 + x`` exactly for ``x = 0``); it raises no flag but
``FE_INEXACT`` (the result is normal, also for a subnormal ``x``, where the polynomial's
``r^2`` would underflow).

Error: below **0.89 ulp** of the exact ``e^x`` for every float ``x`` in ``[-80, 80]``
(all 2 235 564 034 of them, checked against glibc's double ``exp``; 0.79 % of the results
differ from the correctly rounded float), and monotone non-decreasing there (no float
``x < x'`` with ``stt_expf(x) > stt_expf(x')``, as for a correctly rounded ``exp``; the
switch of ``k`` is where a table-driven exp could step back). The function raises no
floating-point exception flag other than ``FE_INEXACT`` on ``[-80, 80]`` and never
touches ``errno`` there. ``tests/test_c_maths.py`` checks the bound on a sample of the
domain, monotonicity where ``k`` changes, and the flags; the exhaustive sweep is
:func:`exhaustive_sweep_source` (about a minute on one core).

``stt_logf`` (the fast path, for ``LOG_FAST_LOW <= x <= LOG_FAST_HIGH``,
``2^-8 <= x <= 2^8``; any other ``x``, zero, negatives, infinities and NaN included,
goes to the C library's ``logf``): the fdlibm scheme without access to the bits.

1. ``x = m 2^k`` with ``m`` in ``[1/sqrt 2, sqrt 2]``: ``k = 0`` and ``m = x`` when ``x``
   is there (two comparisons); else ``k`` is the number of tabled thresholds
   ``sqrt 2 2^j`` below ``x`` (or ``-k`` those ``2^-j / sqrt 2`` above it), counted by
   an integer loop (MISRA C:2012 rule 14.1: no floating loop counter), about 5
   instructions per step of ``k``, and ``m = x 2^-k``, one exact multiplication by a
   tabled power of two. No ``frexpf`` (a library call of about 20 instructions, which
   would leave little to save) and no type punning.
2. ``f = m - 1`` (exact: Sterbenz), ``s = f / (2 + f)`` (``|s| <= 0.1716``),
   ``ln m = 2 atanh(s) = f - f^2/2 + s (f^2/2 + R(s^2))`` with ``R(z) = z (c1 + c2 z +
   c3 z^2)`` (coefficients :data:`LOG_COEFFICIENTS`, the minimax of
   ``(2 atanh(s) - 2 s) / s`` on ``z <= 0.02944`` by Lawson's iteration, rounded to
   float32: approximation error ``1.8e-9``, 0.015 ulp of the result).
3. ``ln x = k ln2_hi - ((f^2/2 - (s (f^2/2 + R) + k ln2_lo)) - f)``: ``ln2_hi`` as in
   ``stt_expf`` (``k ln2_hi`` exact for ``|k| <= 8``); for ``k = 0`` (``x`` in
   ``[1/sqrt 2, sqrt 2]``, no table access) the same value as
   ``f - (f^2/2 - s (f^2/2 + R))``.

Error: below **0.84 ulp** of the exact ``ln x`` for every float ``x`` in ``[2^-8, 2^8]``
(all 134 217 729 of them, checked against glibc's double ``log``), monotone
non-decreasing there, and ``stt_logf(1) = 0`` exactly. The fast path raises no flag but
``FE_INEXACT`` and never touches ``errno``. The single-precision error bounds
(:mod:`stt_codegen.codegen.tolerance`) take one ulp for a ``log``
(:data:`stt_codegen.codegen.tolerance.LOG_ERROR_ULP`), which covers it.
``tests/test_c_maths.py`` checks the bound and monotonicity on every 17th float of the
fast path, the flags, and the fallback; the exhaustive sweep is
:func:`log_sweep_source` (a few seconds).

The results are the same on every IEEE-754 target that evaluates ``float`` expressions in
``float`` (``FLT_EVAL_METHOD == 0``: x86-64 SSE, ARMv7E-M FPv4, AArch64) without
contraction into fused multiply-adds (``-ffp-contract=off``, the default of
``-std=c99`` in gcc); with contraction the values may differ in the last bit.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np

__all__ = ["EXP_COEFFICIENTS", "FAST_BOUND", "FUNCTIONS", "K_MAX", "LN2_HI", "LN2_LO", "LOG2E",
           "LOG_BOUND_ULP", "LOG_COEFFICIENTS", "LOG_FAST_HIGH", "LOG_FAST_LOW", "LOG_K_MAX",
           "SQRT2", "SQRT1_2", "exhaustive_sweep_source", "expf_source", "log_sweep_source",
           "logf_source", "source"]

#: Name of the single-precision exp defined in the generated C.
EXPF_NAME = "stt_expf"
#: Name of the single-precision log defined in the generated C.
LOGF_NAME = "stt_logf"
#: The fast path serves ``|x| <= FAST_BOUND`` (the pieces clamp every exponent to
#: ``[-80, 80]``, :data:`stt_codegen.tube.pieces.EXP_ARGUMENT_BOUND`).
FAST_BOUND = 80.0
#: ... and ``|x| >= TINY`` (``2^-28``): below, ``r^2`` could underflow (raising
#: ``FE_UNDERFLOW``) and ``e^x`` rounds to ``1 + x``, which ``stt_expf`` returns (as the C
#: library's ``expf`` does).
TINY = 2.0 ** -28
#: ``1 / ln 2`` rounded to float32.
LOG2E = float(np.float32(1.4426950408889634))
#: ``1.5 * 2^23``: adding and subtracting it rounds to an integer.
SHIFTER = 12582912.0
#: ``ln 2`` in two parts: 16 significant bits (``0x3f317200``) and the float32 rest.
LN2_HI = 0.693145751953125
LN2_LO = float(np.float32(0.6931471805599453 - 0.693145751953125))
#: ``q(r) = c0 + c1 r + c2 r^2 + c3 r^3 + c4 r^4`` (float32 values), ``e^r ~ 1 + r + r^2 q(r)``.
EXP_COEFFICIENTS: Tuple[float, ...] = (
    0.4999999403953552, 0.16666515171527863, 0.04166845604777336, 0.008369408547878265,
    0.0013813088880851865)
#: Largest ``|k|`` of the fast path (``round(80 / ln 2) = 115``, plus one for the
#: rounding of ``x / ln 2``); the table :func:`expf_source` prints holds ``2^-K .. 2^K``.
K_MAX = 116

#: ``stt_logf``'s fast path serves ``LOG_FAST_LOW <= x <= LOG_FAST_HIGH``: at most
#: :data:`LOG_K_MAX` halvings or doublings bring ``x`` to ``[1/sqrt 2, sqrt 2]``.
LOG_FAST_LOW = 2.0 ** -8
LOG_FAST_HIGH = 2.0 ** 8
LOG_K_MAX = 8
#: ``sqrt 2`` and ``1/sqrt 2`` rounded to float32 (the ends of the reduced range).
SQRT2 = float(np.float32(1.4142135623730951))
SQRT1_2 = float(np.float32(0.7071067811865476))
#: ``R(z) = z (c1 + c2 z + c3 z^2)``, ``ln m ~ f - f^2/2 + s (f^2/2 + R(s^2))``.
LOG_COEFFICIENTS: Tuple[float, ...] = (
    0.6666677594184875, 0.39977532625198364, 0.29872018098831177)
#: The largest error of :func:`logf_source` on its fast path (the exhaustive sweep
#: :func:`log_sweep_source`: 0.8399 ulp at ``x = 0x1.69cf3ep+0``), rounded up.
LOG_BOUND_ULP = 0.84

#: (op name, C name) of the functions defined here, in the order of emission.
FUNCTIONS: Tuple[Tuple[str, str], ...] = (("exp", EXPF_NAME), ("log", LOGF_NAME))


def _f(value: float) -> str:
    """A float constant that reads back exactly (``value`` is a float32 number)."""
    if float(np.float32(value)) != value:
        raise ValueError(f"{value!r} is not a float32 number")
    return repr(float(value)) + "f"


def _powers_of_two(per_line: int) -> str:
    """``2^-K_MAX .. 2^K_MAX`` as hexadecimal float constants (C99), ``per_line`` a line."""
    items = [f"0x1p{k}f" for k in range(-K_MAX, K_MAX + 1)]
    lines = [", ".join(items[i:i + per_line]) for i in range(0, len(items), per_line)]
    return ",\n    ".join(lines)


def expf_source() -> str:
    """C99 text of ``static float stt_expf(float x)`` (needs ``<math.h>``).

    Returns
    -------
    str
        The definition, with a comment stating its algorithm and error bound.
    """
    c = EXP_COEFFICIENTS
    return f"""\
/* {EXPF_NAME}(x): expf(x), within 0.89 ulp of the exact e^x for |x| <= {FAST_BOUND:g} (every
   float there checked), with no library call for |x| <= {FAST_BOUND:g}: below 2^-28, 1 + x (the
   correctly rounded e^x); else k = round(x / ln 2), r = x - k ln 2 in two
   parts (Cody-Waite), e^r = 1 + r + r^2 q(r) (q minimax, degree 4), then one exact
   multiplication by a tabled power of two. Other x (and NaN) go to expf. There it
   raises no exception flag but FE_INEXACT and does not touch errno. See
   stt_codegen/codegen/emit/c_maths.py. */
static float {EXPF_NAME}(float x) {{
  /* 2^k for k = -{K_MAX} .. {K_MAX} */
  static const float POWERS_OF_TWO[{2 * K_MAX + 1}] = {{
    {_powers_of_two(8)}
  }};
  const float magnitude = fabsf(x);
  float y;
  if (magnitude < {_f(TINY)}) {{
    y = 1.0f + x;
  }} else if (magnitude <= {_f(FAST_BOUND)}) {{
    const float k = ((x * {_f(LOG2E)}) + {_f(SHIFTER)}) - {_f(SHIFTER)};
    const float r_hi = x - (k * {_f(LN2_HI)});
    const float r_lo = k * {_f(LN2_LO)};
    const float r = r_hi - r_lo;
    const float r_err = (r_hi - r) - r_lo;
    const int k_int = (int)k;
    float q = {_f(c[4])};
    q = (q * r) + {_f(c[3])};
    q = (q * r) + {_f(c[2])};
    q = (q * r) + {_f(c[1])};
    q = (q * r) + {_f(c[0])};
    y = (1.0f + (r + (r_err + ((r * r) * q)))) * POWERS_OF_TWO[(unsigned int)k_int + {K_MAX}u];
  }} else {{
    y = expf(x);
  }}
  return y;
}}
"""


def exhaustive_sweep_source() -> str:
    """A C program that checks :func:`expf_source` on every float in ``[-80, 80]``.

    It walks the floats in increasing order and prints the largest error in ulps of the
    exact value (glibc's double ``exp`` as the reference), how many results differ from
    the correctly rounded float and how many times the result decreases (monotonicity).
    Exit status 0 when the error is below one ulp and the function is monotone. Build
    with ``gcc -O2 -std=c99 -ffp-contract=off sweep.c -lm``.

    Returns
    -------
    str
    """
    return f"""\
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

{expf_source()}
static double worst = 0.0;
static float worst_x = 0.0f;
static long long count = 0, not_rounded = 0, decreasing = 0;
static float previous = 0.0f;

static void check(uint32_t bits) {{
  float x, y;
  double ref, err;
  int e;
  memcpy(&x, &bits, sizeof x);
  y = {EXPF_NAME}(x);
  ref = exp((double)x);
  (void)frexp(ref, &e);
  err = fabs((double)y - ref) / ldexp(1.0, e - 24);
  if (err > worst) {{ worst = err; worst_x = x; }}
  if ((float)ref != y) {{ ++not_rounded; }}
  if (count > 0 && y < previous) {{ ++decreasing; }}
  previous = y;
  ++count;
}}

int main(void) {{
  uint32_t bits;
  for (bits = 0x42a00000u + 1u; bits-- > 0u;) {{   /* -80 .. -0 */
    check(bits | 0x80000000u);
  }}
  for (bits = 0u; bits <= 0x42a00000u; ++bits) {{   /* +0 .. 80 */
    check(bits);
  }}
  printf("%lld floats, max error %.4f ulp at x = %a, %lld not correctly rounded, "
         "%lld decreasing steps\\n", count, worst, (double)worst_x, not_rounded, decreasing);
  return (worst < 1.0 && decreasing == 0) ? 0 : 1;
}}
"""



def _thresholds(base: float, sign: int) -> str:
    """``base 2^(sign j)``, ``j = 0 .. LOG_K_MAX - 1`` (exact: powers of two times a float)."""
    return ", ".join(_f(base * 2.0 ** (sign * j)) for j in range(LOG_K_MAX))


def _log_scales() -> str:
    """``2^-LOG_K_MAX .. 2^LOG_K_MAX`` as hexadecimal float constants."""
    return ", ".join(f"0x1p{j}f" for j in range(-LOG_K_MAX, LOG_K_MAX + 1))


def logf_source() -> str:
    """C99 text of ``static float stt_logf(float x)`` (needs ``<math.h>``).

    Returns
    -------
    str
        The definition, with a comment stating its algorithm and error bound.
    """
    c = LOG_COEFFICIENTS
    return f"""\
/* {LOGF_NAME}(x): logf(x), within {LOG_BOUND_ULP:g} ulp of the exact ln x for 2^-{LOG_K_MAX} <= x <= 2^{LOG_K_MAX} (every
   float there checked), with no library call there: x = m 2^k with m in [1/sqrt 2, sqrt 2]
   (k counted against tabled thresholds, m = x 2^-k exact), f = m - 1, s = f / (2 + f),
   ln m = f - f^2/2 + s (f^2/2 + R(s^2)) (R minimax, degree 3), plus k ln 2 in two parts.
   Other x (zero, negative, infinite, NaN) go to logf. The fast path raises no exception
   flag but FE_INEXACT and does not touch errno. See stt_codegen/codegen/emit/c_maths.py. */
static float {LOGF_NAME}(float x) {{
  /* sqrt 2 2^j and 2^-j / sqrt 2 (j = 0 .. {LOG_K_MAX - 1}): where k steps up or down */
  static const float ABOVE[{LOG_K_MAX}] = {{ {_thresholds(SQRT2, 1)} }};
  static const float BELOW[{LOG_K_MAX}] = {{ {_thresholds(SQRT1_2, -1)} }};
  /* 2^j for j = -{LOG_K_MAX} .. {LOG_K_MAX} */
  static const float SCALE[{2 * LOG_K_MAX + 1}] = {{ {_log_scales()} }};
  float y;
  if ((x >= {_f(LOG_FAST_LOW)}) && (x <= {_f(LOG_FAST_HIGH)})) {{
    float m = x;
    int j = 0;
    if (x > ABOVE[0]) {{
      j = 1;
      while ((j < {LOG_K_MAX}) && (x > ABOVE[j])) {{
        j = j + 1;
      }}
    }} else if (x < BELOW[0]) {{
      j = 1;
      while ((j < {LOG_K_MAX}) && (x < BELOW[j])) {{
        j = j + 1;
      }}
      j = -j;
    }} else {{
      /* x in [1/sqrt 2, sqrt 2]: k = 0, m = x */
    }}
    if (j != 0) {{
      m = x * SCALE[{LOG_K_MAX} - j];
    }}
    {{
      const float f = m - 1.0f;
      const float s = f / (2.0f + f);
      const float z = s * s;
      const float half_f2 = (0.5f * f) * f;
      float r = {_f(c[2])};
      r = (r * z) + {_f(c[1])};
      r = (r * z) + {_f(c[0])};
      r = r * z;
      if (j == 0) {{
        y = f - (half_f2 - (s * (half_f2 + r)));
      }} else {{
        const float k = (float)j;
        y = (k * {_f(LN2_HI)}) - ((half_f2 - ((s * (half_f2 + r)) + (k * {_f(LN2_LO)}))) - f);
      }}
    }}
  }} else {{
    y = logf(x);
  }}
  return y;
}}
"""


def log_sweep_source() -> str:
    """A C program that checks :func:`logf_source` on every float of its fast path.

    It walks the floats of ``[2^-8, 2^8]`` in increasing order and prints the largest
    error in ulps of the exact value (glibc's double ``log`` as the reference; at
    ``x = 1``, where ``ln x = 0``, any nonzero result counts as an infinite error), how
    many results differ from the correctly rounded float and how many times the result
    decreases. Exit status 0 when the error is below :data:`LOG_BOUND_ULP` and the
    function is monotone. Build with ``gcc -O2 -std=c99 -ffp-contract=off sweep.c -lm``.

    Returns
    -------
    str
    """
    return f"""\
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

{logf_source()}
int main(void) {{
  const float low = {_f(LOG_FAST_LOW)};
  const float high = {_f(LOG_FAST_HIGH)};
  uint32_t bits, first, last;
  double worst = 0.0;
  float worst_x = 0.0f, previous = -HUGE_VALF;
  long long count = 0, not_rounded = 0, decreasing = 0;
  memcpy(&first, &low, sizeof first);
  memcpy(&last, &high, sizeof last);
  for (bits = first; bits <= last; ++bits) {{
    float x, y;
    double ref, err;
    int e;
    memcpy(&x, &bits, sizeof x);
    y = {LOGF_NAME}(x);
    ref = log((double)x);
    if (ref == 0.0) {{
      err = (y == 0.0f) ? 0.0 : HUGE_VAL;
    }} else {{
      (void)frexp(ref, &e);
      err = fabs((double)y - ref) / ldexp(1.0, e - 24);
    }}
    if (err > worst) {{ worst = err; worst_x = x; }}
    if ((float)ref != y) {{ ++not_rounded; }}
    if (y < previous) {{ ++decreasing; }}
    previous = y;
    ++count;
  }}
  printf("%lld floats, max error %.4f ulp at x = %a, %lld not correctly rounded, "
         "%lld decreasing steps\\n", count, worst, (double)worst_x, not_rounded, decreasing);
  return (worst < {LOG_BOUND_ULP!r} && decreasing == 0) ? 0 : 1;
}}
"""


def source(op: str) -> str:
    """C text of the function of this module that computes ``op`` (see :data:`FUNCTIONS`).

    Parameters
    ----------
    op : str
        An op name (:mod:`.ops`); ``"exp"`` and ``"log"`` have a function here.

    Returns
    -------
    str
        The C text of the function (``stt_expf`` or ``stt_logf``).

    Raises
    ------
    KeyError
        If no function here computes ``op``.
    """
    sources = {"exp": expf_source, "log": logf_source}
    return sources[op]()
