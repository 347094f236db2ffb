"""The single-precision exp and log of the generated C (``stt_expf``, ``stt_logf``,
codegen/emit/c_maths.py).

Compiled with the host C compiler (strict warnings, ``-ffp-contract=off``) and called
through ctypes on float32 arrays:

* on a sample of every float of ``[-80, 80]`` (every 499th bit pattern, about 4.5
  million floats, plus the point of the largest error of the exhaustive sweep and the
  points where ``round(x / ln 2)`` changes) the error against ``exp`` in double is
  below the documented 0.8904 ulp;
* it does not decrease across the points where ``round(x / ln 2)`` changes (64 floats
  each side);
* outside the fast path (``|x| > 80``, infinities, NaN) it returns the C library's
  ``expf`` bit for bit, and below ``2^-28`` ``1 + x``, also the C library's value;
* no float of the sample (subnormals included) raises a floating-point exception flag but
  ``FE_INEXACT`` or sets ``errno``;
* the pieces' exponent clamp lies inside the fast path, so every exp of a deployed step
  takes it.
The exhaustive sweep over all 2.2e9 floats of ``[-80, 80]`` (``exhaustive_sweep_source``,
about a minute) is run by hand; its result is the documented bound (and monotonicity on
the whole domain).

``stt_logf``: below the documented ``LOG_BOUND_ULP`` (0.84 ulp) and monotone on every 17th
float of its fast path ``[2^-8, 2^8]`` (7.9 million) and around every point where its
reduction changes ``k``; exactly 0 at 1; no flag but ``FE_INEXACT`` and no ``errno``; the
C library's ``logf`` bit for bit elsewhere; the bound within what the error analysis
assumes for a ``log``. The exhaustive sweep of the fast path (``log_sweep_source``, a few
seconds) runs in the slow tier.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

from stt_codegen.codegen.emit import CPrinter, c_maths
from stt_codegen.tube import pieces

CC = shutil.which("gcc") or shutil.which("clang")
STRICT = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow",
          "-Wconversion", "-Wdouble-promotion", "-Wcast-qual", "-Wstrict-prototypes",
          "-Wmissing-prototypes", "-Werror"]
#: The largest error of the exhaustive sweep (0.8903 ulp at x = 0x1.2067a6p+2), rounded up.
BOUND_ULP = 0.8904
WORST_X = float.fromhex("0x1.2067a6p+2")

DRIVER = r"""
#include <errno.h>
#include <fenv.h>
#include <math.h>
#include <stddef.h>

