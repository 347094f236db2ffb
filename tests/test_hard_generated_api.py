"""Hostile inputs to the generated C and Python APIs of every controller variant.

Every API function the header declares (``P_tube``, ``P_alpha_step``, ``P_step`` and the
variant's own: ``P_control`` of the first order, ``P_virtual_velocity`` of the cascade) of
one bundled case per variant (:mod:`hard_helpers`), double and single, is called with
NaN, infinities, huge and tiny values, states whose tube point is inside, exactly on and
outside the tube, ``t < 0`` and far past ``t_c``, ``dt <= 0``, too small and too large,
at the period and off it (every row at ``dt = PERIOD`` and at ``1.5 PERIOD``: the step's
OFF_PERIOD), ``alpha`` negative and beyond ``ALPHA_MAX``, NULL pointers and in-place
updates. The C
driver is built with ``-fsanitize=address,undefined -fno-sanitize-recover=all`` by gcc
and clang and must run clean. Checked: the status is the documented one (the input domain
of the header), every number written is finite (outputs are pre-filled with NaN, so an
output left unwritten fails too), INVALID_INPUT leaves ``alpha_next = alpha`` (non-finite
entries 0) and every other output 0, every status of the header is reached, and the
Python module returns the same statuses and (double) the same outputs. The number of
hostile inputs per variant is printed (``-s``) and asserted by
:func:`test_hostile_input_counts`.
"""

from __future__ import annotations

import itertools
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hard_helpers import OPTIONAL_OUTPUTS, hard_case, variant_params

from stt_codegen.tube import reference as R

SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
FLAGS = ["-std=c99", "-O1", "-g", "-ffp-contract=off", "-Wall", "-Wextra", "-Werror",
         "-fno-omit-frame-pointer"]
#: The inputs of an API function, by parameter name, and the row entry that feeds it.
INPUTS = {"x": 0, "t": 1, "dt": 2, "alpha": 3}


def _compilers() -> list[str]:
    return [cc for cc in ("gcc", "clang") if shutil.which(cc)]


def hostile_inputs(case) -> list[tuple]:
    """``(x (N_STATE,), t, dt, alpha (N_ALPHA,))`` rows, deterministic."""
    design, m = case.tube, case.macros
    n_alpha, n_state, t_c = case.size("N_ALPHA"), case.size("N_STATE"), design.prescribed_time
    nan, inf = math.nan, math.inf
    times = [0.0, -0.0, 1e-300, 0.5 * t_c, t_c * (1 - 1e-12), t_c, t_c * (1 + 1e-12),
             10 * t_c, 1e30, 1e300, -1e-300, -1.0, -1e300, nan, inf, -inf]
    steps = [1.0 / design.rate_hz, m["DT_MIN"], m["DT_MIN"] * 0.999,
             m["DT_MAX"], m["DT_MAX"] * 1.001, 0.0, -0.0, -1e-3, 5e-324, 1e300, nan, inf]
    rows = []
    for t in times:
        t_eval = min(max(t, 0.0), 1e6) if math.isfinite(t) else 0.0
        psi = R.conflict_distance(design, np.array([t_eval]))[0]
        alpha0 = np.maximum(0.0, -psi + 1e-2)
        g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t_eval]), alpha0[None, :])
        g_l, g_u = g_l[0], g_u[0]
        centre = case.state_at((g_l + g_u) / 2)
        states = [centre, case.state_at(g_u), case.state_at(g_l),
                  case.state_at(np.nextafter(g_u, -inf)), case.state_at(g_u + (g_u - g_l)),
                  case.state_at((g_l + g_u) / 2 + 1e300), case.state_at((g_l + g_u) / 2 - 1e300),
                  np.full(n_state, 1.7e308), np.array([nan] + list(centre[1:])),
                  np.array([inf] + list(centre[1:])), *case.extra_states((g_l + g_u) / 2)]
        if "INPUT_CLAMPED" in case.statuses:     # an actuator bound: law (13) asks for more
            states += [case.state_at(g_u - (g_u - g_l) * 1e-3),
                       case.state_at(g_l + (g_u - g_l) * 1e-3)]
        alphas = [alpha0, np.zeros(n_alpha), alpha0 + 1e3, np.full(n_alpha, m["ALPHA_MAX"]),
                  np.full(n_alpha, m["ALPHA_MAX"] * 1.5), -alpha0 - 1e-3,
                  np.array([-0.0] * n_alpha), np.array([nan] + list(alpha0[1:])),
                  np.array([1e300] * n_alpha), np.array([-inf] + list(alpha0[1:]))]
        for x, dt, a in itertools.product(states, steps, alphas):
            rows.append((np.asarray(x, float), t, dt, np.asarray(a, float)))
    rng = np.random.default_rng(7)
    keep = rng.random(len(rows)) < 0.25          # a fixed quarter of the product
    keep[:200] = True
    chosen = [r for r, k in zip(rows, keep) if k]
    # the step's period check: every row at dt = PERIOD (OK and INPUT_CLAMPED are the
    # step's only there) and each again at 1.5 PERIOD (OFF_PERIOD), not a quarter of them
    period = 1.0 / design.rate_hz
    chosen += [r for r, k in zip(rows, keep) if not k and r[2] == period]
    chosen += [(x, t, 1.5 * period, a) for x, t, dt, a in rows if dt == period]
    return chosen


