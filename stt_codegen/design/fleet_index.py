"""A space-time index of the robots' tubes placed so far (docs/fleets.md, "The design").

A robot designed into a fleet need only be compared with the robots whose tubes come near
its own. Each placed tube is kept as *chunks*: its certified enclosure (on a partition of
``[0, inf)``, :class:`~.certificate.fleet.RobotTube`) merged into boxes over at most
``span`` seconds each, the last one until ``inf``. The chunks are bucketed by the cells of
a uniform grid over the body dimensions that they meet, so a query reads only the buckets
its own boxes meet, and compares box with box only for the robots found there: the work of
a query grows with the robots placed near it, not with the fleet.

The index only *selects* which pairs to check; the pair certificate
(:func:`~.certificate.fleet.pair_margin`) is the judge of every pair it selects, and
:func:`~.fleet.certify_fleet` certifies every pair of the fleet at the end. A robot left
out of a query has boxes apart from the query's boxes (grown by ``grow``) on every
interval, so its pair is apart there too.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .certificate.fleet import RobotTube

__all__ = ["Chunks", "TubeIndex", "chunks"]


@dataclass(frozen=True)
class Chunks:
    """A tube's boxes, each over a time span.

    Attributes
    ----------
    t_start, t_end : ndarray, shape (K,)
        Seconds; consecutive (``t_end[k] == t_start[k + 1]``), the last ``t_end`` is
        ``inf``.
    lower, upper : ndarray, shape (K, len(dims))
        The box holding the tube over ``[t_start[k], t_end[k]]``, on the body dimensions.
    """

    t_start: np.ndarray
    t_end: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    def meets(self, other: "Chunks", grow: float, timed: bool = True) -> bool:
        """Whether some box of ``self`` grown by ``grow`` meets some box of ``other``
        (over a common time, when ``timed``).

        Parameters
        ----------
        other : Chunks
        grow : float
            Added to each side of ``self``'s boxes, state units (both robots' reaches).
        timed : bool
            ``False``: in space only, whenever each box is.

        Returns
        -------
        bool
        """
        apart = np.any((self.lower[:, None, :] - grow > other.upper[None, :, :])
                       | (other.lower[None, :, :] > self.upper[:, None, :] + grow), axis=2)
        if timed:
            apart |= ((self.t_end[:, None] < other.t_start[None, :])
                      | (other.t_end[None, :] < self.t_start[:, None]))
        return not bool(apart.all())


def chunks(tube: RobotTube, dims: Sequence[int], span: float) -> Chunks:
    """``tube``'s enclosure merged into boxes over at most ``span`` seconds each.

    Parameters
    ----------
    tube : RobotTube
        Enclosed on a partition of ``[0, inf)``.
    dims : sequence of int
        The body's state dimensions.
    span : float
        The longest time span of a merged box, seconds (an interval longer than that
        stays one box).

    Returns
    -------
    Chunks
        Each box the hull of the enclosure's boxes it merges; together they hold the tube
        at every ``t >= 0``.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.design.fleet import enclosed
    >>> fleet = stt.load_fleet("swap-fleet")
    >>> tube = enclosed(stt.design_tube(fleet.robots[0].spec))
    >>> c = chunks(tube, (0, 1), 1.0)
    >>> float(c.t_start[0]), float(c.t_end[-1]), bool(np.all(c.t_end[:-2] - c.t_start[:-2] <= 1.0))
    (0.0, inf, True)
    """
    t0, t1, lo, hi = tube.boxes(dims)
    first = [0]
    for k in range(1, t0.size):
        if not np.isfinite(t1[k]) or t1[k] - t0[first[-1]] > span:
            first.append(k)
    starts = np.array(first)
    ends = np.append(starts[1:], t0.size)
    return Chunks(t0[starts], t1[ends - 1], np.minimum.reduceat(lo, starts, axis=0),
                  np.maximum.reduceat(hi, starts, axis=0))


class TubeIndex:
    """The placed robots' tube chunks, bucketed by grid cell (module notes).

    Parameters
    ----------
    cell : float
        The grid's cell edge, state units (metres), > 0.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.design.fleet import enclosed
    >>> fleet = stt.load_fleet("swap-fleet")
    >>> east, west = (chunks(enclosed(stt.design_tube(r.spec)), (0, 1), 1.0)
    ...               for r in fleet.robots)
    >>> index = TubeIndex(2.0)
    >>> index.add("east", east)
    >>> index.near(west, 0.4), index.near(west, 0.4, timed=False)
    (['east'], ['east'])
    """

    def __init__(self, cell: float = 2.0):
        if not cell > 0:
            raise ValueError(f"cell must be > 0, got {cell!r}")
        self.cell = float(cell)
        self._cells: dict[tuple[int, ...], set[str]] = {}
        self._chunks: dict[str, Chunks] = {}

    def __len__(self) -> int:
        return len(self._chunks)

    def _keys(self, lower: np.ndarray, upper: np.ndarray):
        """The grid cells a box ``[lower, upper]`` meets."""
        lo = np.floor(lower / self.cell).astype(int)
        hi = np.floor(upper / self.cell).astype(int)
        return itertools.product(*(range(a, b + 1) for a, b in zip(lo, hi)))

    def add(self, name: str, boxes: Chunks) -> None:
        """Place a robot's tube.

        Parameters
        ----------
        name : str
            The robot (a later ``add`` of the same name replaces nothing: names are
            unique in a fleet).
        boxes : Chunks
            Its tube's chunks.
        """
        self._chunks[name] = boxes
        for lo, hi in zip(boxes.lower, boxes.upper):
            for key in self._keys(lo, hi):
                self._cells.setdefault(key, set()).add(name)

    def near(self, boxes: Chunks, grow: float, timed: bool = True) -> list[str]:
        """The placed robots some of whose boxes meet ``boxes`` grown by ``grow``.

        Parameters
        ----------
        boxes : Chunks
            The query: a candidate tube's chunks.
        grow : float
            Both robots' reaches (the largest over the placed robots), state units.
        timed : bool
            ``True``: boxes that meet over a common time; ``False``: in space only
            (whatever the times: the robots a re-timed tube through the same boxes may
            meet).

        Returns
        -------
        list of str
            Sorted names.
        """
        found: set[str] = set()
        for lo, hi in zip(boxes.lower, boxes.upper):
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
                return sorted(name for name, c in self._chunks.items()
                              if boxes.meets(c, grow, timed))
            for key in self._keys(lo - grow, hi + grow):
                found |= self._cells.get(key, set())
        return sorted(name for name in found
                      if boxes.meets(self._chunks[name], grow, timed))