%s
void many(const float* x, float* y, float* libm, size_t count, int* flags, int* err);
void many(const float* x, float* y, float* libm, size_t count, int* flags, int* err) {
  size_t i;
  errno = 0;
  feclearexcept(FE_ALL_EXCEPT);
  for (i = 0; i < count; ++i) {
    y[i] = stt_expf(x[i]);
  }
  *flags = fetestexcept(FE_OVERFLOW | FE_UNDERFLOW | FE_INVALID | FE_DIVBYZERO);
  *err = errno;
  for (i = 0; i < count; ++i) {
    libm[i] = expf(x[i]);
  }
}
"""


@pytest.fixture(scope="module")
def stt_expf(tmp_path_factory):
    if CC is None:
        pytest.skip("no C compiler (gcc or clang)")
    tmp = tmp_path_factory.mktemp("c_maths")
    src = tmp / "expf.c"
    src.write_text(DRIVER % c_maths.expf_source())
    lib = tmp / "libexpf.so"
    proc = subprocess.run([CC, *STRICT, "-fPIC", "-shared", str(src), "-o", str(lib), "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    dll = ctypes.CDLL(str(lib))

    def call(x):
        x = np.ascontiguousarray(x, dtype=np.float32)
        y, libm = np.empty_like(x), np.empty_like(x)
        flags, err = ctypes.c_int(-1), ctypes.c_int(-1)
        dll.many(ctypes.c_void_p(x.ctypes.data), ctypes.c_void_p(y.ctypes.data),
                 ctypes.c_void_p(libm.ctypes.data), ctypes.c_size_t(x.size),
                 ctypes.byref(flags), ctypes.byref(err))
        return y, libm, flags.value, err.value

    return call


def _sample() -> np.ndarray:
    top = int(np.array([80.0], dtype=np.float32).view(np.uint32)[0])
    bits = np.arange(0, top + 1, 499, dtype=np.uint32)
    positive = np.concatenate([bits.view(np.float32), np.float32([80.0, WORST_X])])
    # where k = round(x / ln 2) changes: (j + 1/2) ln 2 and its float neighbours
    edges = np.float32((np.arange(-115, 116) + 0.5) * np.log(2.0))
    near = np.concatenate([np.nextafter(edges, np.float32(-np.inf)), edges,
                           np.nextafter(edges, np.float32(np.inf))])
    near = near[np.abs(near) <= 80.0]
    return np.concatenate([positive, -positive, near])


def _ulp_error(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    exact = np.exp(x.astype(np.float64))
    ulp = np.ldexp(1.0, np.frexp(exact)[1] - 24)
    return np.abs(y.astype(np.float64) - exact) / ulp


def test_error_below_the_documented_bound(stt_expf):
    x = _sample()
    y, _, _, _ = stt_expf(x)
    err = _ulp_error(y, x)
    assert err.max() < BOUND_ULP, (err.max(), x[np.argmax(err)])
    assert err.max() > 0.5  # not correctly rounded: the bound is not vacuous
    # the largest error of the exhaustive sweep is in the sample
    assert err[np.nonzero(x == np.float32(WORST_X))[0][0]] > 0.89


def test_monotone_where_the_reduction_switches(stt_expf):
    # 64 consecutive floats on each side of every point where k = round(x / ln 2) changes
    for edge in np.float32((np.arange(-115, 116) + 0.5) * np.log(2.0)):
        if abs(edge) > 80.0:
            continue
        below = [edge]
        for _ in range(64):
            below.append(np.nextafter(below[-1], np.float32(-np.inf)))
        above = [edge]
        for _ in range(64):
            above.append(np.nextafter(above[-1], np.float32(np.inf)))
        x = np.float32(below[::-1] + above[1:])
        y, _, _, _ = stt_expf(x)
        assert np.all(np.diff(y.astype(np.float64)) >= 0.0), edge


def test_no_flag_and_no_errno_on_the_clamped_domain(stt_expf):
    x = _sample()
    _, _, flags, err = stt_expf(x)
    assert flags == 0 and err == 0


@pytest.mark.parametrize("values", [
    [80.00001, -80.00001, 88.7, -88.7, 100.0, -104.0, 1e30, -1e30],
    [np.inf, -np.inf, np.nan],
    # below 2^-28: 1 + x, which is also the C library's value
    [0.0, -0.0, 1e-30, -1e-30, 1e-40, 2.0 ** -29, -(2.0 ** -29), 2.0 ** -28 * 0.999],
])
def test_outside_the_fast_path_is_the_c_library(stt_expf, values):
    x = np.float32(values)
    y, libm, _, _ = stt_expf(x)
    assert np.array_equal(y.view(np.uint32), libm.view(np.uint32))


def test_the_pieces_clamp_lies_in_the_fast_path():
    assert pieces.EXP_ARGUMENT_BOUND <= c_maths.FAST_BOUND
    # |k| stays within the table: round(80 / ln 2) + 1
    assert c_maths.K_MAX >= round(c_maths.FAST_BOUND / np.log(2.0)) + 1


def test_constants_are_float32_numbers():
    for value in (c_maths.LOG2E, c_maths.LN2_HI, c_maths.LN2_LO, *c_maths.EXP_COEFFICIENTS):
        assert float(np.float32(value)) == value
    # k ln2_hi is exact for |k| <= 128: ln2_hi has at most 16 significant bits
    mantissa = int(np.float32(c_maths.LN2_HI).view(np.uint32)) & 0x7FFFFF
    assert mantissa & 0xFF == 0


def test_only_single_precision_defines_it():
    import casadi as ca
    x = ca.SX.sym("x")
    fn = ca.Function("f", [x], [ca.exp(x)])
    assert "stt_expf(w0)" in CPrinter("single").doprint(fn)
    double = CPrinter("double").doprint(fn)
    assert "stt_expf" not in double and "exp(w0)" in double
    # not defined when not used
    assert "stt_expf" not in CPrinter("single").doprint(ca.Function("g", [x], [ca.log(x)]))


# ----------------------------------------------------------------------------- stt_logf

LOG_DRIVER = r"""
#include <errno.h>
#include <fenv.h>
#include <math.h>
#include <stddef.h>

