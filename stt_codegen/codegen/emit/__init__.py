"""Code emitter: CasADi SX Functions to source code, one printer per language.

* :mod:`.instructions` lowers a Function to a deterministic instruction stream.
* :mod:`.ops` is the table of supported CasADi operations.
* :mod:`.counts` counts operations per op and per category.
* :mod:`.printer` is the base printer; :mod:`.python_printer` prints Python.
"""

from .counts import OperationCounts, count_operations
from .errors import EmitError, UnsupportedOperation
from .instructions import (Binary, Const, IfElseZero, Input, Instruction, IOSpec, Output,
                           Program, Unary, lower)
from .printer import InstructionPrinter
from .python_printer import PythonPrinter, python_function, python_source

__all__ = [
    "Binary",
    "Const",
    "EmitError",
    "IfElseZero",
    "Input",
    "IOSpec",
    "Instruction",
    "InstructionPrinter",
    "OperationCounts",
    "Output",
    "Program",
    "PythonPrinter",
    "Unary",
    "UnsupportedOperation",
    "count_operations",
    "lower",
    "python_function",
    "python_source",
]
