"""Base class of the instruction printers (one subclass per target language).

Modelled on SymPy's ``CodePrinter``: :meth:`InstructionPrinter.doprint` walks the
instruction stream of each Function and dispatches every instruction to a
``_print_<Kind>`` method (``_print_Input``, ``_print_Output``, ``_print_Const``,
``_print_Unary``, ``_print_Binary``, ``_print_IfElseZero``). Unary and binary ops are
rendered by :meth:`InstructionPrinter.op_expression`, which looks, in this order, for

1. a method ``_print_op_<op>(*operands)`` (e.g. ``_print_op_fmax``);
2. ``known_functions[op]``: the op is a call ``name(operands...)``;
3. ``infix_operators[op]``: the op is ``a <symbol> b``;

and otherwise raises :class:`~stt_codegen.codegen.emit.errors.UnsupportedOperation`.

Shared logic lives here: register names (``w<k>``, CasADi's register numbers kept),
constants (``repr(float)``: shortest text that reads back to the same double, never a
fixed number of decimals; ``inf``/``nan`` through :meth:`_print_inf`/:meth:`_print_nan`),
the ops that reduce to other ops (``sq`` is ``mul(x, x)``, ``twice`` is ``add(x, x)``,
``inv`` is ``div(1.0, x)``, ``constpow`` is ``pow``, ``assign`` is a copy), and tracking of
registers that hold a known constant (:meth:`known_value`), so that a printer can skip a
guard, e.g. on a division by a nonzero constant.

A C-like printer needs only: the statement hooks (:meth:`_assign`, :meth:`_input_ref`,
:meth:`_output_ref`, :meth:`_function_text`, :meth:`_module_text`), its
``known_functions``/``infix_operators`` tables, and the few ops whose semantics need
care (comparisons, ``if_else_zero``, ``fmin``/``fmax``, ``sign``).
"""

from __future__ import annotations

import math
from typing import Dict, List, Mapping, Optional, Sequence, Tuple, Union

import casadi

from .errors import EmitError, UnsupportedOperation
from .instructions import (Binary, Const, IfElseZero, Input, Instruction, IOSpec, Output,
                           Program, Unary, lower)

__all__ = ["FunctionLike", "InstructionPrinter"]

FunctionLike = Union[casadi.Function, Program]


