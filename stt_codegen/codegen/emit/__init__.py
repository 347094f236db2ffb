"""Code emitter: CasADi SX Functions to source code, one printer per language.

* :mod:`.instructions` lowers a Function to a deterministic instruction stream.
* :mod:`.ops` is the table of supported CasADi operations.
* :mod:`.counts` counts operations per op and per category.
* :mod:`.printer` is the base printer; :mod:`.c_printer` prints C (double or single),
  :mod:`.python_printer` prints Python, :mod:`.sympy_printer` builds SymPy expressions.
"""

from .counts import OperationCounts, count_operations
from .errors import EmitError, UnsupportedOperation
from .instructions import (Binary, Const, IfElseZero, Input, Instruction, IOSpec, Output,
                           Program, Unary, lower)
from .c_printer import CPrinter, Precision, c_source
from .printer import InstructionPrinter
from .sympy_printer import SymPyPrinter, sympy_expressions
from .python_printer import PythonPrinter, python_function, python_source

__all__ = [
    "Binary",
    "CPrinter",
    "Const",
    "EmitError",
    "IfElseZero",
    "Input",
    "IOSpec",
    "Instruction",
    "InstructionPrinter",
    "OperationCounts",
    "Output",
    "Precision",
    "Program",
    "PythonPrinter",
    "SymPyPrinter",
    "Unary",
    "UnsupportedOperation",
    "c_source",
    "count_operations",
    "lower",
    "python_function",
    "python_source",
    "sympy_expressions",
]