%s
void many(const float* x, float* y, float* libm, size_t count, int* flags, int* err);
void many(const float* x, float* y, float* libm, size_t count, int* flags, int* err) {
  size_t i;
  errno = 0;
  feclearexcept(FE_ALL_EXCEPT);
  for (i = 0; i < count; ++i) {
    y[i] = stt_logf(x[i]);
  }
  *flags = fetestexcept(FE_OVERFLOW | FE_UNDERFLOW | FE_INVALID | FE_DIVBYZERO);
  *err = errno;
  for (i = 0; i < count; ++i) {
    libm[i] = logf(x[i]);
  }
}
"""
#: The largest error of the exhaustive sweep of the fast path (0.8399 ulp).
LOG_WORST_X = float.fromhex("0x1.69cf3ep+0")


@pytest.fixture(scope="module")
def stt_logf(tmp_path_factory):
    if CC is None:
        pytest.skip("no C compiler (gcc or clang)")
    tmp = tmp_path_factory.mktemp("c_maths_log")
    src = tmp / "logf.c"
    src.write_text(LOG_DRIVER % c_maths.logf_source())
    lib = tmp / "liblogf.so"
    proc = subprocess.run([CC, *STRICT, "-fPIC", "-shared", str(src), "-o", str(lib), "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    dll = ctypes.CDLL(str(lib))

    def call(x):
        x = np.ascontiguousarray(x, dtype=np.float32)
        y, libm = np.empty_like(x), np.empty_like(x)
        flags, err = ctypes.c_int(-1), ctypes.c_int(-1)
        dll.many(ctypes.c_void_p(x.ctypes.data), ctypes.c_void_p(y.ctypes.data),
                 ctypes.c_void_p(libm.ctypes.data), ctypes.c_size_t(x.size),
                 ctypes.byref(flags), ctypes.byref(err))
        return y, libm, flags.value, err.value

    return call


def _log_sample() -> np.ndarray:
    """Every 17th float of the fast path, its ends, the sweep's worst point and the floats
    around every point where the reduction's k changes (sqrt 2 times a power of two)."""
    low, high = np.float32([c_maths.LOG_FAST_LOW, c_maths.LOG_FAST_HIGH]).view(np.uint32)
    bits = np.arange(low, high + 1, 17, dtype=np.uint32)
    edges = np.float32(np.sqrt(2.0) * 2.0 ** np.arange(-9, 8))
    near = [edges]
    for _ in range(8):
        near.append(np.nextafter(near[-1], np.float32(np.inf)))
        near.insert(0, np.nextafter(near[0], np.float32(-np.inf)))
    x = np.concatenate([bits.view(np.float32), np.concatenate(near),
                        np.float32([c_maths.LOG_FAST_LOW, c_maths.LOG_FAST_HIGH, LOG_WORST_X, 1.0])])
    x = x[(x >= c_maths.LOG_FAST_LOW) & (x <= c_maths.LOG_FAST_HIGH)]
    return np.unique(x)


