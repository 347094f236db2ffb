"""A certificate's per-sample step folded into a loop that CasADi's virtual machine runs.

A sampled certificate propagates an enclosure of the error from one sample to the next:
each step depends on the one before, so the loop is sequential. A step written once on
CasADi ``SX`` symbols (:data:`~.operations.SYMBOLS`, without simplifications: the same IEEE
operations in the same order as on floats) as a function ``(state, column, constants) ->
(next state, figures)`` is unrolled :data:`UNROLLED` times and folded with ``mapaccum``
(no C compiler); :func:`run_steps` evaluates it over the samples in chunks and stops after
the first chunk in which a judgement fails, so a refusal costs about as many steps as a
loop that stops at the failing sample. The cascade's certificate
(:mod:`.cascade_step`) and law (13)'s per-axis check (:mod:`.sampled_fold`) are written so.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import casadi
import numpy as np

from .operations import exact_symbols

__all__ = ["FIRST_CHUNK", "LONGEST_CHUNK", "StepLayout", "StepSymbols", "UNROLLED", "run_steps",
           "split"]

#: Steps of the first chunk :func:`run_steps` evaluates; each next chunk is twice as long,
#: up to :data:`LONGEST_CHUNK`.
FIRST_CHUNK = 64
#: The longest chunk.
LONGEST_CHUNK = 4096


class StepLayout:
    """The rows of a step's columns and constants: ``layout.rows(name)`` is the slice of
    ``name``'s rows, ``layout.size`` their number.

    Parameters
    ----------
    blocks : sequence of (str, int)
        Each name and its number of rows, in order.
    """

    def __init__(self, blocks) -> None:
        self.blocks, start = {}, 0
        for name, size in blocks:
            self.blocks[name] = slice(start, start + size)
            start += size
        self.size = start

    def rows(self, name: str) -> slice:
        """The rows of ``name``."""
        return self.blocks[name]

    def pack(self, values: dict, width: int | None = None) -> np.ndarray:
        """The column(s) of ``values`` (each ``(size,)`` or ``(size, width)``) in order."""
        shape = (self.size,) if width is None else (self.size, width)
        out = np.empty(shape)
        for name, rows in self.blocks.items():
            out[rows] = values[name]
        return out


def split(symbol, layout: StepLayout, name: str) -> list:
    """The entries of ``symbol`` (a column or the constants) in ``name``'s rows."""
    return [symbol[j] for j in range(layout.rows(name).start, layout.rows(name).stop)]


class StepSymbols:
    """The inputs of a step, built within :func:`~.operations.exact_symbols`: ``state``
    (``rows`` entries), ``column`` and ``constants`` (``SX``), and their entries by name,
    ``c[name]`` of the column and ``p[name]`` of the constants (lists of ``SX``).

    Parameters
    ----------
    rows : int
        Rows of the state.
    columns, constants : StepLayout
    """

    def __init__(self, rows: int, columns: StepLayout, constants: StepLayout) -> None:
        self.state = casadi.SX.sym("state", rows)
        self.column = casadi.SX.sym("column", columns.size)
        self.constants = casadi.SX.sym("constants", constants.size)
        self.c = {name: split(self.column, columns, name) for name in columns.blocks}
        self.p = {name: split(self.constants, constants, name) for name in constants.blocks}

    def function(self, name: str, following, shown) -> casadi.Function:
        """The step ``(state, column, constants) -> (following, shown)``, one node per
        distinct operation on the same operands (the same doubles)."""
        return casadi.Function(name, [self.state, self.column, self.constants],
                               casadi.cse([following, shown]))


#: Steps written out one after the other in one function (:func:`_block`), which
#: ``mapaccum`` then repeats: a call of a folded function costs about as much as a few
#: hundred operations, once per block instead of once per step.
UNROLLED = 16


@lru_cache(maxsize=16)
def _block(step: casadi.Function) -> casadi.Function:
    """:data:`UNROLLED` steps of ``step`` in one function ``(state, columns, constants) ->
    (state after them, the states and figures after each step)``."""
    with exact_symbols():
        state = casadi.SX.sym("state", step.size1_in(0))
        columns = casadi.SX.sym("columns", step.size1_in(1), UNROLLED)
        constants = casadi.SX.sym("constants", step.size1_in(2))
        shown, now = [], state
        for j in range(UNROLLED):
            now, figures = step(now, columns[:, j], constants)
            shown.append(casadi.vertcat(now, figures))
        return casadi.Function(f"{step.name()}_block", [state, columns, constants],
                               [now, casadi.horzcat(*shown)])


@lru_cache(maxsize=64)
def _folded(step: casadi.Function, blocks: int) -> casadi.Function:
    return _block(step).mapaccum(f"{step.name()}_{blocks}", blocks)


def run_steps(step: casadi.Function, start: np.ndarray,
              columns: Callable[[int, int], np.ndarray], count: int,
              constants: np.ndarray, failed: Callable[[np.ndarray], bool],
              progress: Callable[[int], None] | None = None, kinds: int = 8
              ) -> tuple[np.ndarray, np.ndarray]:
    """Run ``step`` from ``start`` over ``count`` steps, in chunks, until the end or the
    first chunk in which ``failed`` is true.

    Parameters
    ----------
    step : casadi.Function
        ``(state, column, constants) -> (next state, figures)``, the figures ``kinds``
        rows per axis (:func:`~.cascade_step.sampled_step`, :func:`~.sampled_fold.axis_step`).
    start : ndarray, (rows of the state,)
        The state before the first step.
    columns : callable
        ``columns(a, b)``: the columns of steps ``a .. b - 1``, ``(rows of a column, b -
        a)`` (computed when a chunk needs them: a check that fails early computes few).
    count : int
        Steps.
    constants : ndarray, (rows of the constants,)
    failed : callable
        Given the figures of a chunk, ``(kinds, n, steps)``, whether a judgement fails in
        it.
    progress : callable, optional
        Called with the steps done before each chunk.
    kinds : int
        Figures per axis (the cascade's :data:`~.cascade_step.FIGURES`: 8).

    Returns
    -------
    figures : ndarray, (kinds, n, steps done)
        The figures of every step run (every step of a chunk that failed, and no more).
    state : ndarray, (rows of the state,)
        After the last step run.
    """
    rows = step.size1_in(0)
    n = step.size1_out(1) // kinds
    shown, state, done, chunk = [], np.asarray(start, dtype=float), 0, FIRST_CHUNK
    while done < count:
        if progress is not None:
            progress(done)
        length = min(chunk, count - done)
        blocks = -(-length // UNROLLED)
        blocks = 1 << (blocks - 1).bit_length()   # a power of two: few folded functions
        block = columns(done, done + length)
        if blocks * UNROLLED > length:            # a shorter last chunk, padded
            block = np.hstack([block, np.repeat(block[:, -1:], blocks * UNROLLED - length,
                                                axis=1)])
        _, after = _folded(step, blocks)(state, block,
                                         np.repeat(constants[:, None], blocks, axis=1))
        after = np.asarray(after)[:, :length]
        state = after[:rows, -1]
        shown.append(after[rows:].reshape(kinds, n, length))
        done += length
        if failed(shown[-1]):
            break
        chunk = min(2 * chunk, LONGEST_CHUNK)
    return np.concatenate(shown, axis=2), state
