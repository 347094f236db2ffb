"""A normal step raises no floating-point exception flag and leaves errno alone.

Every vector of the generated self-test (inside and outside the tube) goes through
``P_step``, ``P_control``, ``P_alpha_step`` and ``P_tube`` with the flags cleared and
``errno = 0`` before each call; afterwards ``fetestexcept(FE_OVERFLOW | FE_UNDERFLOW |
FE_INVALID | FE_DIVBYZERO)`` must be 0 and errno 0 (glibc's libm reports range errors
through both), in double and single precision.
"""

from __future__ import annotations

import subprocess

import pytest
from conftest import designed
from codegen_helpers import COMPILERS, files_of, write

DRIVER = r"""
#include <errno.h>
#include <fenv.h>
#include <stdio.h>
#define main selftest_main
#include "PREFIX_selftest.c"
#undef main

#define FLAGS (FE_OVERFLOW | FE_UNDERFLOW | FE_INVALID | FE_DIVBYZERO)

static int raised(const char* what, int k) {
  int f = fetestexcept(FLAGS);
  if (f != 0 || errno != 0) {
    printf("RAISED %s vector %d: flags %d errno %d\n", what, k, f, errno);
    return 1;
  }
  return 0;
}

int main(void) {
  int k, bad = 0;
  for (k = 0; k < NV; ++k) {
    PREFIX_real u[UPREFIX_N], next[UPREFIX_N_ALPHA], gl[UPREFIX_N], gu[UPREFIX_N];
    PREFIX_real gld[UPREFIX_N], gud[UPREFIX_N];
    feclearexcept(FE_ALL_EXCEPT); errno = 0;
    (void)PREFIX_step(IN_X[k], IN_T[k], IN_DT[k], IN_ALPHA[k], u, next);
    bad += raised("step", k);
    feclearexcept(FE_ALL_EXCEPT); errno = 0;
    (void)PREFIX_control(IN_X[k], IN_T[k], IN_ALPHA[k], u);
    bad += raised("control", k);
    feclearexcept(FE_ALL_EXCEPT); errno = 0;
    (void)PREFIX_alpha_step(IN_T[k], IN_DT[k], IN_ALPHA[k], next);
    bad += raised("alpha_step", k);
    feclearexcept(FE_ALL_EXCEPT); errno = 0;
    (void)PREFIX_tube(IN_T[k], IN_ALPHA[k], gl, gu, gld, gud);
    bad += raised("tube", k);
  }
  printf("%d vectors, %d calls raised\n", NV, bad);
  return bad == 0 ? 0 : 1;
}
"""


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (install gcc or clang)")
@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("case", ["omnirobot-s1", "omnirobot-s2"])
def test_no_flag_and_no_errno_on_normal_steps(case, precision, tmp_path):
    spec, _, _ = designed(case)
    prefix = spec.c_name
    folder = write(tmp_path, files_of(case, precision))
    driver = DRIVER.replace("UPREFIX", prefix.upper()).replace("PREFIX", prefix)
    (folder / "driver.c").write_text(driver)
    exe = folder / "driver"
    build = subprocess.run([COMPILERS[0], "-std=c99", "-O2", "-ffp-contract=off",
                            "-frounding-math", "driver.c", f"{prefix}.c", "-o", str(exe), "-lm"],
                           cwd=folder, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-3000:]
    assert run.stdout.strip().endswith("calls raised"), run.stdout[-500:]
