"""The grid of two-significant-digit numbers on which searches report a value.

A searched rate (Hz) or prescribed time (s) is reported as the smallest number
``m 10^e`` (``10 <= m <= 99``) that passes, so that a refusal names a value a user can
type and two runs name the same one. The grid is indexed by integers (``90 e + m - 10``)
so that a search can bisect on it. A searched prescribed time is then tried once more at the
half step below it (:func:`half_step_below`: 37.5 s between 37 and 38 s), since a time
is compared with a horizon, where 3 % matters.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["MAX_TIME_FACTOR", "grid_index", "grid_value", "half_step_below", "smallest_passing"]

#: The ``prescribed_time`` search tries up to this many times the spec's ``t_c``.
MAX_TIME_FACTOR = 16.0


def grid_index(value: float) -> int:
    """Index of the smallest two-significant-digit number ``>= value`` (``value > 0``).

    Parameters
    ----------
    value : float
        A positive number (a rate in Hz, a time in s).

    Returns
    -------
    int
        ``90 e + m - 10`` for the smallest ``m 10^e >= value``, ``10 <= m <= 99``.
    """
    e = math.floor(math.log10(value)) - 1
    m = math.ceil(value / 10.0 ** e * (1.0 - 1e-12))
    if m >= 100:
        e, m = e + 1, 10
    return 90 * e + max(m, 10) - 10


def grid_value(index: int) -> float:
    """The number of index ``index`` (:func:`grid_index`'s inverse on the grid).

    Parameters
    ----------
    index : int
        A grid index.

    Returns
    -------
    float
        ``m 10^e`` with ``e, m - 10 = divmod(index, 90)``.
    """
    e, m = divmod(index, 90)
    return float(f"{m + 10}e{e}")


def smallest_passing(passes: Callable[[int], bool], low: int, high: int) -> int:
    """The smallest index in ``(low, high]`` at which ``passes`` holds, by bisection, given
    that it fails at ``low`` and holds at ``high`` (and is monotone between them).

    Parameters
    ----------
    passes : callable
        ``passes(index) -> bool``, monotone in the index.
    low : int
        An index at which ``passes`` fails.
    high : int
        An index at which ``passes`` holds, ``high > low``.

    Returns
    -------
    int
        The smallest passing index in ``(low, high]``.
    """
    while high - low > 1:
        mid = (low + high) // 2
        if passes(mid):
            high = mid
        else:
            low = mid
    return high


def half_step_below(passes: Callable[[float], bool], index: int, above: float) -> float:
    """``grid_value(index)``, or the value halfway to the grid value below it where that lies
    above ``above`` and passes (one more trial).

    Parameters
    ----------
    passes : callable
        ``passes(value) -> bool``.
    index : int
        A passing index whose predecessor fails (what :func:`smallest_passing` returns).
    above : float
        The half step is tried only above this (the value known to fail).

    Returns
    -------
    float
        A value at which ``passes`` held: the half step, three significant digits, or
        ``grid_value(index)``.

    Examples
    --------
    >>> half_step_below(lambda value: value >= 37.2, grid_index(38.0), 37.0)
    37.5
    >>> half_step_below(lambda value: value >= 37.6, grid_index(38.0), 37.0)
    38.0
    """
    value = grid_value(index)
    half = float(f"{0.5 * (grid_value(index - 1) + value):.3g}")
    if above < half < value and passes(half):
        return half
    return value
