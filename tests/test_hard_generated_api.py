"""Hostile inputs to the generated C and Python APIs.

Every public function (``P_tube``, ``P_control``, ``P_alpha_step``, ``P_step``) of a
bundled spec, double and single, is called with NaN, infinities, huge and tiny values,
states inside, exactly on and outside the tube, ``t < 0`` and far past ``t_c``,
``dt <= 0``, too small and too large, ``alpha`` negative and beyond ``ALPHA_MAX``, NULL
pointers and in-place updates. The C driver is built with
``-fsanitize=address,undefined -fno-sanitize-recover=all`` by gcc and clang and must
run clean. Checked: the status is the documented one (the input domain of the header),
every number written is finite (outputs are pre-filled with NaN, so an output left
unwritten fails too), INVALID_INPUT leaves ``u = 0``, ``alpha_next = alpha`` (non-finite
entries 0) and ``gamma_* = 0``, and the Python module returns the same statuses and
(double) the same outputs.
"""

from __future__ import annotations

import itertools
import math
import shutil
import subprocess

import numpy as np
import pytest

from conftest import designed
from stt_codegen.tube import reference as R
from stt_codegen.runtime.compiled import load_python_module
from stt_codegen.codegen.generate import generate_files, input_limits
from stt_codegen.codegen.options import Options

CASE = "omnirobot-s1"
OK, OUTSIDE, INVALID = 0, 1, 2
SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
FLAGS = ["-std=c99", "-O1", "-g", "-ffp-contract=off", "-Wall", "-Wextra", "-Werror",
         "-fno-omit-frame-pointer"]


def _compilers() -> list[str]:
    return [cc for cc in ("gcc", "clang") if shutil.which(cc)]


def hostile_inputs(design) -> list[tuple]:
    """``(x (n,), t, dt, alpha (2n,))`` rows, deterministic."""
    n, t_c = design.dimension, design.prescribed_time
    limits = input_limits(design)
    nan, inf = math.nan, math.inf
    times = [0.0, -0.0, 1e-300, 0.5 * t_c, t_c * (1 - 1e-12), t_c, t_c * (1 + 1e-12),
             10 * t_c, 1e30, 1e300, -1e-300, -1.0, -1e300, nan, inf, -inf]
    steps = [1.0 / design.rate_hz, limits["dt_min"], limits["dt_min"] * 0.999,
             limits["dt_max"], limits["dt_max"] * 1.001, 0.0, -0.0, -1e-3, 5e-324, 1e300,
             nan, inf]
    rows = []
    for t in times:
        t_eval = min(max(t, 0.0), 1e6) if math.isfinite(t) else 0.0
        psi = R.conflict_distance(design, np.array([t_eval]))[0]
        alpha0 = np.maximum(0.0, -psi + 1e-2)
        g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t_eval]), alpha0[None, :])
        g_l, g_u = g_l[0], g_u[0]
        centre = (g_l + g_u) / 2
        states = [centre, g_u.copy(), g_l.copy(), np.nextafter(g_u, -inf),
                  g_u + (g_u - g_l), centre + 1e300, centre - 1e300,
                  np.full(n, 1.7e308), np.array([nan] + list(centre[1:])),
                  np.array([inf] + list(centre[1:]))]
        alphas = [alpha0, np.zeros(n * 2), alpha0 + 1e3, np.full(2 * n, limits["alpha_max"]),
                  np.full(2 * n, limits["alpha_max"] * 1.5), -alpha0 - 1e-3,
                  np.array([-0.0] * 2 * n), np.array([nan] + list(alpha0[1:])),
                  np.array([1e300] * 2 * n), np.array([-inf] + list(alpha0[1:]))]
        for x, dt, a in itertools.product(states, steps[:4] + steps[4:], alphas):
            rows.append((np.asarray(x, float), t, dt, np.asarray(a, float)))
    rng = np.random.default_rng(7)
    keep = rng.random(len(rows)) < 0.25          # a fixed quarter of the product
    keep[:200] = True
    return [r for r, k in zip(rows, keep) if k]