class InstructionPrinter:
    """Print :class:`~stt_codegen.codegen.emit.instructions.Program` s as source code.

    Subclasses set :attr:`language`, :attr:`known_functions`, :attr:`infix_operators`
    and implement the hooks that raise ``NotImplementedError`` here.

    Examples
    --------
    The C and Python printers print the same instruction stream of a CasADi SX Function:

    >>> import casadi as ca
    >>> from stt_codegen.codegen.emit.c_printer import CPrinter
    >>> x = ca.SX.sym("x")
    >>> twice_sin = ca.Function("twice_sin", [x], [2 * ca.sin(x)], ["x"], ["y"])
    >>> print(CPrinter().print_function(twice_sin))
    /* CasADi Function 'twice_sin': 4 instructions. */
    static void twice_sin(const double* x, double* y) {
      double w0;
      w0 = x[0];
      w0 = sin(w0);
      w0 = w0 + w0;
      y[0] = w0;
    }
    """

    #: Name of the target language, used in error messages.
    language: str = "abstract"
    #: Prefix of work-register names (register k is ``f"{register_prefix}{k}"``).
    register_prefix: str = "w"
    #: Op name -> callable name, for ops printed as ``name(operands...)``.
    known_functions: Mapping[str, str] = {}
    #: Op name -> infix symbol, for binary ops printed as ``a <symbol> b``.
    infix_operators: Mapping[str, str] = {}

    def __init__(self) -> None:
        self._program: Optional[Program] = None
        self._known: Dict[str, float] = {}

    # ------------------------------------------------------------------ entry points
    def doprint(self, functions: Union[FunctionLike, Sequence[FunctionLike]]) -> str:
        """Print a whole source file holding one function per CasADi Function.

        Parameters
        ----------
        functions : casadi.Function or Program, or a sequence of them
            SX Functions (lowered with :func:`~stt_codegen.codegen.emit.instructions.lower`)
            or already lowered programs; printed in the given order.

        Returns
        -------
        str
            Source text, deterministic for given Functions and CasADi version.
        """
        if isinstance(functions, (casadi.Function, Program)):
            functions = [functions]
        programs = [f if isinstance(f, Program) else lower(f) for f in functions]
        names = [p.name for p in programs]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise EmitError(f"several Functions named {duplicates[0]!r} in one file")
        texts = [self.print_function(p) for p in programs]
        return self._module_text(programs, texts)

    def print_function(self, program: FunctionLike) -> str:
        """Print one function (without the file's header or support code).

        Parameters
        ----------
        program : casadi.Function or Program

        Returns
        -------
        str
        """
        if not isinstance(program, Program):
            program = lower(program)
        self._program = program
        self._known = {}
        try:
            body = [self._print(ins) for ins in self._track(program.instructions)]
            return self._function_text(program, body)
        finally:
            self._program = None
            self._known = {}

    # --------------------------------------------------------------------- dispatch
    def _track(self, instructions: Sequence[Instruction]):
        """Yield instructions, updating :meth:`known_value` after each one is printed."""
        for ins in instructions:
            yield ins
            if isinstance(ins, Output):
                continue
            dest = self.register(ins.dest)
            if isinstance(ins, Const):
                self._known[dest] = ins.value
            elif isinstance(ins, Unary) and ins.op == "assign" and self.register(ins.arg) in self._known:
                self._known[dest] = self._known[self.register(ins.arg)]
            else:
                self._known.pop(dest, None)

    def _print(self, ins: Instruction) -> str:
        method = getattr(self, "_print_" + type(ins).__name__, None)
        if method is None:  # pragma: no cover - every kind has a method
            raise EmitError(f"{type(self).__name__} cannot print {type(ins).__name__}")
        return method(ins)

    def _print_Input(self, ins: Input) -> str:
        spec = self.program.inputs[ins.input_index]
        return self._assign(self.register(ins.dest), self._input_ref(spec, ins.position))

    def _print_Output(self, ins: Output) -> str:
        spec = self.program.outputs[ins.output_index]
        return self._assign(self._output_ref(spec, ins.position), self.register(ins.src))

    def _print_Const(self, ins: Const) -> str:
        return self._assign(self.register(ins.dest), self.constant(ins.value))

    def _print_Unary(self, ins: Unary) -> str:
        expr = self.op_expression(ins.op, (self.register(ins.arg),))
        return self._assign(self.register(ins.dest), expr)

    def _print_Binary(self, ins: Binary) -> str:
        expr = self.op_expression(ins.op, (self.register(ins.a), self.register(ins.b)))
        return self._assign(self.register(ins.dest), expr)

    def _print_IfElseZero(self, ins: IfElseZero) -> str:
        expr = self.op_expression("if_else_zero", (self.register(ins.cond), self.register(ins.value)))
        return self._assign(self.register(ins.dest), expr)

    def op_expression(self, op: str, operands: Tuple[str, ...]) -> str:
        """Expression computing ``op`` on already printed operands.

        Parameters
        ----------
        op : str
            Op name (see :mod:`stt_codegen.codegen.emit.ops`).
        operands : tuple of str
            Printed operands (register names or constants).

        Returns
        -------
        str

        Raises
        ------
        UnsupportedOperation
            If this printer has no translation for ``op``.
        """
        method = getattr(self, "_print_op_" + op, None)
        if method is not None:
            return method(*operands)
        if op in self.known_functions:
            return f"{self.known_functions[op]}({', '.join(operands)})"
        if op in self.infix_operators and len(operands) == 2:
            return f"{operands[0]} {self.infix_operators[op]} {operands[1]}"
        name = self._program.name if self._program is not None else "?"
        raise UnsupportedOperation(
            op, name, f"{type(self).__name__} has no {self.language} translation for it"
        )

    # ------------------------------------------------------- ops shared by languages
    def _print_op_assign(self, a: str) -> str:
        return a

    def _print_op_sq(self, a: str) -> str:
        return self.op_expression("mul", (a, a))

    def _print_op_twice(self, a: str) -> str:
        return self.op_expression("add", (a, a))

    def _print_op_inv(self, a: str) -> str:
        return self.op_expression("div", (self.constant(1.0), a))

    def _print_op_neg(self, a: str) -> str:
        return f"-{a}"

    def _print_op_constpow(self, a: str, b: str) -> str:
        return self.op_expression("pow", (a, b))

    #: Comparison op name -> infix symbol (the result is 1 or 0, see :meth:`_compare`).
    comparisons: Mapping[str, str] = {"lt": "<", "le": "<=", "eq": "==", "ne": "!="}

    def _compare(self, op: str, a: str, b: str) -> str:
        """Expression that is 1 when ``a comparisons[op] b`` holds, else 0 (per language)."""
        raise NotImplementedError

    def _print_op_lt(self, a: str, b: str) -> str:
        return self._compare("lt", a, b)

    def _print_op_le(self, a: str, b: str) -> str:
        return self._compare("le", a, b)

    def _print_op_eq(self, a: str, b: str) -> str:
        return self._compare("eq", a, b)

    def _print_op_ne(self, a: str, b: str) -> str:
        return self._compare("ne", a, b)

    def _name_io(self, program: Program, identifier) -> None:
        """Name every input and output of ``program`` with ``identifier(name, taken)``
        (distinct names, inputs first); see :meth:`io_name`."""
        taken: set = set()
        self._io_names: Dict[Tuple[str, int], str] = {}
        for kind, specs in (("in", program.inputs), ("out", program.outputs)):
            for spec in specs:
                ident = identifier(spec.name, taken)
                taken.add(ident)
                self._io_names[kind, spec.index] = ident

    def io_name(self, kind: str, index: int) -> str:
        """Name given by :meth:`_name_io` to input (``kind="in"``) or output ``index``."""
        return self._io_names[kind, index]

    # ------------------------------------------------------------------ shared logic
    @property
    def program(self) -> Program:
        """The program being printed (only during :meth:`print_function`)."""
        if self._program is None:
            raise EmitError("no program is being printed")
        return self._program

    def register(self, index: int) -> str:
        """Name of work register ``index``."""
        return f"{self.register_prefix}{index}"

    def known_value(self, operand: str) -> Optional[float]:
        """Value of a register known to hold a constant at this point, else ``None``.

        Parameters
        ----------
        operand : str
            A printed operand (register name).

        Returns
        -------
        float or None
        """
        return self._known.get(operand)

    def constant(self, value: float) -> str:
        """Print a double constant exactly.

        Finite values use ``repr(float(value))``, the shortest decimal text that reads
        back to the same double (``-0.0`` keeps its sign); infinities and NaN are
        delegated to :meth:`_print_inf` and :meth:`_print_nan`.

        Parameters
        ----------
        value : float

        Returns
        -------
        str
        """
        value = float(value)
        if math.isnan(value):
            return self._print_nan()
        if math.isinf(value):
            return self._print_inf(value < 0)
        return self._print_float(value)

    def _print_float(self, value: float) -> str:
        return repr(value)

    # ------------------------------------------------------------ hooks (per language)
    def _print_inf(self, negative: bool) -> str:
        raise NotImplementedError

    def _print_nan(self) -> str:
        raise NotImplementedError

    def _assign(self, target: str, expr: str) -> str:
        """Statement storing ``expr`` into ``target``."""
        raise NotImplementedError

    def _input_ref(self, spec: IOSpec, position: int) -> str:
        """Expression reading dense entry ``position`` of input ``spec``."""
        raise NotImplementedError

    def _output_ref(self, spec: IOSpec, position: int) -> str:
        """Assignable reference to dense entry ``position`` of output ``spec``."""
        raise NotImplementedError

    def _function_text(self, program: Program, body: List[str]) -> str:
        """Wrap the body statements into a complete function definition."""
        raise NotImplementedError

    def _module_text(self, programs: List[Program], functions: List[str]) -> str:
        """Assemble the file: header, support code and function texts."""
        raise NotImplementedError
