"""The pair of state dimensions a figure of the arena is drawn on (``--dims I,J``).

Apart from :mod:`.plots` so that a command checks ``--dims`` before any work without
importing matplotlib (docs/performance.md, command overhead).
"""

from __future__ import annotations

import numpy as np

from ..errors import SpecError

__all__ = ["DEFAULT_DIMS", "check_dims", "parse_dims"]

#: The state dimensions the arena is drawn on unless told otherwise.
DEFAULT_DIMS = (0, 1)


def check_dims(dims: tuple[int, int], n: int) -> tuple[int, int]:
    """Validate the pair of state dimensions an arena is drawn on.

    Parameters
    ----------
    dims : tuple of int, length 2
        Zero-based state indices ``(i, j)``: ``x_{i+1}`` horizontal, ``x_{j+1}`` vertical.
    n : int
        State dimension of the spec.

    Returns
    -------
    tuple of int
        ``dims`` as plain ints.

    Raises
    ------
    SpecError
        Field ``dims``: not two different integers in ``0..n-1``.
    """
    pair = tuple(dims)
    if (len(pair) != 2 or not all(isinstance(d, (int, np.integer)) and not isinstance(d, bool)
                                  for d in pair)):
        raise SpecError("dims", f"must be two dimension indices, got {dims!r}")
    if n < 2:
        raise SpecError("dims", f"the state space has {n} dimension: no pair to plot")
    i, j = int(pair[0]), int(pair[1])
    if i == j or not (0 <= i < n and 0 <= j < n):
        raise SpecError("dims", f"must be two different dimension indices in 0..{n - 1}, "
                                f"got {i},{j}")
    return i, j


def parse_dims(text: str | None, n: int) -> tuple[int, int]:
    """The pair of a command line's ``--dims I,J`` (:data:`DEFAULT_DIMS` when not given).

    Parameters
    ----------
    text : str or None
        ``"I,J"``, zero-based state indices.
    n : int
        State dimension of the spec.

    Returns
    -------
    tuple of int, length 2
        The two distinct state dimensions ``(I, J)``.

    Raises
    ------
    SpecError
        Field ``dims``: not two comma-separated integers, or not a valid pair
        (:func:`check_dims`).
    """
    if text is None:
        return DEFAULT_DIMS
    parts = text.split(",")
    try:
        i, j = (int(p) for p in parts)
    except ValueError:      # not integers, or not two of them
        raise SpecError("dims", f"expected two integers I,J, got {text!r}") from None
    return check_dims((i, j), n)
