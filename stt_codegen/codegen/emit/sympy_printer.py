"""Turn the instruction stream of a CasADi SX Function into SymPy expressions.

The same stream the C and Python printers print (:func:`~.instructions.lower`), walked by
the same base class, but every register holds a SymPy expression instead of a name, so
that symbolic checks (``stt-codegen verify``) reason about the deployed expressions
themselves. Inputs are SymPy symbols (one per dense entry, given by the caller or named
``<input>_<position>``); constants become exact ``sympy.Float`` values of the double (or
``oo``/``nan``).

Translations: ``fmin``/``fmax`` -> ``Min``/``Max``; comparisons, ``not``/``and``/``or``
-> ``Piecewise((1, condition), (0, True))``; ``if_else_zero(c, y)`` ->
``Piecewise((0, Eq(c, 0)), (y, True))``; ``log1p(x)`` -> ``log(1 + x)``; ``expm1(x)`` ->
``exp(x) - 1``; ``sign``, ``fabs`` -> ``sign``, ``Abs``; ``sq``, ``twice``, ``inv``,
``constpow`` through the base class (``x*x``, ``x + x``, ``1/x``, ``x**c``). Rounding is not
modelled: the expressions are the real-number functions the code evaluates.
"""

from __future__ import annotations

from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import sympy

from .errors import UnsupportedOperation
from .instructions import IOSpec, Program, lower
from .printer import FunctionLike, InstructionPrinter

__all__ = ["SymPyPrinter", "sympy_expressions"]


def _piece(condition) -> sympy.Expr:
    return sympy.Piecewise((sympy.Integer(1), condition), (sympy.Integer(0), True))


