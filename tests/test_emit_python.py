"""Generated Python is bit-identical to CasADi's own evaluation on DM.

"Bit-identical" here is stricter than ``==``: equal bit patterns (so ``-0.0`` differs
from ``0.0``), except that any NaN matches any NaN (sign and payload of NaN are not
specified by IEEE 754 for most operations).
"""

from __future__ import annotations

import math
import struct
from typing import List, Sequence

import casadi as ca
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stt_codegen.codegen.emit import count_operations, lower, python_function, python_source
from stt_codegen.codegen.emit.ops import OPS_BY_NAME
from stt_codegen.codegen.emit.python_printer import PythonPrinter

from test_emit_cases import CASES

INF, NAN = math.inf, math.nan
SPECIAL = [0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 2.0, -2.0, 9.0, 1e-310, -1e-310,
           1e308, -1e308, 710.0, -710.0, INF, -INF, NAN]

#: Any double (NaN and infinities included), moderate values, and special values.
floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-20.0, 20.0),
    st.sampled_from(SPECIAL),
)

SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


def same_double(x: float, y: float) -> bool:
    """Equal bit patterns, or both NaN."""
    if math.isnan(x) or math.isnan(y):
        return math.isnan(x) and math.isnan(y)
    return struct.pack("<d", x) == struct.pack("<d", y)


def casadi_dense(fn: ca.Function, inputs: Sequence[Sequence[float]]) -> List[List[float]]:
    """Evaluate ``fn`` on DM; outputs as dense column-major lists."""
    args = []
    for i, vals in enumerate(inputs):
        sp = fn.sparsity_in(i)
        args.append(ca.DM(np.reshape(np.asarray(vals, float), (sp.size1(), sp.size2()), order="F")))
    res = fn.call(args)
    return [list(np.asarray(r.full(), float).ravel(order="F")) for r in res]


def assert_bit_identical(fn: ca.Function, gen, inputs: Sequence[Sequence[float]]) -> None:
    expected = casadi_dense(fn, inputs)
    got = gen(*inputs)
    assert isinstance(got, tuple) and len(got) == len(expected)
    for k, (e, g) in enumerate(zip(expected, got)):
        assert isinstance(g, list) and len(g) == len(e)
        for j, (ev, gv) in enumerate(zip(e, g)):
            assert type(gv) is float
            assert same_double(ev, gv), (
                f"{fn.name()} output {fn.name_out(k)}[{j}]: casadi {ev!r}, generated {gv!r}"
                f" for inputs {inputs!r}"
            )


def input_strategy(fn: ca.Function):
    return st.tuples(*[st.lists(floats, min_size=fn.numel_in(i), max_size=fn.numel_in(i))
                       for i in range(fn.n_in())])


@pytest.mark.parametrize("case", list(CASES))
def test_cases_bit_identical(case: str) -> None:
    fn = CASES[case]()
    gen = python_function(fn)

    @SETTINGS
    @given(input_strategy(fn))
    def check(inputs):
        assert_bit_identical(fn, gen, inputs)

    check()


def test_cases_bit_identical_on_a_grid_of_special_values() -> None:
    for fn in (CASES["smooth_max"](), CASES["tanh_time"](), CASES["if_else_nan_branch"]()):
        gen = python_function(fn)
        n = fn.n_in()
        for i, a in enumerate(SPECIAL):
            for b in SPECIAL:
                vals = [a, b, SPECIAL[(i + 3) % len(SPECIAL)]][:n]
                assert_bit_identical(fn, gen, [[v] for v in vals])


def test_tanh_time_near_tc() -> None:
    fn = CASES["tanh_time"]()
    gen = python_function(fn)
    tc = 9.0
    ts = [tc, math.nextafter(tc, 0), math.nextafter(tc, 20), 0.0, -0.0, tc - 1e-12, 1e6]
    for t in ts:
        assert_bit_identical(fn, gen, [[t], [tc]])
    raw, s, _ = gen([tc], [tc])
    assert raw == [1.0] and s == [1.0]


