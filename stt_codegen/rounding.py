"""Numbers rounded in a stated direction to a few significant digits, the same on every CPU.

numpy's ``exp``, ``log``, ``tanh`` and friends dispatch to SIMD kernels chosen at run time
(AVX2, AVX-512, NEON, or the baseline that calls libm), whose results differ in the last
bits. A number that such a computation feeds into a generated file or a design decision
(a derived gain, the certified narrowest width it comes from, a test tolerance) would then
differ from machine to machine. Where only a few digits matter, the number is rounded here
to :data:`DIGITS` significant digits *in the direction that keeps the argument it serves
valid* (a lower bound down, an upper bound up), and every later step (the certificate's
use of the number, the tolerance argument, the printed file) works with the rounded value.
Two machines then agree unless their values straddle a rounding boundary, which needs a
relative difference of about ``10**-DIGITS`` where the kernels differ by about ``10**-16``.
The rule is in docs/codegen.md, "Numbers independent of the CPU". The other way round,
:func:`distinct` prints a number compared with a limit with the digits it takes to tell
them apart.
"""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

import numpy as np

__all__ = ["DIGITS", "distinct", "round_down", "round_up", "round_up_array"]

#: Significant digits kept by :func:`round_down` and :func:`round_up`.
DIGITS = 4


def _round(x: float, digits: int, rounding: str) -> float:
    value = float(x)
    if value == 0.0 or not math.isfinite(value):
        return value
    exact = Decimal(value)        # the float's exact binary value, no rounding
    quantum = Decimal(1).scaleb(exact.adjusted() - digits + 1)
    return float(exact.quantize(quantum, rounding=rounding))


def round_down(x: float, digits: int = DIGITS) -> float:
    """The largest number of ``digits`` significant decimal digits at most ``x``, as a float.

    The float returned is at most ``x`` too: ``x`` is itself a float at or above the
    decimal, so the float nearest the decimal cannot pass it.

    Parameters
    ----------
    x : float
        Any float; 0, infinities and NaN are returned unchanged.
    digits : int, optional
        Significant digits kept, at least 1 (default :data:`DIGITS`).

    Returns
    -------
    float
        The rounded value, ``<= x``.
    """
    return _round(x, digits, ROUND_FLOOR)


def round_up(x: float, digits: int = DIGITS) -> float:
    """The smallest number of ``digits`` significant decimal digits at least ``x``, as a float
    (at least ``x``; see :func:`round_down`).

    Parameters
    ----------
    x : float
        Any float; 0, infinities and NaN are returned unchanged.
    digits : int, optional
        Significant digits kept, at least 1 (default :data:`DIGITS`).

    Returns
    -------
    float
        The rounded value, ``>= x``.
    """
    return _round(x, digits, ROUND_CEILING)


def round_up_array(a, digits: int = DIGITS) -> np.ndarray:
    """:func:`round_up` on every entry of an array.

    Parameters
    ----------
    a : array_like
        Floats, any shape.
    digits : int, optional
        Significant digits kept (default :data:`DIGITS`).

    Returns
    -------
    numpy.ndarray
        Same shape as ``a``, float64, every entry ``>=`` the one of ``a``.
    """
    a = np.asarray(a, dtype=float)
    return np.array([round_up(v, digits) for v in a.ravel()], dtype=float).reshape(a.shape)


def distinct(value: float, other: float, digits: int = 3) -> str:
    """``value`` printed with at least ``digits`` significant digits, and with as many more
    (up to 17) as it takes to differ from ``other`` printed the same way.

    A check that compares ``value`` with a limit ``other`` prints both: where they differ
    only in late digits, a FAIL whose printed figures look equal (or a PASS whose figures
    look reversed) would contradict itself.

    Parameters
    ----------
    value, other : float
        The number to print and the one it was compared with.
    digits : int, optional
        The fewest significant digits (default 3).

    Returns
    -------
    str
        ``value`` in ``g`` format.
    """
    for d in range(digits, 18):
        if f"{value:.{d}g}" != f"{other:.{d}g}" or value == other:
            return f"{value:.{d}g}"
    return repr(value)