class SymPyPrinter(InstructionPrinter):
    """Evaluate a :class:`Program` on SymPy symbols (one printer of the emitter family).

    Parameters
    ----------
    symbols : mapping of str to sequence of sympy.Expr, optional
        Input name -> dense column-major entries (length ``nrow * ncol``); inputs not given
        get fresh symbols ``<name>_<position>``.
    """

    language = "SymPy"
    _functions = {
        "exp": sympy.exp, "log": sympy.log, "sqrt": sympy.sqrt, "tanh": sympy.tanh,
        "sin": sympy.sin, "cos": sympy.cos, "tan": sympy.tan, "asin": sympy.asin,
        "acos": sympy.acos, "atan": sympy.atan, "sinh": sympy.sinh, "cosh": sympy.cosh,
        "asinh": sympy.asinh, "acosh": sympy.acosh, "atanh": sympy.atanh, "erf": sympy.erf,
        "fabs": sympy.Abs, "sign": sympy.sign, "floor": sympy.floor, "ceil": sympy.ceiling,
        "log1p": lambda x: sympy.log(1 + x), "expm1": lambda x: sympy.exp(x) - 1,
        "neg": lambda x: -x, "assign": lambda x: x,
        "add": lambda a, b: a + b, "sub": lambda a, b: a - b, "mul": lambda a, b: a * b,
        "div": lambda a, b: a / b, "pow": lambda a, b: a ** b, "constpow": lambda a, b: a ** b,
        "sq": lambda x: x * x, "twice": lambda x: x + x, "inv": lambda x: 1 / x,
        "fmin": sympy.Min, "fmax": sympy.Max, "atan2": sympy.atan2,
        "lt": lambda a, b: _piece(sympy.Lt(a, b)), "le": lambda a, b: _piece(sympy.Le(a, b)),
        "eq": lambda a, b: _piece(sympy.Eq(a, b)), "ne": lambda a, b: _piece(sympy.Ne(a, b)),
        "not": lambda a: _piece(sympy.Eq(a, 0)),
        "and": lambda a, b: _piece(sympy.And(sympy.Ne(a, 0), sympy.Ne(b, 0))),
        "or": lambda a, b: _piece(sympy.Or(sympy.Ne(a, 0), sympy.Ne(b, 0))),
        "if_else_zero": lambda c, y: sympy.Piecewise((sympy.Integer(0), sympy.Eq(c, 0)),
                                                     (y, True)),
        "copysign": lambda a, b: sympy.Abs(a) * sympy.Piecewise((-1, b < 0), (1, True)),
    }

    def __init__(self, symbols: Optional[Mapping[str, Sequence[sympy.Expr]]] = None) -> None:
        super().__init__()
        self._symbols = dict(symbols or {})
        self._registers: Dict[int, sympy.Expr] = {}
        self._outputs: List[List[sympy.Expr]] = []
        self._constants_text: Dict[str, sympy.Expr] = {}

    def expressions(self, fn: FunctionLike) -> Tuple[List[sympy.Expr], ...]:
        """The outputs of ``fn`` as SymPy expressions.

        Parameters
        ----------
        fn : casadi.Function or Program

        Returns
        -------
        tuple of list of sympy.Expr
            One list per output, dense column-major (structural zeros are ``0``).

        Raises
        ------
        UnsupportedOperation
            For an op without a SymPy translation.
        """
        program = fn if isinstance(fn, Program) else lower(fn)
        self._registers = {}
        self._outputs = [[sympy.Integer(0)] * s.numel for s in program.outputs]
        self.print_function(program)
        return tuple(self._outputs)

    # the base class hands printed operands around as strings: registers are named
    # w<k> and resolved here, constants are kept exactly through a side table
    def op_expression(self, op: str, operands: Tuple[str, ...]):  # noqa: D102
        function = self._functions.get(op)
        if function is None:
            name = self._program.name if self._program is not None else "?"
            raise UnsupportedOperation(op, name, "SymPyPrinter has no translation for it")
        return function(*[self._value(o) for o in operands])

    def _value(self, operand):
        if isinstance(operand, str) and operand in self._constants_text:
            return self._constants_text[operand]
        if isinstance(operand, str) and operand.startswith(self.register_prefix):
            return self._registers[int(operand[len(self.register_prefix):])]
        return operand

    def _print_float(self, value: float) -> str:
        text = repr(value)
        self._constants_text[text] = sympy.Float(value, 17)
        return text

    def _print_inf(self, negative: bool) -> str:
        text = "-oo" if negative else "oo"
        self._constants_text[text] = -sympy.oo if negative else sympy.oo
        return text

    def _print_nan(self) -> str:
        self._constants_text["nan"] = sympy.nan
        return "nan"

    def _assign(self, target, expr) -> str:
        if isinstance(target, tuple):
            index, position = target
            self._outputs[index][position] = self._value(expr)
        else:
            self._registers[int(target[len(self.register_prefix):])] = self._value(expr)
        return ""

    def _input_ref(self, spec: IOSpec, position: int):
        given = self._symbols.get(spec.name)
        if given is not None:
            return sympy.sympify(given[position])
        return sympy.Symbol(f"{spec.name}_{position}", real=True)

    def _output_ref(self, spec: IOSpec, position: int):
        return (spec.index, position)

    def _function_text(self, program: Program, body: List[str]) -> str:
        return ""

    def _module_text(self, programs: List[Program], functions: List[str]) -> str:
        return ""


def sympy_expressions(fn: FunctionLike,
                      symbols: Optional[Mapping[str, Sequence[sympy.Expr]]] = None
                      ) -> Tuple[List[sympy.Expr], ...]:
    """The outputs of a CasADi SX Function as SymPy expressions of its inputs.

    Parameters
    ----------
    fn : casadi.Function or Program
    symbols : mapping of str to sequence of sympy.Expr, optional
        Input name -> its dense entries; default fresh real symbols ``<name>_<position>``.

    Returns
    -------
    tuple of list of sympy.Expr
        One list per output (dense, column-major).
    """
    return SymPyPrinter(symbols).expressions(fn)
