"""Operation counts of a Function, per op and per cost category (for benchmarks)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Union

import casadi

from .instructions import Program, lower, op_name
from .ops import CATEGORIES, OPS_BY_NAME

__all__ = ["OperationCounts", "count_operations"]


@dataclass(frozen=True)
class OperationCounts:
    """How many VM instructions of each kind a Function executes per call.

    Attributes
    ----------
    by_op : dict of str to int
        Count per op name, keys sorted alphabetically.
    by_category : dict of str to int
        Count per category (``"data"``, ``"arithmetic"``, ``"logic"``,
        ``"transcendental"``; see :mod:`stt_codegen.codegen.emit.ops`), all four keys present.
    """

    by_op: Dict[str, int]
    by_category: Dict[str, int]

    @property
    def arithmetic(self) -> int:
        """Number of arithmetic operations."""
        return self.by_category["arithmetic"]

    @property
    def transcendental(self) -> int:
        """Number of maths-library calls (exp, log, tanh, sqrt, pow, ...)."""
        return self.by_category["transcendental"]

    @property
    def logic(self) -> int:
        """Number of comparisons, boolean operations and ``if_else_zero``."""
        return self.by_category["logic"]

    @property
    def total(self) -> int:
        """Number of instructions, data moves included."""
        return sum(self.by_category.values())


def count_operations(fn: Union[casadi.Function, Program]) -> OperationCounts:
    """Count the operations of an SX Function (or of its lowered :class:`Program`).

    Parameters
    ----------
    fn : casadi.Function or Program

    Returns
    -------
    OperationCounts

    Raises
    ------
    UnsupportedOperation, EmitError
        As :func:`stt_codegen.codegen.emit.instructions.lower`.
    """
    program = fn if isinstance(fn, Program) else lower(fn)
    by_op: Dict[str, int] = {}
    for ins in program.instructions:
        name = op_name(ins)
        by_op[name] = by_op.get(name, 0) + 1
    by_category = {c: 0 for c in CATEGORIES}
    for name, n in by_op.items():
        by_category[OPS_BY_NAME[name].category] += n
    return OperationCounts(dict(sorted(by_op.items())), by_category)
