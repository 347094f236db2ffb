"""The single-precision Newton stop test raises no flag and decides as the plain product.

The generated ``P_newton_stop(a6, d, r)`` (``templates/c_source.c.j2``) decides
``a6 d^2 <= r`` without a subnormal or overflowing intermediate (docs/codegen.md, "Single
precision stops"). A driver that includes the generated single-precision source samples
``(a6, d, r)`` over float32's whole exponent range (and ``r`` at the plain product and its
neighbours, where the decision flips); for each it evaluates the plain test
``(a6 * (d * d)) <= r`` of the earlier code, then ``P_newton_stop``: the latter must raise
no flag but ``FE_INEXACT``, and must agree wherever the plain test raised neither
``FE_UNDERFLOW`` nor ``FE_OVERFLOW``.
"""

from __future__ import annotations

import re
import subprocess

import pytest
from codegen_helpers import COMPILERS, write
from hard_helpers import hard_case

DRIVER = r"""
#include <fenv.h>
#include <math.h>
#include <stdio.h>
#include "PREFIX.c"

#define FLAGS (FE_OVERFLOW | FE_UNDERFLOW | FE_INVALID | FE_DIVBYZERO)
static unsigned long long state = 88172645463325252ULL;
static unsigned long long next(void) {
  state ^= state << 13; state ^= state >> 7; state ^= state << 17; return state;
}
static __attribute__((noinline)) int plain_stop(float a6, float d, float r) {
  volatile float p = a6 * (d * d);   /* volatile: not moved past the flag tests */
  return p <= r;
}
static __attribute__((noinline)) float plain_product(float a6, float d) {
  volatile float p = a6 * (d * d);
  return p;
}
static float sample(int lo, int hi) {
  float m = 1.0f + (float)(next() % 8388608ULL) / 8388608.0f;
  return ldexpf(m, lo + (int)(next() % (unsigned long long)(hi - lo + 1)));
}

int main(void) {
  long compared = 0, scaled = 0, flagged = 0, stops = 0, bad = 0;
  int k, j;
  for (k = 0; k < 400000; ++k) {
    volatile float a6 = sample(-149, 127);
    volatile float d = (next() & 1 ? -1.0f : 1.0f) * sample(-149, 63);
    float r0 = sample(-149, 127);
    if (k % 3 == 0) {   /* r at the plain product and its neighbours */
      feclearexcept(FE_ALL_EXCEPT);
      r0 = plain_product(a6, d);
      if (fetestexcept(FLAGS) != 0 || r0 == 0.0f) {
        r0 = sample(-149, 127);
      }
    }
    for (j = -1; j <= 1; ++j) {
      volatile float r = j == 0 ? r0 : nextafterf(r0, j < 0 ? 0.0f : INFINITY);
      int plain, fast, before, after;
      feclearexcept(FE_ALL_EXCEPT);
      plain = plain_stop(a6, d, r);
      before = fetestexcept(FE_UNDERFLOW | FE_OVERFLOW);
      feclearexcept(FE_ALL_EXCEPT);
      fast = PREFIX_newton_stop(a6, d, r);
      after = fetestexcept(FLAGS);
      if (after != 0) {
        ++bad;
        if (bad < 10) printf("RAISED %d: a6 %a d %a r %a\n", after, a6, d, r);
      }
      if (before != 0) {
        ++flagged;
        continue;
      }
      ++compared;
      stops += plain;
      if (a6 < 0x1p-40f || fabsf(d) < 0x1p-40f || a6 >= 0x1p40f || fabsf(d) >= 0x1p40f) ++scaled;
      if (plain != fast) {
        ++bad;
        if (bad < 10) printf("DIFFER: a6 %a d %a r %a plain %d\n", a6, d, r, plain);
      }
    }
  }
  printf("%ld compared %ld scaled %ld stops %ld flagged %ld bad\n", compared, scaled, stops,
         flagged, bad);
  return bad == 0 ? 0 : 1;
}
"""


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (install gcc or clang)")
def test_newton_stop_has_no_flag_and_the_plain_decision(tmp_path):
    hard = hard_case("first-order")
    prefix = hard.prefix
    files = hard.files("single")
    assert f"static int {prefix}_newton_stop(".encode() in files[f"{prefix}.c"]
    folder = write(tmp_path, {k: v for k, v in files.items() if k in (f"{prefix}.c",
                                                                       f"{prefix}.h")})
    (folder / "driver.c").write_text(DRIVER.replace("PREFIX", prefix))
    exe = folder / "driver"
    build = subprocess.run([COMPILERS[0], "-std=c99", "-O2", "-ffp-contract=off",
                            "-frounding-math", "driver.c", "-o", str(exe), "-lm"],
                           cwd=folder, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-3000:]
    counts = dict((name, int(n)) for n, name in
                  re.findall(r"(\d+) (compared|scaled|stops|flagged|bad)", run.stdout))
    assert counts["bad"] == 0
    # the samples reach every outcome: plain decisions both ways, in the scaled range,
    # and plain products that underflow or overflow
    assert counts["scaled"] > 10000, run.stdout
    assert 0 < counts["stops"] < counts["compared"], run.stdout
    assert counts["flagged"] > 10000, run.stdout
