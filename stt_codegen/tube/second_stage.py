"""The second stage of the cascade law for second-order plants: plain data.

For ``x1_dot = x2``, ``x2_dot = f(x1, x2) + g(x1, x2) u + w`` the designed tube keeps the
position ``x1`` as today; law (13) on the position error, with gain ``k1``, is the virtual
velocity ``r(x1, t) = -k1 xi1 epsilon1``; the velocity error ``x2 - r`` is kept inside the
performance tube ``|x2_i - r_i| < rho2_i(t)`` by ``u = -k2 xi2 epsilon2`` (the same
transform). The argument, its assumptions and its limits: docs/second-order.md.

This module is plain data, like :mod:`.parameters`: the CasADi pieces are
:mod:`.cascade`, the numpy oracle :mod:`.cascade_reference`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SecondStage"]


@dataclass(frozen=True)
class SecondStage:
    """The numbers of the cascade's second stage (docs/second-order.md).

    Attributes
    ----------
    position_gain : float
        ``k1``: the gain of law (13) on the position error, whose output is the virtual
        velocity ``r``, (state units)^2 per second.
    velocity_gain : float
        ``k2`` of ``u = -k2 xi2 epsilon2``, input units times velocity units.
    width_start : tuple of float
        ``rho2_i(0)``, half-width of the velocity tube at ``t = 0``, velocity units
        (state units per second), one per dimension, positive; must exceed
        ``|x2_i(0) - r_i(x1(0), 0)|``.
    width_floor : tuple of float
        ``rho2_i(inf)``, the floor, velocity units, positive, at most ``width_start``.
    decay : float
        ``l`` of ``rho2(t) = (rho2(0) - rho2(inf)) exp(-l t) + rho2(inf)``, 1/s, >= 0.

    Raises
    ------
    ValueError
        A number out of its range, or vectors of different lengths.
    """

    position_gain: float
    velocity_gain: float
    width_start: tuple[float, ...]
    width_floor: tuple[float, ...]
    decay: float

    def __post_init__(self) -> None:
        numbers = (self.position_gain, self.velocity_gain, self.decay,
                   *self.width_start, *self.width_floor)
        if not all(math.isfinite(v) for v in numbers):
            raise ValueError("second stage: every number must be finite")
        if self.position_gain <= 0 or self.velocity_gain <= 0:
            raise ValueError("second stage: the gains k1 and k2 must be positive")
        if self.decay < 0:
            raise ValueError("second stage: the decay l must be >= 0")
        if len(self.width_start) != len(self.width_floor) or not self.width_start:
            raise ValueError("second stage: width_start and width_floor need one entry per "
                             "dimension")
        if not all(0 < f <= s for f, s in zip(self.width_floor, self.width_start)):
            raise ValueError("second stage: need 0 < width_floor <= width_start")

    @property
    def dimension(self) -> int:
        """``n``, the number of positions (and of velocities, and of inputs)."""
        return len(self.width_start)
