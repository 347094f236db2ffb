"""Print CasADi SX Functions as standalone Python functions (``import math`` only).

Each CasADi Function becomes one ``def`` taking one sequence of floats per input
(dense, column-major, ``nrow * ncol`` entries; parameter names are the CasADi input
names) and returning a tuple of lists of floats, one per output (dense, column-major,
structural zeros as ``0.0``; local names are the CasADi output names). Every input
value goes through ``float()``. Register ``k`` of CasADi's VM is the local ``w<k>``; the
statements are CasADi's VM instructions in order, so results are bit-identical to
``f(...)`` evaluated by CasADi on ``DM`` (checked by ``tests/test_emit_python.py``).

Semantic choices, each made to match CasADi 3.8.2's VM (C library, IEEE 754):

* ``+``, ``-``, ``*``, unary ``-`` are Python float operators (IEEE, never raise).
  ``sq(x)`` is ``x * x``, ``twice(x)`` is ``x + x`` (exact, like CasADi's ``2.*x``).
* Division: Python raises ``ZeroDivisionError``; IEEE gives ``+-inf`` (sign of the
  quotient, ``-0.0`` counts as negative) or ``nan`` for ``0/0`` and ``nan/0``.
  Divisions by a register known to hold a nonzero constant are printed as plain
  ``a / b``; the others call the helper ``_div``. ``inv(x)`` is ``1.0 / x``.
* ``math`` functions that raise outside their domain or on overflow are wrapped in
  helpers returning the C result: ``_log`` (``-inf`` at ``+-0``, ``nan`` below),
  ``_log1p`` (``-inf`` at -1, ``nan`` below), ``_sqrt``, ``_asin``, ``_acos``,
  ``_acosh`` (``nan``), ``_atanh`` (``+-inf`` at ``+-1``, ``nan`` beyond), ``_exp``,
  ``_expm1``, ``_cosh`` (``inf`` on overflow), ``_sinh`` (``+-inf``), ``_sin``,
  ``_cos``, ``_tan`` (``nan`` at ``+-inf``), ``_pow`` (C99 ``pow`` special cases),
  ``_fmod``, ``_remainder`` (``nan``), ``_floor``, ``_ceil`` (a float with the sign of
  zero kept; ``inf``/``nan`` unchanged). The fast path of each helper is the plain
  ``math`` call, so normal values get exactly libm's result. Functions that never raise
  (``math.tanh``, ``math.fabs``, ``math.atan``, ``math.asinh``, ``math.erf``,
  ``math.copysign``, ``math.atan2``) are called directly.
* ``fmin``/``fmax`` (``_fmin``/``_fmax``): a NaN operand is ignored (the result is NaN
  only if both are); on equal operands (``-0.0`` vs ``0.0``) the first one is returned,
  as measured on CasADi 3.8.2.
* ``sign(x)`` (``_sign``) is ``-1.0``/``1.0``, and ``x`` itself for ``+-0.0`` and NaN.
* Comparisons, ``not``, ``and``, ``or`` give ``1.0`` or ``0.0``; any nonzero value,
  NaN included, is true (C semantics); comparisons with NaN are false except ``!=``.
* ``if_else_zero(c, y)`` is ``0.0 if c == 0.0 else y``: ``0.0`` even when ``y`` is NaN
  or infinite, so an untaken branch of ``casadi.if_else`` cannot leak a NaN.
* Constants are printed with ``repr(float)`` (round-trips exactly); ``inf``/``nan`` as
  ``math.inf``/``math.nan``.
* ``hypot`` is not supported (CPython's ``math.hypot`` is not libm's ``hypot``), nor
  is any op absent from :mod:`stt_codegen.codegen.emit.ops`: they raise
  :class:`~stt_codegen.codegen.emit.errors.UnsupportedOperation`.

NaN results are NaN but their sign/payload bits may differ from CasADi's.
"""

from __future__ import annotations

import keyword
import re
from typing import Callable, Dict, List, Sequence, Set, Tuple, Union

import casadi

from .errors import EmitError
from .instructions import IOSpec, Program, lower
from .printer import FunctionLike, InstructionPrinter
from .python_helpers import HELPER_DEPENDENCIES, HELPERS

__all__ = ["PythonPrinter", "python_function", "python_source"]

_RESERVED = frozenset({"math", "float", "len", "ValueError"})
_REGISTER = re.compile(r"^w[0-9]+$")


