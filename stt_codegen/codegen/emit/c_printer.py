"""Print CasADi SX Functions as C99 functions, in double or single precision.

Each CasADi Function becomes one ``static void`` function whose parameters are one
pointer per input (``const real*``, dense column-major ``nrow * ncol`` entries, named after
the CasADi input) followed by one pointer per output (``real*``, dense). Register ``k`` of
CasADi's VM is the local variable ``w<k>``; the statements are CasADi's VM instructions in
order, so in double precision, compiled with ``-ffp-contract=off`` against the same libm,
results are bit-identical to ``f(...)`` evaluated by CasADi on ``DM``.

The real type is a parameter (:class:`Precision`): it gives the C type, the suffix of
constants (``1.5`` or ``1.5f``) and the table of maths functions (``exp`` or ``expf``, ...),
so single precision computes in ``float`` throughout (no promotion to double, no
implicit conversion: clean under ``-Wconversion -Wdouble-promotion``).

Semantic choices (inputs of the deployed controller are checked to be finite before a
body runs, so the NaN cases below never occur on a valid step):

* ``fmin(a, b)`` is printed ``(b < a) ? b : a`` and ``fmax(a, b)`` ``(b > a) ? b : a``: one
  comparison instead of a library call (on the Cortex-M4 ``fmaxf`` costs a call and a
  ``__fpclassifyf``). Equal to C's ``fmin``/``fmax`` for every non-NaN pair; a NaN ``b``
  gives ``a`` (as C), a NaN ``a`` gives NaN (C: ``b``).
* comparisons, ``not``, ``and``, ``or`` give ``1`` or ``0`` of the real type; a register
  is true when it is not zero (C semantics, NaN is true).
* ``if_else_zero(c, y)`` is ``(c != 0) ? y : 0``: 0 even when ``y`` is NaN or infinite.
* ``sign(x)`` is ``-1``/``1`` and ``x`` itself for zeros and NaN (CasADi's ``casadi_sign``).
* ``sq(x)`` is ``x * x``, ``twice(x)`` is ``x + x``, ``inv(x)`` is ``1 / x``, ``constpow``
  is ``pow`` (all exact rewrites of CasADi's own C).
* in single precision ``exp`` is ``stt_expf`` and ``log`` is ``stt_logf``, defined in the
  printed text before the functions that use them (:mod:`~stt_codegen.codegen.emit.c_maths`:
  within 0.89 ulp of ``e^x``, the C library's ``expf`` outside ``|x| <= 80``; within 0.84
  ulp of ``ln x``, the C library's ``logf`` outside ``[2^-8, 2^8]``); they are cheaper than
  newlib's ``expf`` and ``logf`` on the Cortex-M4F. Double precision calls the C library
  (bit-identity with CasADi).
* every floating constant is ``repr(float)`` of the double, with the ``f`` suffix in single
  precision (the decimal is then rounded once, to the nearest float); infinities are
  ``HUGE_VAL``/``HUGE_VALF``, NaN is ``NAN`` (cast to double in double precision).

``hypot`` and any op absent from :mod:`stt_codegen.codegen.emit.ops` raise
:class:`~stt_codegen.codegen.emit.errors.UnsupportedOperation`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Dict, List, Sequence, Set, Tuple, Union

from . import c_maths
from .errors import EmitError
from .instructions import Input, IOSpec, Output, Program, Unary, lower
from .printer import FunctionLike, InstructionPrinter

__all__ = ["CPrinter", "Precision", "c_source"]

#: C99 ``<math.h>`` functions the printer may call (op name = double function name).
MATH_FUNCTIONS: Tuple[str, ...] = (
    "fabs", "copysign", "floor", "ceil", "fmod", "remainder", "sqrt", "pow", "exp", "expm1",
    "log", "log1p", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh",
    "tanh", "asinh", "acosh", "atanh", "erf")

_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary".split())


@dataclass(frozen=True)
class Precision:
    """The real type of generated C and what depends on it.

    Attributes
    ----------
    name : {"double", "single"}
    c_type : str
        ``"double"`` or ``"float"``.
    suffix : str
        Suffix of floating constants and of maths functions (``""`` or ``"f"``).
    huge : str
        C expression of +infinity of the type.
    nan : str
        C expression of a quiet NaN of the type.
    own : tuple of str
        Ops computed by a function of the project's own, defined in the generated file
        before the functions that use it (:mod:`~stt_codegen.codegen.emit.c_maths`).
    """

    name: str
    c_type: str
    suffix: str
    huge: str
    nan: str
    own: Tuple[str, ...] = ()

    @property
    def math(self) -> Dict[str, str]:
        """Op name -> C maths function of this precision (``exp`` -> ``expf``; an op in
        ``own`` -> the function of :mod:`~stt_codegen.codegen.emit.c_maths`)."""
        table = {name: name + self.suffix for name in MATH_FUNCTIONS}
        table.update((op, name) for op, name in c_maths.FUNCTIONS if op in self.own)
        return table


DOUBLE = Precision("double", "double", "", "HUGE_VAL", "((double)NAN)")
#: Single precision computes ``exp`` and ``log`` with the project's own ``stt_expf`` and
#: ``stt_logf`` (see :mod:`~stt_codegen.codegen.emit.c_maths`: within 0.89 and 0.84 ulp,
#: about 20 instructions cheaper per call than newlib's on the Cortex-M4F).
SINGLE = Precision("single", "float", "f", "HUGE_VALF", "NAN", own=("exp", "log"))
PRECISIONS: Dict[str, Precision] = {"double": DOUBLE, "single": SINGLE}


def c_identifier(name: str, taken: Set[str]) -> str:
    """Turn a CasADi name into a C identifier not in ``taken`` (deterministic).

    Characters outside ``[A-Za-z0-9_]`` become ``_``; a leading digit or underscore gets a
    ``v`` prefix; keywords, register names (``w<k>``) and taken names get ``_`` appended.
    """
    ident = re.sub(r"[^A-Za-z0-9_]", "_", name) or "v"
    if ident[0].isdigit() or ident[0] == "_":
        ident = "v" + ident
    while ident in _C_KEYWORDS or re.fullmatch(r"w[0-9]+", ident) or ident in taken:
        ident += "_"
    return ident


class CPrinter(InstructionPrinter):
    """Printer of C99 functions; see the module docstring for semantics.

    Parameters
    ----------
    precision : {"double", "single"} or Precision
        Real type of every value.
    real : str, optional
        Name of the real type in the generated code (a typedef of the caller, e.g.
        ``"omnirobot_s1_real"``); default the C type itself.
    prefix : str
        Prepended to every generated function name (``prefix + casadi name``).
    """

    language = "C"
    infix_operators: Dict[str, str] = {"add": "+", "sub": "-", "mul": "*", "div": "/"}

    def __init__(self, precision: Union[str, Precision] = "double", real: str = "",
                 prefix: str = "") -> None:
        super().__init__()
        if isinstance(precision, str):
            if precision not in PRECISIONS:
                raise EmitError(f"precision must be one of {sorted(PRECISIONS)}, got {precision!r}")
            precision = PRECISIONS[precision]
        self.precision = precision
        self.real = real or precision.c_type
        self.prefix = prefix
        self.known_functions = precision.math

    # ------------------------------------------------------------------ ops
    def _bool(self, condition: str) -> str:
        return f"({condition}) ? {self.constant(1.0)} : {self.constant(0.0)}"

    def _true(self, a: str) -> str:
        return f"({a} != {self.constant(0.0)})"

    def _compare(self, op: str, a: str, b: str) -> str:
        return self._bool(f"{a} {self.comparisons[op]} {b}")

    def _print_op_not(self, a: str) -> str:
        return self._bool(f"{a} == {self.constant(0.0)}")

    def _print_op_and(self, a: str, b: str) -> str:
        return self._bool(f"{self._true(a)} && {self._true(b)}")

    def _print_op_or(self, a: str, b: str) -> str:
        return self._bool(f"{self._true(a)} || {self._true(b)}")

    def _print_op_if_else_zero(self, cond: str, value: str) -> str:
        return f"{self._true(cond)} ? {value} : {self.constant(0.0)}"

    def _print_op_fmin(self, a: str, b: str) -> str:
        return f"({b} < {a}) ? {b} : {a}"

    def _print_op_fmax(self, a: str, b: str) -> str:
        return f"({b} > {a}) ? {b} : {a}"

    def _print_op_sign(self, a: str) -> str:
        zero = self.constant(0.0)
        return (f"({a} < {zero}) ? {self.constant(-1.0)} : "
                f"(({a} > {zero}) ? {self.constant(1.0)} : {a})")

    # ------------------------------------------------------------- constants
    def _print_float(self, value: float) -> str:
        return repr(value) + self.precision.suffix

    def _print_inf(self, negative: bool) -> str:
        return ("-" if negative else "") + self.precision.huge

    def _print_nan(self) -> str:
        return self.precision.nan

    # ------------------------------------------------------------ statements
    def _assign(self, target: str, expr: str) -> str:
        return f"{target} = {expr};"

    def _input_ref(self, spec: IOSpec, position: int) -> str:
        return f"{self.io_name('in', spec.index)}[{position}]"

    def _output_ref(self, spec: IOSpec, position: int) -> str:
        return f"{self.io_name('out', spec.index)}[{position}]"

    def function_name(self, program: Program) -> str:
        """C name of the generated function: ``prefix`` + the sanitised CasADi name."""
        return self.prefix + c_identifier(program.name, set())

    def print_function(self, program: FunctionLike) -> str:  # noqa: D102
        if not isinstance(program, Program):
            program = lower(program)
        self._name_io(program, c_identifier)
        return super().print_function(program)

    def signature(self, program: Program) -> str:
        """``static void name(const real* in..., real* out...)`` (no trailing ``;``)."""
        params = [f"const {self.real}* {self.io_name('in', s.index)}" for s in program.inputs]
        params += [f"{self.real}* {self.io_name('out', s.index)}" for s in program.outputs]
        return f"static void {self.function_name(program)}({', '.join(params) or 'void'})"

    def _function_text(self, program: Program, body: List[str]) -> str:
        used_inputs = {ins.input_index for ins in program.instructions if isinstance(ins, Input)}
        written = {(ins.output_index, ins.position) for ins in program.instructions
                   if isinstance(ins, Output)}
        registers = sorted({ins.dest for ins in program.instructions
                            if not isinstance(ins, Output)})
        lines = [f"/* CasADi Function {program.name!r}: {len(program.instructions)} instructions. */",
                 self.signature(program) + " {"]
        # one declaration per line (MISRA C:2012 rule 12.3 reads a comma there as the
        # comma operator)
        lines += [f"  {self.real} {self.register(r)};" for r in registers]
        for spec in program.inputs:
            if spec.index not in used_inputs:
                lines.append(f"  (void){self.io_name('in', spec.index)};")
        for spec in program.outputs:
            for position in range(spec.numel):
                if (spec.index, position) not in written:
                    lines.append(f"  {self._output_ref(spec, position)} = {self.constant(0.0)};")
        lines += ["  " + stmt for stmt in body]
        lines.append("}")
        return "\n".join(lines) + "\n"

    def _module_text(self, programs: List[Program], functions: List[str]) -> str:
        names = [self.function_name(p) for p in programs]
        for name in names:
            if names.count(name) > 1:
                raise EmitError(f"two Functions map to the C name {name!r}")
        used = {ins.op for p in programs for ins in p.instructions if isinstance(ins, Unary)}
        support = []
        for op, name in c_maths.FUNCTIONS:
            if op in self.precision.own and op in used:
                if name in names:
                    raise EmitError(f"a Function maps to the C name {name!r} of the maths "
                                    "function the printer defines")
                support.append(c_maths.source(op))
        return "\n".join(support + functions)


def c_source(functions: Union[FunctionLike, Sequence[FunctionLike]],
             precision: str = "double", real: str = "", prefix: str = "") -> str:
    """C text of one static function per CasADi Function (no includes, no typedef).

    Parameters
    ----------
    functions : casadi.Function or Program, or a sequence of them
    precision : {"double", "single"}
    real : str, optional
        Name of the real type used in the text (default ``double``/``float``).
    prefix : str, optional
        Prefix of the function names.

    Returns
    -------
    str

    Raises
    ------
    UnsupportedOperation, EmitError
        As :class:`CPrinter`.
    """
    return CPrinter(precision, real, prefix).doprint(functions)
