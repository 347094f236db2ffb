"""Code emitter: CasADi SX Functions to source code, one printer per language.

* :mod:`.instructions` lowers a Function to a deterministic instruction stream.
* :mod:`.ops` is the table of supported CasADi operations.
* :mod:`.counts` counts operations per op and per category.
* :mod:`.printer` is the base printer; :mod:`.c_printer` prints C (double or single),
  :mod:`.python_printer` prints Python, :mod:`.sympy_printer` builds SymPy expressions.

The SymPy printer's names are imported on first use (PEP 562): generating code does not
import SymPy, only the proofs do.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .counts import OperationCounts, count_operations
from .errors import EmitError, UnsupportedOperation
from .instructions import (Binary, Const, IfElseZero, Input, Instruction, IOSpec, Output,
                           Program, Unary, lower)
from .c_printer import CPrinter, Precision, c_source
from .printer import InstructionPrinter
from .python_printer import PythonPrinter, python_function, python_source

if TYPE_CHECKING:
    from .sympy_printer import SymPyPrinter, sympy_expressions

#: The names of :mod:`.sympy_printer`, imported on first attribute access (SymPy is heavy).
_LAZY = ("SymPyPrinter", "sympy_expressions")


def __getattr__(name: str) -> Any:
    """Import the SymPy printer's names on first use (PEP 562)."""
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.sympy_printer"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))

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