def in_domain(case, x, t, dt, alpha, names) -> bool:
    """Whether the inputs a function takes (``names``) lie in the header's input domain."""
    m = case.macros
    ok = math.isfinite(t) and t >= 0 and all(0 <= a <= m["ALPHA_MAX"] for a in alpha)
    if "dt" in names:
        ok = ok and m["DT_MIN"] <= dt <= m["DT_MAX"]
    if "x" in names:
        ok = ok and all(math.isfinite(v) for v in x)
    return ok


def _hex(v: float) -> str:
    return float(v).hex() if math.isfinite(v) else ("NAN" if math.isnan(v) else
                                                    ("INFINITY" if v > 0 else "-INFINITY"))


def _call(prefix: str, name: str, args, given: dict) -> str:
    """The C call of ``P_name`` with each parameter taken from ``given`` (by name)."""
    return f"{prefix}_{name}(" + ", ".join(given[a.name] for a in args) + ")"


def driver_source(case, rows, single: bool) -> str:
    """A C program calling every API function on every row and printing the results (%a).

    Lines ``name k status values...``: each function (outputs pre-filled with NaN, printed
    in parameter order), ``tube_nodot`` (the optional outputs NULL), ``step_inplace``
    (``alpha_next == alpha``, prints alpha); then ``null name:param status`` for every
    required pointer passed as NULL.
    """
    prefix, up = case.prefix, case.prefix.upper()
    real = "float" if single else "double"
    cast = "(float)" if single else ""
    functions = case.functions

    def lit(v):
        return f"{cast}({_hex(v)})"

    xs = ",\n".join("{" + ", ".join(lit(v) for v in r[0]) + "}" for r in rows)
    ts = ", ".join(lit(r[1]) for r in rows)
    dts = ", ".join(lit(r[2]) for r in rows)
    als = ",\n".join("{" + ", ".join(lit(v) for v in r[3]) + "}" for r in rows)
    inputs = {"x": "X[k]", "t": "T[k]", "dt": "DT[k]", "alpha": "A[k]"}
    body = []
    for name, args in functions.items():
        outs = [a for a in args if a.kind == "out"]
        body.append("  {")
        body += [f"    {real} {a.name}[{up}_{a.size}];" for a in outs]
        body.append("    int s;")
        body += [f"    fill({a.name}, {up}_{a.size});" for a in outs]
        given = {**inputs, **{a.name: a.name for a in outs}}
        body.append(f"    s = {_call(prefix, name, args, given)};")
        body.append(f'    printf("{name} %d %d", k, s);')
        body += [f"    show({a.name}, {up}_{a.size});" for a in outs]
        body.append('    printf("\\n");')
        if name == "tube":
            given = {**inputs, **{a.name: "NULL" if a.name in OPTIONAL_OUTPUTS else a.name
                                  for a in outs}}
            body += [f"    fill({a.name}, {up}_{a.size});" for a in outs]
            body.append(f"    s = {_call(prefix, name, args, given)};")
            body.append('    printf("tube_nodot %d %d", k, s);')
            body += [f"    show({a.name}, {up}_{a.size});" for a in outs
                     if a.name not in OPTIONAL_OUTPUTS]
            body.append('    printf("\\n");')
        if name == "step":                 # in place: alpha_next == alpha
            body.append(f"    {{ {real} a[{up}_N_ALPHA]; int i;")
            body.append(f"      for (i = 0; i < {up}_N_ALPHA; ++i) a[i] = A[k][i];")
            body += [f"      fill({a.name}, {up}_{a.size});" for a in outs
                     if a.name != "alpha_next"]
            given = {**inputs, **{a.name: a.name for a in outs}, "alpha": "a",
                     "alpha_next": "a"}
            body.append(f"      s = {_call(prefix, name, args, given)};")
            body.append('      printf("step_inplace %d %d", k, s);')
            body.append(f'      show(a, {up}_N_ALPHA); printf("\\n"); }}')
        body.append("  }")
    nulls = []
    for name, args in functions.items():
        given = {"x": "X[0]", "t": "(" + real + ")1", "dt": "DT[0]", "alpha": "A[0]",
                 **{a.name: a.name for a in args if a.kind == "out"}}
        for a in args:
            if a.kind != "scalar" and a.name not in OPTIONAL_OUTPUTS:
                call = _call(prefix, name, args, {**given, a.name: "NULL"})
                nulls.append(f'    printf("null {name}:{a.name} %d\\n", {call});')
    buffers = "".join(f"    {real} {a.name}[{up}_{a.size}];\n"
                      for a in {a.name: a for args in functions.values() for a in args
                                if a.kind == "out"}.values())
    return f"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "{prefix}.h"