def in_domain(design, x, t, dt, alpha, with_dt: bool, with_x: bool) -> bool:
    limits = input_limits(design)
    ok = math.isfinite(t) and t >= 0 and all(0 <= a <= limits["alpha_max"] for a in alpha)
    if with_dt:
        ok = ok and limits["dt_min"] <= dt <= limits["dt_max"]
    if with_x:
        ok = ok and all(math.isfinite(v) for v in x)
    return ok


def _hex(v: float) -> str:
    return float(v).hex() if math.isfinite(v) else ("NAN" if math.isnan(v) else
                                                    ("INFINITY" if v > 0 else "-INFINITY"))


def driver_source(prefix: str, rows, single: bool) -> str:
    """A C program calling every function on every row and printing the results (%a)."""
    up = prefix.upper()
    real = "float" if single else "double"
    cast = "(float)" if single else ""

    def lit(v):
        h = _hex(v)
        return f"{cast}({h})"

    xs = ",\n".join("{" + ", ".join(lit(v) for v in r[0]) + "}" for r in rows)
    ts = ", ".join(lit(r[1]) for r in rows)
    dts = ", ".join(lit(r[2]) for r in rows)
    als = ",\n".join("{" + ", ".join(lit(v) for v in r[3]) + "}" for r in rows)
    return f"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "{prefix}.h"
