"""The C printer: same instruction stream as the Python printer, real type a parameter.

Double precision, compiled with ``-ffp-contract=off`` against the system libm, is
bit-identical to CasADi's evaluation on DM on finite inputs (NaN inputs are excluded: the
printer's comparisons for fmin/fmax differ from C's fmin on a NaN first operand, a case
the deployed controller rules out by its input checks). Single precision calls the float
maths functions only and compiles without a warning under -Wconversion -Wdouble-promotion.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest
import sympy

from stt_codegen.codegen.emit import CPrinter, UnsupportedOperation, c_source, lower
from stt_codegen.codegen.emit import sympy_expressions
from test_emit_cases import CASES
from test_emit_python import casadi_dense, same_double

CC = shutil.which("gcc") or shutil.which("clang")
STRICT = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow",
          "-Wconversion", "-Wdouble-promotion", "-Wcast-qual", "-Wstrict-prototypes",
          "-Wmissing-prototypes", "-Werror"]
PRINTABLE = [name for name, make in CASES.items()]


def _wrapper(printer: CPrinter, fn: ca.Function, program) -> str:
    """A non-static entry ``call_<name>(const real** in, real** out)`` for ctypes."""
    real = printer.real
    args = [f"in[{i}]" for i in range(len(program.inputs))]
    args += [f"out[{i}]" for i in range(len(program.outputs))]
    name = printer.function_name(program)
    return (f"void call_{name}(const {real}* const* in, {real}* const* out);\n"
            f"void call_{name}(const {real}* const* in, {real}* const* out) {{\n"
            f"  {name}({', '.join(args)});\n}}\n")


def _build(tmp_path, fn: ca.Function, precision: str):
    printer = CPrinter(precision)
    program = lower(fn)
    text = "#include <math.h>\n" + printer.doprint(program) + "\n" + _wrapper(printer, fn, program)
    src = tmp_path / f"{fn.name()}_{precision}.c"
    src.write_text(text)
    lib = tmp_path / f"lib{fn.name()}_{precision}.so"
    proc = subprocess.run([CC, *STRICT, "-fPIC", "-shared", str(src), "-o", str(lib), "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    return ctypes.CDLL(str(lib)), printer.function_name(program), program, text


@pytest.mark.skipif(CC is None, reason="no C compiler (gcc or clang)")
@pytest.mark.parametrize("case", PRINTABLE)
def test_double_bit_identical_to_casadi(case, tmp_path):
    fn = CASES[case]()
    lib, name, program, _ = _build(tmp_path, fn, "double")
    call = getattr(lib, f"call_{name}")
    rng = np.random.default_rng(3)
    for _ in range(200):
        inputs = [list(rng.uniform(-3, 3, s.numel)) for s in program.inputs]
        ins = [np.ascontiguousarray(v, dtype=np.float64) for v in inputs]
        outs = [np.zeros(s.numel) for s in program.outputs]
        in_ptrs = (ctypes.c_void_p * len(ins))(*[a.ctypes.data for a in ins])
        out_ptrs = (ctypes.c_void_p * len(outs))(*[a.ctypes.data for a in outs])
        call(in_ptrs, out_ptrs)
        expected = casadi_dense(fn, inputs)
        for got, exp in zip(outs, expected):
            assert all(same_double(float(g), e) for g, e in zip(got, exp)), (case, got, exp)


@pytest.mark.skipif(CC is None, reason="no C compiler (gcc or clang)")
def test_single_uses_float_functions_only(tmp_path):
    x = ca.SX.sym("x", 2)
    fn = ca.Function("g", [x], [ca.exp(x[0]) + ca.tanh(x[1]) * ca.log1p(ca.fabs(x[0])) ** 1.5
                                + ca.fmax(x[0], 2.0)])
    _, _, _, text = _build(tmp_path, fn, "single")
    assert "expf(" in text and "tanhf(" in text and "log1pf(" in text and "powf(" in text
    code = text.split("\n", 1)[1]
    assert "double" not in code and "exp(" not in code.replace("expf(", "")
    assert "fmaxf" not in code  # a comparison, not a call


def test_unsupported_op_names_op_and_function():
    x = ca.SX.sym("x")
    fn = ca.Function("h", [x], [ca.hypot(x, 2.0)])
    with pytest.raises(UnsupportedOperation, match="hypot.*'h'"):
        c_source(fn)


def test_sympy_printer_follows_the_same_stream():
    x = ca.SX.sym("x", 2)
    t = ca.SX.sym("t")
    fn = ca.Function("f", [x, t], [ca.fmax(x[0], t) * ca.exp(x[1]) / 4,
                                   ca.if_else(t < 1, ca.log1p(t), 0)], ["x", "t"], ["y", "z"])
    a, b, s = sympy.symbols("a b s", real=True)
    y, z = sympy_expressions(fn, {"x": [a, b], "t": [s]})
    assert sympy.simplify(y[0] - sympy.Max(a, s) * sympy.exp(b) / 4) == 0
    assert z[0].subs(s, sympy.Rational(1, 2)) == sympy.log(sympy.Rational(3, 2))
    assert z[0].subs(s, 2) == 0
    # numerically equal to CasADi on a point
    vals = {a: 0.3, b: -0.7, s: 0.25}
    expected = casadi_dense(fn, [[0.3, -0.7], [0.25]])
    assert abs(float(y[0].subs(vals)) - expected[0][0]) < 1e-15
    assert abs(float(z[0].subs(vals)) - expected[1][0]) < 1e-15