#define NR {len(rows)}
static const {real} X[NR][{up}_N_STATE] = {{{xs}}};
static const {real} T[NR] = {{{ts}}};
static const {real} DT[NR] = {{{dts}}};
static const {real} A[NR][{up}_N_ALPHA] = {{{als}}};
static void fill({real}* v, int n) {{ int i; for (i = 0; i < n; ++i) v[i] = ({real})NAN; }}
static void show(const {real}* v, int n) {{
  int i;
  for (i = 0; i < n; ++i) printf(" %a", (double)v[i]);
}}
int main(void) {{
  int k;
  for (k = 0; k < NR; ++k) {{
{chr(10).join(body)}
  }}
  /* NULL pointers: no crash, documented status */
  {{
{buffers}{chr(10).join(nulls)}
  }}
  return 0;
}}
"""


def _parse(text: str) -> dict:
    results = {}
    for line in text.splitlines():
        parts = line.split()
        if parts[0] == "null":
            results[("null", parts[1])] = int(parts[2])
            continue
        results[(parts[0], int(parts[1]))] = (int(parts[2]), [float.fromhex(p) if "0x" in p
                                                              else float(p) for p in parts[3:]])
    return results


def _run_c(tmp_path, case, rows, precision, cc):
    files = case.files(precision)
    prefix = case.prefix
    for name in (f"{prefix}.c", f"{prefix}.h"):
        (tmp_path / name).write_bytes(files[name])
    single = precision == "single"
    with np.errstate(over="ignore"):     # 1e300 becomes inf in float32: still hostile
        cast_rows = [(np.float32(r[0]).astype(float), float(np.float32(r[1])),
                      float(np.float32(r[2])), np.float32(r[3]).astype(float))
                     if single else r for r in rows]
    (tmp_path / "driver.c").write_text(driver_source(case, cast_rows, single))
    exe = tmp_path / "driver"
    build = subprocess.run([cc, *FLAGS, *SANITIZE, "driver.c",
                            f"{prefix}.c", "-o", str(exe), "-lm"],
                           cwd=tmp_path, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and "runtime error" not in run.stderr \
        and "AddressSanitizer" not in run.stderr, run.stderr[-3000:]
    return cast_rows, _parse(run.stdout)


def _check(case, rows, results, python=None):
    """Every result of the driver against the header's promises; the statuses counted."""
    st = case.statuses
    ok, invalid = st["OK"], st["INVALID_INPUT"]
    functions = case.functions
    checked = dict.fromkeys(st.values(), 0)
    for k, (x, t, dt, alpha) in enumerate(rows):
        keep = [a if math.isfinite(a) else 0.0 for a in alpha]
        for fn in [*functions, "tube_nodot"]:
            args = functions["tube" if fn == "tube_nodot" else fn]
            names = {a.name for a in args}
            status, values = results[(fn, k)]
            assert all(math.isfinite(v) for v in values), (fn, k, status, values)
            valid = in_domain(case, x, t, dt, alpha, names)
            if not valid:
                assert status == invalid, (fn, k, x, t, dt, alpha, status)
            else:
                assert status != invalid or fn.startswith("tube"), (fn, k, x, t, dt, alpha)
            checked[status] += 1
            if status == invalid:
                expected = []
                for a in args:
                    if a.kind == "out" and not (fn == "tube_nodot" and a.name in OPTIONAL_OUTPUTS):
                        expected += keep if a.name == "alpha_next" else [0.0] * case.size(a.size)
                assert values == expected, (fn, k, values)
            if "x" not in names:           # no state: the tube and alpha_step
                assert status in (ok, invalid), (fn, k, status)
        s_step, v_step = results[("step", k)]
        s_inplace, v_inplace = results[("step_inplace", k)]
        assert s_inplace == s_step and v_inplace == v_step[case.size("N_INPUT"):], k
        if python is not None:
            _compare_python(python, case, k, x, t, dt, alpha, results)
    nulls = {key: v for key, v in results.items() if key[0] == "null"}
    assert len(nulls) >= 2 * len(functions)          # every function has two pointers at least
    assert set(nulls.values()) == {invalid}, nulls
    return checked