#define NR {len(rows)}
#define N {up}_N
#define NA {up}_N_ALPHA
static const {real} X[NR][N] = {{{xs}}};
static const {real} T[NR] = {{{ts}}};
static const {real} DT[NR] = {{{dts}}};
static const {real} A[NR][NA] = {{{als}}};
static void fill({real}* v, int n) {{ int i; for (i = 0; i < n; ++i) v[i] = ({real})NAN; }}
static void out(const char* what, int k, int status, const {real}* v, int n) {{
  int i;
  printf("%s %d %d", what, k, status);
  for (i = 0; i < n; ++i) printf(" %a", (double)v[i]);
  printf("\\n");
}}
int main(void) {{
  int k;
  for (k = 0; k < NR; ++k) {{
    {real} u[N], nx[NA], gl[N], gu[N], gld[N], gud[N], a[NA], buf[4 * N];
    int s, i;
    fill(u, N); fill(nx, NA);
    s = {prefix}_step(X[k], T[k], DT[k], A[k], u, nx);
    for (i = 0; i < N; ++i) buf[i] = u[i];
    for (i = 0; i < NA; ++i) buf[N + i] = nx[i];
    out("step", k, s, buf, N + NA);
    fill(u, N);
    s = {prefix}_control(X[k], T[k], A[k], u);
    out("control", k, s, u, N);
    fill(nx, NA);
    s = {prefix}_alpha_step(T[k], DT[k], A[k], nx);
    out("alpha_step", k, s, nx, NA);
    fill(gl, N); fill(gu, N); fill(gld, N); fill(gud, N);
    s = {prefix}_tube(T[k], A[k], gl, gu, gld, gud);
    for (i = 0; i < N; ++i) {{ buf[i] = gl[i]; buf[N + i] = gu[i]; buf[2 * N + i] = gld[i];
                               buf[3 * N + i] = gud[i]; }}
    out("tube", k, s, buf, 4 * N);
    fill(gl, N); fill(gu, N);
    s = {prefix}_tube(T[k], A[k], gl, gu, NULL, NULL);
    for (i = 0; i < N; ++i) {{ buf[i] = gl[i]; buf[N + i] = gu[i]; }}
    out("tube_nodot", k, s, buf, 2 * N);
    for (i = 0; i < NA; ++i) a[i] = A[k][i];          /* in place: alpha_next == alpha */
    fill(u, N);
    s = {prefix}_step(X[k], T[k], DT[k], a, u, a);
    out("step_inplace", k, s, a, NA);
  }}
  /* NULL pointers: no crash, documented status */
  {{
    {real} u[N], nx[NA], gl[N], gu[N];
    printf("null %d %d %d %d %d %d %d %d\\n",
      {prefix}_step(NULL, 1, 1e-3f, A[0], u, nx), {prefix}_step(X[0], 1, 1e-3f, NULL, u, nx),
      {prefix}_step(X[0], 1, 1e-3f, A[0], NULL, nx), {prefix}_step(X[0], 1, 1e-3f, A[0], u, NULL),
      {prefix}_control(NULL, 1, A[0], u), {prefix}_alpha_step(1, 1e-3f, NULL, nx),
      {prefix}_tube(1, NULL, gl, gu, NULL, NULL), {prefix}_tube(1, A[0], NULL, gu, NULL, NULL));
  }}
  return 0;
}}
"""


def _parse(text: str) -> dict:
    results = {}
    for line in text.splitlines():
        parts = line.split()
        if parts[0] == "null":
            results["null"] = [int(p) for p in parts[1:]]
            continue
        results[(parts[0], int(parts[1]))] = (int(parts[2]), [float.fromhex(p) if "0x" in p
                                                              else float(p) for p in parts[3:]])
    return results


@pytest.fixture(scope="module")
def setup():
    spec, design, _ = designed(CASE)
    return spec, design, hostile_inputs(design)


def _run_c(tmp_path, spec, design, rows, precision, cc):
    files = generate_files(spec, design, Options(("c",), precision))
    prefix = spec.c_name
    for name in (f"{prefix}.c", f"{prefix}.h"):
        (tmp_path / name).write_bytes(files[name])
    single = precision == "single"
    with np.errstate(over="ignore"):     # 1e300 becomes inf in float32: still hostile
        cast_rows = [(np.float32(r[0]).astype(float), float(np.float32(r[1])),
                      float(np.float32(r[2])), np.float32(r[3]).astype(float))
                     if single else r for r in rows]
    (tmp_path / "driver.c").write_text(driver_source(prefix, cast_rows, single))
    exe = tmp_path / "driver"
    build = subprocess.run([cc, *FLAGS, *SANITIZE, "driver.c", f"{prefix}.c", "-o", str(exe),
                            "-lm"], cwd=tmp_path, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and "runtime error" not in run.stderr \
        and "AddressSanitizer" not in run.stderr, run.stderr[-3000:]
    return cast_rows, _parse(run.stdout)


def _check(design, rows, results, python=None):
    n = design.dimension
    checked = {OK: 0, OUTSIDE: 0, INVALID: 0}
    for k, (x, t, dt, alpha) in enumerate(rows):
        keep = [a if math.isfinite(a) else 0.0 for a in alpha]
        for fn, with_dt, with_x in (("step", True, True), ("control", False, True),
                                    ("alpha_step", True, False), ("tube", False, False),
                                    ("tube_nodot", False, False)):
            status, values = results[(fn, k)]
            assert all(math.isfinite(v) for v in values), (fn, k, status, values)
            valid = in_domain(design, x, t, dt, alpha, with_dt, with_x)
            if not valid:
                assert status == INVALID, (fn, k, x, t, dt, alpha, status)
            else:
                assert status != INVALID or fn.startswith("tube"), (fn, k, x, t, dt, alpha)
            checked[status] += 1
            if status == INVALID:
                if fn == "step":
                    assert values[:n] == [0.0] * n and values[n:] == keep
                elif fn == "control":
                    assert values == [0.0] * n
                elif fn == "alpha_step":
                    assert values == keep
                else:
                    assert values == [0.0] * len(values)
            if fn in ("step", "control"):
                assert status in (OK, OUTSIDE, INVALID)
            else:
                assert status in (OK, INVALID)
        s_step, v_step = results[("step", k)]
        s_inplace, v_inplace = results[("step_inplace", k)]
        assert s_inplace == s_step and v_inplace == v_step[n:], k
        if python is not None:
            _compare_python(python, design, k, x, t, dt, alpha, results)
    assert results["null"] == [INVALID] * 8
    return checked


def _compare_python(mod, design, k, x, t, dt, alpha, results):
    n = design.dimension
    got = {"step": mod.step(list(x), t, dt, list(alpha)),
           "control": mod.control(list(x), t, list(alpha)),
           "alpha_step": mod.alpha_step(t, dt, list(alpha)),
           "tube": mod.tube(t, list(alpha))}
    for fn, value in got.items():
        status = value[-1]
        flat = [v for part in value[:-1] for v in part]
        c_status, c_values = results[(fn, k)]
        assert status == c_status, (fn, k, x, t, dt, alpha, status, c_status)
        assert all(isinstance(v, float) and math.isfinite(v) for v in flat)
        np.testing.assert_allclose(flat, c_values, rtol=1e-9, atol=1e-12,
                                   err_msg=f"{fn} row {k}")
    assert len(got["step"][0]) == n


#: Double with gcc and single with clang in the fast tier, the two other pairs in the slow one.
PAIRS = [pytest.param(p, cc, marks=() if (p, cc) in (("double", "gcc"), ("single", "clang"))
                      else pytest.mark.slow)
         for p in ("double", "single") for cc in _compilers()]


@pytest.mark.parametrize("precision, cc", PAIRS)
def test_c_api_hostile_inputs_sanitized(tmp_path, setup, cc, precision):
    spec, design, rows = setup
    files = generate_files(spec, design, Options(("python",), "double"))
    python = load_python_module(files[f"{spec.c_name}.py"], spec.c_name)
    rows, results = _run_c(tmp_path, spec, design, rows, precision, cc)
    checked = _check(design, rows, results, python if precision == "double" else None)
    assert min(checked.values()) > 50, checked      # every status is exercised
    if precision == "single":
        _compare_single_statuses(python, design, rows, results)


def _compare_single_statuses(python, design, rows, results):
    """Single vs the double Python module: same status wherever the status is certain."""
    for k, (x, t, dt, alpha) in enumerate(rows):
        status, values = results[("step", k)]
        p_status = python.step(list(x), t, dt, list(alpha))[2]
        if status == INVALID or p_status == INVALID:
            assert status == p_status, (k, x, t, dt, alpha)
            continue
        g_l, g_u, *_ = python.tube(t, list(alpha))
        width = np.maximum(np.array(g_u) - np.array(g_l), 1e-6)
        e = (2 * np.asarray(x) - (np.array(g_u) + np.array(g_l))) / width
        if np.all(np.abs(np.abs(e) - 1) > 1e-3):
            assert status == p_status, (k, x, t, dt, alpha)


def test_python_module_rejects_non_numbers(setup):
    spec, design, _ = setup
    files = generate_files(spec, design, Options(("python",), "double"))
    mod = load_python_module(files[f"{spec.c_name}.py"], spec.c_name)
    n = design.dimension
    good_x, good_a = [2.0, 4.7, 0.0], [0.01] * (2 * n)
    for x, t, dt, a in [(None, 1.0, 1e-3, good_a), (good_x, "1", 1e-3, good_a),
                        (good_x, 1.0, 1e-3, [10**400] * (2 * n)), (good_x[:2], 1.0, 1e-3, good_a),
                        (good_x, 1.0, [1e-3], good_a), (good_x, 10**400, 1e-3, good_a),
                        (good_x, 1.0, 1e-3, "abcdef"), (["x"] * n, 1.0, 1e-3, good_a)]:
        u, nxt, status = mod.step(x, t, dt, a)
        assert status == INVALID and u == [0.0] * n and len(nxt) == 2 * n
        assert all(math.isfinite(v) for v in nxt)