def test_if_else_untaken_nan_branch_gives_the_taken_value() -> None:
    gen = python_function(CASES["if_else_nan_branch"]())
    (r,) = gen([-4.0], [0.0])
    assert r[0] == 2.0  # sqrt(-x) taken; log(-4) = nan not taken
    assert math.isnan(r[1])  # log(x - 1) taken (y == 0)
    (r,) = gen([0.5], [1.0])
    assert r[:2] == [math.log(0.5), 0.5]  # untaken sqrt(-0.5) and log(-0.5) are nan
    (r,) = gen([0.0], [1.0])
    assert r[:2] == [0.0, 0.0]  # untaken log(0) = -inf and log(-1) = nan
    # if_else adds both if_else_zero terms: 0.0 + sqrt(-0.0) = +0.0, as in CasADi
    assert math.copysign(1.0, r[0]) == 1.0


# ---------------------------------------------------------------- one op at a time
a_, b_ = ca.SX.sym("a"), ca.SX.sym("b")
OP_EXPRESSIONS = {
    "add": a_ + b_, "sub": a_ - b_, "mul": a_ * b_, "div": a_ / b_, "neg": -a_,
    "sq": a_ * a_, "twice": 2 * a_, "inv": 1 / a_, "fabs": ca.fabs(a_),
    "sign": ca.sign(a_), "copysign": ca.copysign(a_, b_), "fmin": ca.fmin(a_, b_),
    "fmax": ca.fmax(a_, b_), "floor": ca.floor(a_), "ceil": ca.ceil(a_),
    "fmod": ca.fmod(a_, b_), "remainder": ca.remainder(a_, b_),
    "lt": a_ < b_, "le": a_ <= b_, "eq": a_ == b_, "ne": a_ != b_,
    "not": ca.logic_not(a_), "and": ca.logic_and(a_, b_), "or": ca.logic_or(a_, b_),
    "if_else_zero": ca.if_else(a_, b_, 0), "sqrt": ca.sqrt(a_), "pow": a_ ** b_,
    "constpow": a_ ** 2.5, "exp": ca.exp(a_), "expm1": ca.expm1(a_), "log": ca.log(a_),
    "log1p": ca.log1p(a_), "sin": ca.sin(a_), "cos": ca.cos(a_), "tan": ca.tan(a_),
    "asin": ca.asin(a_), "acos": ca.acos(a_), "atan": ca.atan(a_),
    "atan2": ca.atan2(a_, b_), "sinh": ca.sinh(a_), "cosh": ca.cosh(a_),
    "tanh": ca.tanh(a_), "asinh": ca.asinh(a_), "acosh": ca.acosh(a_),
    "atanh": ca.atanh(a_), "erf": ca.erf(a_),
}
# Ops of the table without an expression above: data moves (covered by every test)
# and ops the Python printer refuses on purpose.
NOT_COVERED = {"input", "output", "const", "assign", "hypot"}


def test_every_op_of_the_table_is_covered() -> None:
    assert set(OPS_BY_NAME) == set(OP_EXPRESSIONS) | NOT_COVERED


def _single_op_bit_identical(op: str, draws: int) -> None:
    """The op alone: every pair of SPECIAL values, then ``draws`` pairs of any doubles."""
    fn = ca.Function(f"op_{op}", [a_, b_], [OP_EXPRESSIONS[op]], ["a", "b"], ["r"])
    assert op in count_operations(fn).by_op, f"{op}: CasADi simplified the expression"
    gen = python_function(fn)
    for x in SPECIAL:
        for y in SPECIAL:
            assert_bit_identical(fn, gen, [[x], [y]])

    @settings(max_examples=draws, deadline=None)
    @given(floats, floats)
    def check(x, y):
        assert_bit_identical(fn, gen, [[x], [y]])

    check()