def _compare_python(mod, case, k, x, t, dt, alpha, results):
    """Every API function the Python module also has: same status, same outputs."""
    row = {"x": list(x), "t": t, "dt": dt, "alpha": list(alpha)}
    compared = 0
    for fn, args in case.functions.items():
        if not hasattr(mod, fn):
            continue
        value = getattr(mod, fn)(*[row[a.name] for a in args if a.kind != "out"])
        status = value[-1]
        flat = [v for part in value[:-1] for v in part]
        c_status, c_values = results[(fn, k)]
        assert status == c_status, (fn, k, x, t, dt, alpha, status, c_status)
        assert all(isinstance(v, float) and math.isfinite(v) for v in flat)
        np.testing.assert_allclose(flat, c_values, rtol=1e-9, atol=1e-12,
                                   err_msg=f"{fn} row {k}")
        compared += 1
    assert compared >= 1          # step at least


@pytest.fixture(scope="module", params=variant_params(fast=()))
def variant_case(request):
    case = hard_case(request.param)
    return case, hostile_inputs(case)


def _pairs():
    """Every (variant, precision, compiler), in the slow tier: one pair builds a hostile
    harness and runs it under the sanitizers for about 14 s."""
    return [pytest.param(variant, p, cc, id=f"{variant}-{p}-{cc}", marks=pytest.mark.slow)
            for variant in ("first-order", "cascade", "look-ahead")
            for p, cc in itertools.product(("double", "single"), _compilers())]


