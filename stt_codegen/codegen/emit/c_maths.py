"""Maths functions of the project's own that the C printer defines in the generated file.

Today one: ``stt_expf``, the single-precision ``exp`` (op ``exp`` of
:data:`stt_codegen.codegen.emit.c_printer.SINGLE`). On the Cortex-M4F newlib's ``expf``
costs about 70 instructions per call (its ``__ieee754_expf`` and the wrapper that checks
for overflow and sets ``errno``) and a single-precision step makes about 8 of them; this
one costs 43 (48 with the call) and is within 0.89 ulp of the exact ``e^x``.

Algorithm (the fast path, for ``TINY <= |x| <= FAST_BOUND``, ``2^-28 <= |x| <= 80``; any
other ``x``, zero, infinities and NaN included, goes to the C library's ``expf``, so the
function is ``expf`` everywhere):

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

Error: below **0.89 ulp** of the exact ``e^x`` for every float ``x`` in ``[-80, 80]``
(all 2 235 564 034 of them, checked against glibc's double ``exp``; 0.79 % of the results
differ from the correctly rounded float), and monotone non-decreasing there (no float
``x < x'`` with ``stt_expf(x) > stt_expf(x')``, as for a correctly rounded ``exp``; the
switch of ``k`` is where a table-driven exp could step back). The fast path raises no floating-point exception
flag other than ``FE_INEXACT`` and never touches ``errno``. ``tests/test_c_maths.py`` checks
the bound on a sample of the domain, monotonicity where ``k`` changes, and the flags; the exhaustive sweep is
:func:`exhaustive_sweep_source` (about a minute on one core).

The results are the same on every IEEE-754 target that evaluates ``float`` expressions in
``float`` (``FLT_EVAL_METHOD == 0``: x86-64 SSE, ARMv7E-M FPv4, AArch64) without
contraction into fused multiply-adds (``-ffp-contract=off``, the default of
``-std=c99`` in gcc); with contraction the values may differ in the last bit and stay
within the bound (every fused operation is at least as accurate).
"""

from __future__ import annotations

from typing import Tuple

import numpy as np

__all__ = ["EXP_COEFFICIENTS", "FAST_BOUND", "FUNCTIONS", "K_MAX", "LN2_HI", "LN2_LO", "LOG2E",
           "expf_source", "source"]

#: Name of the single-precision exp defined in the generated C.
EXPF_NAME = "stt_expf"
#: The fast path serves ``|x| <= FAST_BOUND`` (the pieces clamp every exponent to
#: ``[-80, 80]``, :data:`stt_codegen.tube.pieces.EXP_ARGUMENT_BOUND`).
FAST_BOUND = 80.0
#: ... and ``|x| >= TINY`` (``2^-28``): below, ``r^2`` could underflow (raising
#: ``FE_UNDERFLOW``) and ``e^x`` rounds to ``1 + x``; the C library's ``expf`` returns that.
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

#: (op name, C name) of the functions defined here, in the order of emission.
FUNCTIONS: Tuple[Tuple[str, str], ...] = (("exp", EXPF_NAME),)


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
   float there checked), with no library call for 2^-28 <= |x| <= {FAST_BOUND:g}: k = round(x / ln 2), r = x - k ln 2 in two
   parts (Cody-Waite), e^r = 1 + r + r^2 q(r) (q minimax, degree 4), then one exact
   multiplication by a tabled power of two. Other x (and NaN) go to expf. The fast path
   raises no exception flag but FE_INEXACT and does not touch errno. See
   stt_codegen/codegen/emit/c_maths.py. */
static float {EXPF_NAME}(float x) {{
  /* 2^k for k = -{K_MAX} .. {K_MAX} */
  static const float POWERS_OF_TWO[{2 * K_MAX + 1}] = {{
    {_powers_of_two(8)}
  }};
  const float magnitude = fabsf(x);
  float y;
  if ((magnitude <= {_f(FAST_BOUND)}) && (magnitude >= {_f(TINY)})) {{
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


def source(op: str) -> str:
    """C text of the function of this module that computes ``op`` (see :data:`FUNCTIONS`).

    Parameters
    ----------
    op : str
        An op name (:mod:`.ops`); only ``"exp"`` has a function here.

    Returns
    -------
    str
        The C text of the function (``stt_expf``).

    Raises
    ------
    KeyError
        If no function here computes ``op``.
    """
    if op != "exp":
        raise KeyError(op)
    return expf_source()