def _log_ulp_error(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    exact = np.log(x.astype(np.float64))
    ulp = np.ldexp(1.0, np.frexp(exact)[1] - 24)
    err = np.abs(y.astype(np.float64) - exact) / ulp
    return np.where(exact == 0.0, np.where(y == 0.0, 0.0, np.inf), err)


def test_logf_error_below_the_documented_bound(stt_logf):
    x = _log_sample()
    y, _, _, _ = stt_logf(x)
    err = _log_ulp_error(y, x)
    assert err.max() < c_maths.LOG_BOUND_ULP, (err.max(), x[np.argmax(err)])
    assert err.max() > 0.5  # not correctly rounded: the bound is not vacuous
    assert err[np.nonzero(x == np.float32(LOG_WORST_X))[0][0]] > 0.83
    one = y[np.nonzero(x == 1.0)[0][0]]
    assert one == 0.0 and not np.signbit(one)              # ln 1 = +0 exactly


def test_logf_is_monotone_on_the_sample(stt_logf):
    x = _log_sample()
    y, _, _, _ = stt_logf(x)
    assert np.all(np.diff(y.astype(np.float64)) >= 0.0)


def test_logf_no_flag_and_no_errno_on_the_fast_path(stt_logf):
    _, _, flags, err = stt_logf(_log_sample())
    assert flags == 0 and err == 0


@pytest.mark.parametrize("values", [
    [np.nextafter(np.float32(c_maths.LOG_FAST_LOW), np.float32(0.0)),
     np.nextafter(np.float32(c_maths.LOG_FAST_HIGH), np.float32(np.inf)), 1e-30, 1e-40, 1e30,
     3.0e38],
    [0.0, -0.0, -1.0, -1e-30, np.inf, -np.inf, np.nan],
])
def test_logf_outside_the_fast_path_is_the_c_library(stt_logf, values):
    x = np.float32(values)
    y, libm, _, _ = stt_logf(x)
    assert np.array_equal(y, libm, equal_nan=True)
    assert np.array_equal(y[~np.isnan(y)].view(np.uint32), libm[~np.isnan(libm)].view(np.uint32))


def test_logf_bound_is_within_what_the_error_analysis_assumes():
    from stt_codegen.codegen import tolerance
    assert c_maths.LOG_BOUND_ULP <= tolerance.LOG_ERROR_ULP
    # |k| <= LOG_K_MAX on the fast path, so k ln2_hi (16 significant bits) is exact
    assert c_maths.LOG_FAST_HIGH == 2.0 ** c_maths.LOG_K_MAX == 1.0 / c_maths.LOG_FAST_LOW
    for value in (c_maths.SQRT2, c_maths.SQRT1_2, *c_maths.LOG_COEFFICIENTS):
        assert float(np.float32(value)) == value


@pytest.mark.slow
def test_logf_exhaustive_sweep_of_the_fast_path(tmp_path):
    """Every float of ``[2^-8, 2^8]``: the documented bound and monotonicity."""
    if CC is None:
        pytest.skip("no C compiler (gcc or clang)")
    src = tmp_path / "sweep.c"
    src.write_text(c_maths.log_sweep_source())
    exe = tmp_path / "sweep"
    subprocess.run([CC, "-O2", "-std=c99", "-ffp-contract=off", str(src), "-o", str(exe), "-lm"],
                   check=True)
    proc = subprocess.run([str(exe)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout
    assert "134217729 floats" in proc.stdout and "0 decreasing" in proc.stdout


def test_only_single_precision_defines_stt_logf():
    import casadi as ca
    x = ca.SX.sym("x")
    fn = ca.Function("f", [x], [ca.log(x)])
    single = CPrinter("single").doprint(fn)
    assert "stt_logf(w0)" in single and "static float stt_logf(float x)" in single
    double = CPrinter("double").doprint(fn)
    assert "stt_logf" not in double and "log(w0)" in double
    assert "stt_logf" not in CPrinter("single").doprint(ca.Function("g", [x], [ca.exp(x)]))