@pytest.mark.parametrize("variant, precision, cc", _pairs())
def test_c_api_hostile_inputs_sanitized(tmp_path, variant, cc, precision):
    case = hard_case(variant)
    python = case.python()
    rows, results = _run_c(tmp_path, case, hostile_inputs(case), precision, cc)
    checked = _check(case, rows, results, python if precision == "double" else None)
    assert min(checked.values()) > 50, checked      # every status is exercised
    if precision == "single":
        _compare_single_statuses(case, python, rows, results)


def _compare_single_statuses(case, python, rows, results):
    """Single vs the double Python module: same status wherever the status is certain
    (the tube point farther than 1e-3 of the half-width from each bound, in every
    dimension; the bounds are the single C's own)."""
    invalid, n = case.statuses["INVALID_INPUT"], case.n
    for k, (x, t, dt, alpha) in enumerate(rows):
        status, _ = results[("step", k)]
        p_status = python.step(list(x), t, dt, list(alpha))[2]
        if status == invalid or p_status == invalid:
            assert status == p_status, (k, x, t, dt, alpha)
            continue
        _, bounds = results[("tube", k)]
        g_l, g_u = np.array(bounds[:n]), np.array(bounds[n:2 * n])
        width = np.maximum(g_u - g_l, 1e-6)
        e = (2 * case.point_of(x) - (g_u + g_l)) / width
        if np.all(np.abs(np.abs(e) - 1) > 1e-3):
            assert status == p_status, (k, x, t, dt, alpha)


@pytest.mark.parametrize("variant", variant_params())
def test_python_module_rejects_non_numbers(variant):
    case = hard_case(variant)
    mod = case.python()
    n_state, n_alpha = case.size("N_STATE"), case.size("N_ALPHA")
    invalid = case.statuses["INVALID_INPUT"]
    good_x, good_a = [float(v) for v in case.state_at(np.full(case.n, 1.0))], [0.01] * n_alpha
    for x, t, dt, a in [(None, 1.0, 1e-3, good_a), (good_x, "1", 1e-3, good_a),
                        (good_x, 1.0, 1e-3, [10**400] * n_alpha),
                        (good_x[:-1], 1.0, 1e-3, good_a), (good_x, 1.0, [1e-3], good_a),
                        (good_x, 10**400, 1e-3, good_a), (good_x, 1.0, 1e-3, "abcdef"),
                        (["x"] * n_state, 1.0, 1e-3, good_a)]:
        u, nxt, status = mod.step(x, t, dt, a)
        assert status == invalid and u == [0.0] * case.size("N_INPUT") and len(nxt) == n_alpha
        assert all(math.isfinite(v) for v in nxt)


@pytest.mark.parametrize("variant", variant_params())
def test_hostile_input_counts(variant, capsys):
    """The counts docs/embedded.md gives: hostile rows, calls per row, NULL calls (its
    table of counts per variant must match)."""
    case = hard_case(variant)
    rows = hostile_inputs(case)
    calls = len(case.functions) + 2          # + tube_nodot, step_inplace
    nulls = sum(1 for args in case.functions.values() for a in args
                if a.kind != "scalar" and a.name not in {*OPTIONAL_OUTPUTS})
    name = Path(case.case).stem
    with capsys.disabled():
        print(f"\n{variant} ({name}): {len(rows)} hostile inputs x {calls} calls "
              f"= {len(rows) * calls} calls per precision and compiler, {nulls} NULL calls")
    assert len(rows) > 4000
    docs = (Path(__file__).parents[1] / "docs" / "embedded.md").read_text()
    line = [ln for ln in docs.splitlines() if ln.strip().startswith("|") and f"(`{name}`)" in ln]
    assert len(line) == 1, f"docs/embedded.md has no row of counts for {name}"
    cells = [c.strip().replace(",", "") for c in line[0].strip().strip("|").split("|")]
    assert cells[1:] == [str(len(rows)), str(calls), str(nulls)], (cells, "docs/embedded.md")