def python_identifier(name: str, taken: Set[str]) -> str:
    """Turn a CasADi name into a Python identifier not in ``taken`` (deterministic).

    Characters outside ``[A-Za-z0-9_]`` become ``_``; a leading digit gets a ``v_``
    prefix; keywords, names starting with ``_`` (helpers), register names (``w<k>``)
    and names used by the generated code get ``_`` appended until free.

    Parameters
    ----------
    name : str
    taken : set of str
        Names already in use in the same scope.

    Returns
    -------
    str
    """
    ident = re.sub(r"[^A-Za-z0-9_]", "_", name) or "v"
    if ident[0].isdigit():
        ident = "v_" + ident
    if ident.startswith("_"):
        ident = "v" + ident
    while (
        keyword.iskeyword(ident)
        or ident in _RESERVED
        or _REGISTER.match(ident)
        or ident in taken
    ):
        ident += "_"
    return ident


def _shape_text(spec: IOSpec) -> str:
    text = f"length {spec.numel} (dense {spec.nrow}x{spec.ncol}, column-major"
    if spec.nnz != spec.numel:
        text += f", {spec.nnz} structural nonzero{'' if spec.nnz == 1 else 's'}"
    return text + ")"


class PythonPrinter(InstructionPrinter):
    """Printer of standalone Python source; see the module docstring for semantics."""

    language = "Python"
    known_functions: Dict[str, str] = {
        "fabs": "math.fabs",
        "tanh": "math.tanh",
        "atan": "math.atan",
        "asinh": "math.asinh",
        "erf": "math.erf",
        "copysign": "math.copysign",
        "atan2": "math.atan2",
    }
    #: Ops printed as a call of a helper of :mod:`stt_codegen.codegen.emit.python_helpers`.
    helper_functions: Dict[str, str] = {
        "fmin": "_fmin",
        "fmax": "_fmax",
        "sign": "_sign",
        "floor": "_floor",
        "ceil": "_ceil",
        "fmod": "_fmod",
        "remainder": "_remainder",
        "sqrt": "_sqrt",
        "pow": "_pow",
        "exp": "_exp",
        "expm1": "_expm1",
        "log": "_log",
        "log1p": "_log1p",
        "sin": "_sin",
        "cos": "_cos",
        "tan": "_tan",
        "asin": "_asin",
        "acos": "_acos",
        "sinh": "_sinh",
        "cosh": "_cosh",
        "acosh": "_acosh",
        "atanh": "_atanh",
    }
    infix_operators: Dict[str, str] = {"add": "+", "sub": "-", "mul": "*"}

    def __init__(self) -> None:
        super().__init__()
        self._helpers: Set[str] = set()

    # ------------------------------------------------------------------ ops
    def op_expression(self, op: str, operands: Tuple[str, ...]) -> str:  # noqa: D102
        helper = self.helper_functions.get(op)
        if helper is not None and getattr(self, "_print_op_" + op, None) is None:
            self._use(helper)
            return f"{helper}({', '.join(operands)})"
        return super().op_expression(op, operands)

    def _use(self, helper: str) -> None:
        self._helpers.add(helper)
        for dep in HELPER_DEPENDENCIES[helper]:
            self._use(dep)

    def _print_op_div(self, a: str, b: str) -> str:
        divisor = self.known_value(b)
        if divisor is not None and divisor != 0.0:
            return f"{a} / {b}"
        self._use("_div")
        return f"_div({a}, {b})"

    def _compare(self, op: str, a: str, b: str) -> str:
        return f"1.0 if {a} {self.comparisons[op]} {b} else 0.0"

    def _print_op_not(self, a: str) -> str:
        return f"1.0 if {a} == 0.0 else 0.0"

    def _print_op_and(self, a: str, b: str) -> str:
        return f"1.0 if {a} != 0.0 and {b} != 0.0 else 0.0"

    def _print_op_or(self, a: str, b: str) -> str:
        return f"1.0 if {a} != 0.0 or {b} != 0.0 else 0.0"

    def _print_op_if_else_zero(self, cond: str, value: str) -> str:
        return f"0.0 if {cond} == 0.0 else {value}"

    # ------------------------------------------------------------- constants
    def _print_inf(self, negative: bool) -> str:
        return "-math.inf" if negative else "math.inf"

    def _print_nan(self) -> str:
        return "math.nan"

    # ------------------------------------------------------------ statements
    def _assign(self, target: str, expr: str) -> str:
        return f"{target} = {expr}"

    def _input_ref(self, spec: IOSpec, position: int) -> str:
        return f"float({self.io_name('in', spec.index)}[{position}])"

    def _output_ref(self, spec: IOSpec, position: int) -> str:
        return f"{self.io_name('out', spec.index)}[{position}]"

    def print_function(self, program: FunctionLike) -> str:  # noqa: D102
        if not isinstance(program, Program):
            program = lower(program)
        self._name_io(program, python_identifier)
        return super().print_function(program)

    def _function_text(self, program: Program, body: List[str]) -> str:
        ins = [self.io_name("in", s.index) for s in program.inputs]
        outs = [self.io_name("out", s.index) for s in program.outputs]
        fname = self.function_name(program)
        lines = [f"def {fname}({', '.join(ins)}):"]
        doc = [f'"""CasADi Function {program.name!r} ({len(program.instructions)} instructions).', ""]
        if ins:
            doc += ["Parameters", "----------"]
            for spec, ident in zip(program.inputs, ins):
                doc += [f"{ident} : sequence of float, {_shape_text(spec)}"]
            doc += [""]
        doc += ["Returns", "-------"]
        if outs:
            for spec, ident in zip(program.outputs, outs):
                doc += [f"{ident} : list of float, {_shape_text(spec)}"]
        else:
            doc += ["tuple, empty"]
        doc += ['"""']
        lines += ["    " + d if d else "" for d in doc]
        for spec, ident in zip(program.inputs, ins):
            lines += [
                f"    if len({ident}) != {spec.numel}:",
                f"        raise ValueError('{ident}: expected {spec.numel} values, got %d' % len({ident}))",
            ]
        for spec, ident in zip(program.outputs, outs):
            lines.append(f"    {ident} = [0.0] * {spec.numel}")
        lines += ["    " + stmt for stmt in body]
        if len(outs) == 1:
            lines.append(f"    return ({outs[0]},)")
        else:
            lines.append(f"    return ({', '.join(outs)})")
        return "\n".join(lines) + "\n"

    def function_name(self, program: Program) -> str:
        """Python name of the generated function (sanitised CasADi name)."""
        return python_identifier(program.name, set())

    def doprint(self, functions: Union[FunctionLike, Sequence[FunctionLike]]) -> str:  # noqa: D102
        self._helpers = set()
        return super().doprint(functions)

    def _module_text(self, programs: List[Program], functions: List[str]) -> str:
        fnames = [self.function_name(p) for p in programs]
        for name in fnames:
            if fnames.count(name) > 1:
                raise EmitError(f"two Functions map to the Python name {name!r}")
        header = [
            f"# Generated by stt_codegen.codegen.emit.PythonPrinter from CasADi {casadi.__version__}"
            " SX Functions: " + ", ".join(p.name for p in programs) + ".",
            "# Do not edit; regenerate. Depends on the standard library's math only.",
            "import math",
        ]
        parts = ["\n".join(header) + "\n"]
        parts += [src for name, src, _ in HELPERS if name in self._helpers]
        parts += functions
        return "\n\n".join(parts)


