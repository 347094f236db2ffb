"""Instruction stream: structure, determinism, op counts and unsupported operations."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import casadi as ca
import pytest

import stt_codegen.codegen.emit.instructions as instructions_module
import stt_codegen.codegen.emit.ops as ops_module
from stt_codegen.codegen.emit import (
    Binary,
    Const,
    EmitError,
    IfElseZero,
    Input,
    InstructionPrinter,
    IOSpec,
    Output,
    Program,
    PythonPrinter,
    Unary,
    UnsupportedOperation,
    count_operations,
    lower,
    python_function,
    python_source,
)
from stt_codegen.errors import SttError

from test_emit_cases import CASES

ROOT = Path(__file__).resolve().parents[1]


def test_stream_follows_casadi_vm() -> None:
    fn = CASES["multi_output_sparse"]()
    program = lower(fn)
    assert len(program.instructions) == fn.n_instructions()
    for k, ins in enumerate(program.instructions):
        code = fn.instruction_id(k)
        assert ops_module.OPS[code].name == instructions_module.op_name(ins)
        out = list(fn.instruction_output(k))
        if isinstance(ins, Output):
            assert [ins.output_index, ins.nz] == out
        else:
            assert ins.dest == out[0]
    assert program.n_registers <= fn.sz_w()
    assert [s.name for s in program.inputs] == ["x", "y"]
    assert [s.name for s in program.outputs] == ["diag", "sparse_vec", "dense", "lower", "const", "copy"]


def test_output_positions_are_dense_column_major() -> None:
    fn = CASES["multi_output_sparse"]()
    program = lower(fn)
    diag = program.outputs[0]
    assert (diag.nrow, diag.ncol, diag.positions) == (2, 2, (0, 3))
    lower_tri = program.outputs[3]
    assert lower_tri.positions == (0, 1, 3)
    sparse_vec = program.outputs[1]
    assert sparse_vec.numel == 4 and sparse_vec.positions == (1, 3)
    outs = [i for i in program.instructions if isinstance(i, Output) and i.output_index == 0]
    assert [(o.nz, o.position) for o in outs] == [(0, 0), (1, 3)]


def test_instructions_are_frozen_and_comparable() -> None:
    a, b = lower(CASES["jacobians"]()), lower(CASES["jacobians"]())
    assert a == b
    with pytest.raises(Exception):
        a.instructions[0].dest = 5  # type: ignore[misc]


def test_operation_counts() -> None:
    counts = count_operations(CASES["smooth_max"]())
    assert counts.by_op == {
        "add": 1, "div": 1, "exp": 1, "fabs": 1, "fmax": 1, "input": 3, "log1p": 1,
        "mul": 1, "neg": 1, "output": 1, "sub": 1,
    }
    assert (counts.arithmetic, counts.transcendental, counts.logic) == (7, 2, 0)
    assert counts.total == sum(counts.by_op.values()) == 13
    newton = count_operations(CASES["newton_unrolled"]())
    assert newton.transcendental >= 1 and newton.arithmetic > 50
    assert list(newton.by_op) == sorted(newton.by_op)
    assert count_operations(lower(CASES["smooth_max"]())) == counts


# ----------------------------------------------------------------- unsupported ops
def test_unknown_op_raises_clear_error() -> None:
    x = ca.SX.sym("x")
    fn = ca.Function("uses_erfinv", [x], [ca.erfinv(x) + 1], ["x"], ["y"])
    with pytest.raises(UnsupportedOperation, match=r"'OP_ERFINV'.*'uses_erfinv'") as info:
        lower(fn)
    assert info.value.op == "OP_ERFINV" and info.value.function == "uses_erfinv"
    assert isinstance(info.value, SttError)
    with pytest.raises(UnsupportedOperation):
        python_source(fn)
    with pytest.raises(UnsupportedOperation):
        count_operations(fn)


def test_op_removed_from_table_raises(monkeypatch: pytest.MonkeyPatch) -> None:
    table = dict(ops_module.OPS)
    del table[ca.OP_TANH]
    monkeypatch.setattr(instructions_module, "OPS", table)
    with pytest.raises(UnsupportedOperation, match=r"'OP_TANH'.*'tanh_time9'"):
        lower(CASES["tanh_time_const"]())


def test_op_unknown_to_the_printer_raises(monkeypatch: pytest.MonkeyPatch) -> None:
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    fn = ca.Function("uses_hypot", [x, y], [ca.hypot(x, y)], ["x", "y"], ["r"])
    assert lower(fn)  # known to the stream ...
    with pytest.raises(UnsupportedOperation, match=r"'hypot'.*'uses_hypot'.*Python"):
        python_source(fn)  # ... but not to the Python printer
    monkeypatch.delitem(PythonPrinter.known_functions, "tanh")
    with pytest.raises(UnsupportedOperation, match=r"'tanh'.*'tanh_time9'"):
        python_source(CASES["tanh_time_const"]())


def test_free_symbols_and_mx_are_rejected() -> None:
    x, p = ca.SX.sym("x"), ca.SX.sym("p")
    free = ca.Function("free", [x], [x * p], {"allow_free": True})
    with pytest.raises(UnsupportedOperation, match="OP_PARAMETER"):
        lower(free)
    xm = ca.MX.sym("x")
    mx = ca.Function("mx_fn", [xm], [ca.sin(xm)])
    with pytest.raises(EmitError, match="not an SXFunction"):
        lower(mx)
    assert lower(mx.expand()).name == "mx_fn"
    with pytest.raises(EmitError):
        lower("not a function")  # type: ignore[arg-type]


def test_duplicate_function_names_rejected() -> None:
    with pytest.raises(EmitError, match="smooth_max"):
        python_source([CASES["smooth_max"](), CASES["smooth_max"]()])


# --------------------------------------------------------- hand-built instruction streams
def _scalar(name: str, index: int) -> IOSpec:
    return IOSpec(name, index, 1, 1, (0,))


def test_hand_built_program_with_assign_and_inf_nan_constants() -> None:
    program = Program(
        name="hand",
        inputs=(_scalar("x", 0),),
        outputs=(IOSpec("y", 0, 4, 1, (0, 1, 2, 3)),),
        instructions=(
            Input(0, 0, 0, 0),
            Unary("assign", 1, 0),
            Const(2, float("inf")),
            Binary("mul", 1, 1, 2),
            Output(0, 0, 0, 1),
            Const(2, float("-inf")),
            Output(0, 1, 1, 2),
            Const(2, float("nan")),
            IfElseZero(3, 0, 2),
            Output(0, 2, 2, 3),
            Const(2, -0.0),
            Unary("inv", 3, 2),
            Output(0, 3, 3, 3),
        ),
        n_registers=4,
    )
    src = python_source(program)
    assert "w1 = w0" in src and "math.inf" in src and "-math.inf" in src and "math.nan" in src
    assert "w3 = _div(1.0, w2)" in src  # -0.0 is a zero divisor: guarded
    g = python_function(program)
    (y,) = g([2.0])
    assert y[:2] == [float("inf"), float("-inf")]
    assert y[2] != y[2] and y[3] == float("-inf")
    (y,) = g([0.0])
    assert y[2] == 0.0  # if_else_zero(0, nan) is 0


class TinyCPrinter(InstructionPrinter):
    """A C-like printer in a few lines: what a C backend would subclass."""

    language = "C"
    known_functions = {"exp": "exp", "log1p": "log1p", "fabs": "fabs", "fmax": "fmax", "tanh": "tanh"}
    infix_operators = {"add": "+", "sub": "-", "mul": "*", "div": "/", "lt": "<"}

    def _print_inf(self, negative: bool) -> str:
        return "-INFINITY" if negative else "INFINITY"

    def _print_nan(self) -> str:
        return "NAN"

    def _assign(self, target: str, expr: str) -> str:
        return f"{target} = {expr};"

    def _input_ref(self, spec: IOSpec, position: int) -> str:
        return f"arg[{spec.index}][{position}]"

    def _output_ref(self, spec: IOSpec, position: int) -> str:
        return f"res[{spec.index}][{position}]"

    def _function_text(self, program: Program, body) -> str:
        regs = ", ".join(self.register(k) for k in range(program.n_registers))
        lines = [f"void {program.name}(const double** arg, double** res) {{", f"  double {regs};"]
        return "\n".join(lines + ["  " + s for s in body] + ["}"]) + "\n"

    def _module_text(self, programs, functions) -> str:
        return "#include <math.h>\n\n" + "\n".join(functions)


def test_c_like_printer_is_a_small_subclass(tmp_path: Path) -> None:
    src = TinyCPrinter().doprint([CASES["smooth_max"](), CASES["tanh_time_const"]()])
    assert "w0 = arg[0][0];" in src and "res[0][0] = " in src and "fmax(w0, w1)" in src
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not installed")
    path = tmp_path / "tiny.c"
    path.write_text(src)
    subprocess.run([gcc, "-std=c99", "-Wall", "-Werror", "-fsyntax-only", str(path)], check=True)


# ------------------------------------------------------------------------ determinism
_GENERATE = textwrap.dedent(
    """
    import sys
    sys.path.insert(0, {tests!r})
    from test_emit_cases import all_functions
    from stt_codegen.codegen.emit import python_source, lower
    fns = all_functions()
    sys.stdout.write(python_source(fns))
    sys.stdout.write(repr([lower(f) for f in fns]))
    """
)


def _generate(seed: str) -> str:
    env = dict(os.environ, PYTHONHASHSEED=seed)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH", "")]))
    code = _GENERATE.format(tests=str(ROOT / "tests"))
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, check=True, timeout=300)
    return done.stdout


def test_source_identical_across_processes_and_hash_seeds() -> None:
    first = _generate("0")
    second = _generate("4242")
    assert len(first) > 1000
    assert first == second
