"""Lower a CasADi SX ``Function`` to a language-neutral instruction stream.

The stream is read from CasADi's own virtual machine (``Function.n_instructions``,
``instruction_id``, ``instruction_input``, ``instruction_output``,
``instruction_constant``), one instruction per VM instruction, in the VM's order and
with the VM's work-register numbers: CasADi reuses registers (live-variable analysis),
and keeping its numbering means generated code performs exactly the same operations,
in the same order, on the same intermediate values as ``f(...)`` on ``DM``.

Inputs and outputs are addressed by their nonzero (sparse storage) index ``nz`` in
CasADi; each instruction also carries ``position``, the matching index into the dense
column-major vector of the input or output (``row + col * nrow``).

Nothing here iterates over a set or a dict keyed by SX objects (their hash is their
address, which changes from run to run): the stream depends only on the Function.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Tuple, Union

import casadi

from .errors import EmitError, UnsupportedOperation
from .ops import OPS, casadi_op_name

__all__ = ["Binary", "Const", "IOSpec", "IfElseZero", "Input", "Instruction", "OPS", "Output",
           "Program", "Unary", "lower", "op_name"]


@dataclass(frozen=True)
class Input:
    """``w[dest] = input[input_index][position]`` (nonzero ``nz`` of that input).

    Attributes
    ----------
    dest : int
        Work register written.
    input_index : int
        Which input of the Function.
    nz : int
        Index among that input's nonzeros.
    position : int
        Dense column-major index of that nonzero.
    """

    dest: int
    input_index: int
    nz: int
    position: int


@dataclass(frozen=True)
class Output:
    """``output[output_index][position] = w[src]`` (nonzero ``nz`` of that output).

    Attributes
    ----------
    output_index : int
        Which output of the Function.
    nz : int
        Index among that output's nonzeros.
    position : int
        Dense column-major index of that nonzero.
    src : int
        Work register read.
    """

    output_index: int
    nz: int
    position: int
    src: int


@dataclass(frozen=True)
class Const:
    """``w[dest] = value`` (a double, possibly ``inf``, ``-inf``, ``nan`` or ``-0.0``).

    Attributes
    ----------
    dest : int
        Work register written.
    value : float
        The constant.
    """

    dest: int
    value: float


@dataclass(frozen=True)
class Unary:
    """``w[dest] = op(w[arg])``; ``op`` is an op name of :mod:`stt_codegen.codegen.emit.ops`.

    Attributes
    ----------
    op : str
        The operation's name.
    dest : int
        Work register written.
    arg : int
        Work register read.
    """

    op: str
    dest: int
    arg: int


@dataclass(frozen=True)
class Binary:
    """``w[dest] = op(w[a], w[b])``; for ``constpow`` ``w[b]`` holds the exponent.

    Attributes
    ----------
    op : str
        The operation's name.
    dest : int
        Work register written.
    a, b : int
        Work registers read, in operand order.
    """

    op: str
    dest: int
    a: int
    b: int


@dataclass(frozen=True)
class IfElseZero:
    """``w[dest] = 0.0 if w[cond] == 0 else w[value]`` (0.0 even if the value is NaN).

    Attributes
    ----------
    dest : int
        Work register written.
    cond : int
        Work register of the condition.
    value : int
        Work register of the value.
    """

    dest: int
    cond: int
    value: int


Instruction = Union[Input, Output, Const, Unary, Binary, IfElseZero]


@dataclass(frozen=True)
class IOSpec:
    """Shape and sparsity of one input or output of the Function.

    Attributes
    ----------
    name : str
        CasADi name of the input/output.
    index : int
        Its index among the inputs (or outputs).
    nrow, ncol : int
        Dense shape; the dense vector has ``nrow * ncol`` entries, column-major.
    positions : tuple of int, length nnz
        Dense column-major position of each nonzero, in CasADi's storage order.
    """

    name: str
    index: int
    nrow: int
    ncol: int
    positions: Tuple[int, ...]

    @property
    def numel(self) -> int:
        """Number of entries of the dense vector, ``nrow * ncol``."""
        return self.nrow * self.ncol

    @property
    def nnz(self) -> int:
        """Number of structural nonzeros."""
        return len(self.positions)


@dataclass(frozen=True)
class Program:
    """Instruction stream of one Function, with its interface.

    Attributes
    ----------
    name : str
        Name of the CasADi Function.
    inputs, outputs : tuple of IOSpec
        Interface, in CasADi order.
    instructions : tuple of Instruction
        The VM's instructions, in order.
    n_registers : int
        ``1 + `` the largest work-register index used (0 if none).
    """

    name: str
    inputs: Tuple[IOSpec, ...]
    outputs: Tuple[IOSpec, ...]
    instructions: Tuple[Instruction, ...]
    n_registers: int


def _positions(sparsity: casadi.Sparsity) -> Tuple[int, ...]:
    rows, cols = sparsity.get_triplet()
    nrow = sparsity.size1()
    return tuple(int(r) + int(c) * nrow for r, c in zip(rows, cols))


def _io_specs(fn: casadi.Function, n: int, name_of, sparsity_of) -> Tuple[IOSpec, ...]:
    specs = []
    for i in range(n):
        sp = sparsity_of(i)
        specs.append(IOSpec(name_of(i), i, sp.size1(), sp.size2(), _positions(sp)))
    return tuple(specs)


def _lower_one(fn: casadi.Function, k: int, inputs, outputs) -> Instruction:
    code = fn.instruction_id(k)
    info = OPS.get(code)
    if info is None:
        raise UnsupportedOperation(
            casadi_op_name(code), fn.name(), f"instruction {k} has no translation in the emitter"
        )
    args: List[int] = [int(v) for v in fn.instruction_input(k)]
    res: List[int] = [int(v) for v in fn.instruction_output(k)]
    name = info.name
    if name == "input":
        index, nz = args
        return Input(res[0], index, nz, inputs[index].positions[nz])
    if name == "output":
        index, nz = res
        return Output(index, nz, outputs[index].positions[nz], args[0])
    if name == "const":
        return Const(res[0], float(fn.instruction_constant(k)))
    if name == "if_else_zero":
        return IfElseZero(res[0], args[0], args[1])
    if info.arity == 1:
        return Unary(name, res[0], args[0])
    return Binary(name, res[0], args[0], args[1])


def lower(fn: casadi.Function) -> Program:
    """Turn an SX Function into a :class:`Program` (deterministic instruction stream).

    Parameters
    ----------
    fn : casadi.Function
        An SX Function (``fn.is_a("SXFunction")``) without free symbols.

    Returns
    -------
    Program
        Instructions in CasADi's VM order, with CasADi's register numbers.

    Raises
    ------
    EmitError
        If ``fn`` is not an SX Function.
    UnsupportedOperation
        If an instruction's op is not in :data:`stt_codegen.codegen.emit.ops.OPS` (this
        includes ``OP_PARAMETER``, i.e. free symbols, and ``OP_CALL``); the message
        names the op and the Function.
    """
    if not isinstance(fn, casadi.Function):
        raise EmitError(f"expected a casadi.Function, got {type(fn).__name__}")
    if not fn.is_a("SXFunction"):
        raise EmitError(
            f"CasADi Function {fn.name()!r} is a {fn.class_name()}, not an SXFunction; "
            "build it from SX symbols (or call .expand() on it first)"
        )
    inputs = _io_specs(fn, fn.n_in(), fn.name_in, fn.sparsity_in)
    outputs = _io_specs(fn, fn.n_out(), fn.name_out, fn.sparsity_out)
    instructions = tuple(
        _lower_one(fn, k, inputs, outputs) for k in range(fn.n_instructions())
    )
    n_registers = 0
    for ins in instructions:
        for reg in registers_of(ins):
            n_registers = max(n_registers, reg + 1)
    return Program(fn.name(), inputs, outputs, instructions, n_registers)


def registers_of(ins: Instruction) -> Tuple[int, ...]:
    """Work registers read or written by one instruction.

    Parameters
    ----------
    ins : Instruction

    Returns
    -------
    tuple of int
        Written register first (if any), then the registers read.
    """
    if isinstance(ins, Input):
        return (ins.dest,)
    if isinstance(ins, Output):
        return (ins.src,)
    if isinstance(ins, Const):
        return (ins.dest,)
    if isinstance(ins, Unary):
        return (ins.dest, ins.arg)
    if isinstance(ins, Binary):
        return (ins.dest, ins.a, ins.b)
    return (ins.dest, ins.cond, ins.value)


def op_name(ins: Instruction) -> str:
    """Op name of an instruction (``"input"``, ``"const"``, ``"add"``, ...).

    Parameters
    ----------
    ins : Instruction

    Returns
    -------
    str
    """
    if isinstance(ins, (Unary, Binary)):
        return ins.op
    return {
        Input: "input",
        Output: "output",
        Const: "const",
        IfElseZero: "if_else_zero",
    }[type(ins)]