def python_source(functions: Union[FunctionLike, Sequence[FunctionLike]]) -> str:
    """Source of a standalone Python module with one function per CasADi Function.

    Parameters
    ----------
    functions : casadi.Function or Program, or a sequence of them
        SX Functions, printed in the given order.

    Returns
    -------
    str
        Module text (``import math`` only).

    Raises
    ------
    UnsupportedOperation
        If a Function uses an op without a Python translation.
    EmitError
        If a Function is not an SX Function, or two names collide.
    """
    return PythonPrinter().doprint(functions)


def python_function(fn: FunctionLike) -> Callable[..., tuple]:
    """Generate, execute and return the Python function of one CasADi Function.

    Parameters
    ----------
    fn : casadi.Function or Program

    Returns
    -------
    callable
        ``g(*inputs) -> tuple of list of float``; each input a sequence of floats of
        length ``nrow * ncol`` (dense, column-major).
    """
    program = fn if isinstance(fn, Program) else lower(fn)
    printer = PythonPrinter()
    source = printer.doprint(program)
    namespace: Dict[str, object] = {"__name__": f"stt_codegen_generated_{program.name}"}
    exec(compile(source, f"<stt_codegen:{program.name}>", "exec"), namespace)
    return namespace[printer.function_name(program)]  # type: ignore[return-value]