@pytest.mark.parametrize("op", sorted(OP_EXPRESSIONS))
def test_single_op_bit_identical(op: str) -> None:
    _single_op_bit_identical(op, 100)


# the same with four times the draws (the fast tier above: about 0.3 s an op, 46 ops)
@pytest.mark.slow
@pytest.mark.parametrize("op", sorted(OP_EXPRESSIONS))
def test_single_op_bit_identical_on_more_draws(op: str) -> None:
    _single_op_bit_identical(op, 400)


def test_pow_special_cases() -> None:
    fn = ca.Function("p", [a_, b_], [a_ ** b_], ["a", "b"], ["r"])
    gen = python_function(fn)
    exps = [-3.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 3.0, 1e300, -1e300, 2001.0, INF, -INF, NAN]
    bases = [0.0, -0.0, -8.0, 8.0, -1.0, 1.0, 1e200, -1e200, 1e-200, -1e-200, INF, -INF, NAN]
    for x in bases:
        for y in exps:
            assert_bit_identical(fn, gen, [[x], [y]])


# ------------------------------------------------------------------ generated text
def test_source_imports_math_only_and_is_stable() -> None:
    fns = [build() for build in CASES.values()]
    src = python_source(fns)
    assert src == python_source(fns)
    imports = [line for line in src.splitlines() if line.lstrip().startswith(("import", "from"))]
    assert imports == ["import math"]
    namespace: dict = {}
    exec(compile(src, "<generated>", "exec"), namespace)
    for fn in fns:
        assert callable(namespace[fn.name()])


def test_division_by_nonzero_constant_is_plain() -> None:
    src = python_source(CASES["smooth_max_min_const"]())
    assert "_div" not in src
    assert " / w" in src
    src = python_source(CASES["smooth_max"]())  # divides by the input nu
    assert "_div(" in src


def test_parameter_and_result_names_are_casadi_names() -> None:
    fn = CASES["tanh_time"]()
    src = python_source(fn)
    assert "def tanh_time(t, tc):" in src
    assert "return (raw, s, s_dot)" in src


def test_awkward_names_are_sanitised() -> None:
    x = ca.SX.sym("x")
    fn = ca.Function("my_fn", [x, ca.SX.sym("y")], [x * 2, x + 1], ["lambda", "w0"], ["w0 out", "math"])
    src = python_source(fn)
    assert "def my_fn(lambda_, w0_):" and "return (w0_out, math_)" in src
    g = python_function(fn)
    assert g([3.0], [0.0]) == ([6.0], [4.0])


def test_wrong_input_length_raises() -> None:
    gen = python_function(CASES["smooth_max"]())
    with pytest.raises(ValueError, match="a: expected 1 values"):
        gen([1.0, 2.0], [1.0], [1.0])


def test_integer_inputs_are_converted_to_float() -> None:
    fn = ca.Function("d", [a_, b_], [a_ / b_], ["a", "b"], ["r"])
    gen = python_function(fn)
    assert gen([1], [3]) == ([1.0 / 3.0],)
    assert gen(np.array([1.0]), np.array([0.0])) == ([INF],)


def test_constants_use_repr() -> None:
    x = ca.SX.sym("x")
    c = 0.1 + 0.2
    fn = ca.Function("c", [x], [x * c, x + 1e-300, ca.vertcat(INF, -INF, -0.0) * 1.0], ["x"], ["a", "b", "k"])
    src = python_source(fn)
    assert repr(c) in src and "1e-300" in src
    (a, b, k) = python_function(fn)([2.0])
    assert a == [2.0 * c] and b == [2.0 + 1e-300]
    assert k[:2] == [INF, -INF]


def test_program_can_be_printed_directly() -> None:
    program = lower(CASES["smooth_max"]())
    assert PythonPrinter().doprint(program) == python_source(CASES["smooth_max"]())
