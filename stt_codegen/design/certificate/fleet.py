"""The fleet certificate: every pair of robots' tubes, grown by both radii, apart at every ``t``.

Each robot's controller keeps its reference point in its tube box
``[gamma_L(t), gamma_U(t)]`` for every ``t >= 0`` (its own certificate), and its body lies
within its reach (radius plus axle offset) of that point. Each robot's certificate encloses
its tube on a partition of ``[0, inf)`` (:class:`~.report.Enclosure`: on ``[t_a, t_b]`` the
tube lies in ``[lower_min, upper_max]``, with ``alpha`` followed as the deployed implicit
step follows it). For a pair of robots the union of the two partitions' breakpoints cuts
``[0, inf)`` into intervals each of which lies in one interval of each partition, so both
tubes lie in known boxes there; if along some body dimension the two boxes are apart by
more than the sum of the reaches, the bodies cannot meet on that interval (a gap along one
axis bounds the Euclidean distance from below). The pair's margin is the smallest such
gap minus the sum of the reaches, and where it is smallest.

Argument and limits: docs/fleets.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ...tube import reference
from ...tube.parameters import TubeDesign
from .motion import MOTION_INTERVALS, MOTION_SPLIT, cut_enclosure
from .report import ROUNDING_MARGIN, Certificate, CertificateState, Enclosure

__all__ = ["PairMargin", "RobotTube", "pair_margin", "robot_tube"]


@dataclass(frozen=True)
class PairMargin:
    """The separation of two robots' bodies, certified for every ``t >= 0``.

    Attributes
    ----------
    pair : (str, str)
        The two robots' names.
    passed : bool
        ``margin`` exceeds the enclosures' rounding on every interval.
    margin : float
        The smallest, over the intervals, of the largest gap along a body dimension
        between the two tubes' boxes, minus both reaches; state units (metres).
    t_start, t_end : float
        Passed: the interval where the margin is smallest; failed: the run of intervals not
        proven around it (where the tubes may meet), seconds (``t_end`` may be ``inf``).
    dim : int
        The state dimension of that gap.
    intervals : int
        How many intervals the pair's check used.
    t_narrowest : float
        The start of the interval where the margin is smallest, seconds.
    """

    pair: tuple[str, str]
    passed: bool
    margin: float
    t_start: float
    t_end: float
    dim: int
    intervals: int
    t_narrowest: float = 0.0

    @property
    def detail(self) -> str:
        """The margin in words."""
        a, b = self.pair
        where = f"[{self.t_start:.4f}, {self.t_end:.4f}] s"
        if self.passed:
            return (f"{a} and {b}: bodies apart by >= {self.margin:.4g} (narrowest on "
                    f"{where}, along dimension {self.dim}; {self.intervals} intervals)")
        return (f"{a} and {b}: their tubes, grown by both radii, may meet on {where} "
                f"(separation {self.margin:.4g} at t = {self.t_narrowest:.4f} s)")


@dataclass(frozen=True)
class RobotTube:
    """One robot's tube enclosed on a partition of ``[0, inf)``, with what cuts it further.

    Attributes
    ----------
    tube : TubeDesign
        The certified tube.
    enclosure : Enclosure
        Its boxes on the partition.
    state : CertificateState
        The partition's sample indices and ``alpha`` bounds (:mod:`.repropagate` resumes
        from them).
    """

    tube: TubeDesign
    enclosure: Enclosure
    state: CertificateState

    def boxes(self, dims: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                  np.ndarray]:
        """The tube's box on each interval, on ``dims``.

        Parameters
        ----------
        dims : sequence of int
            The body's state dimensions.

        Returns
        -------
        t_start, t_end : ndarray, shape (K,)
            Seconds; the last ``t_end`` is ``inf``.
        lower, upper : ndarray, shape (K, len(dims))
            The box holding the tube on the interval (``lower_min``, ``upper_max``).
        """
        d = list(dims)
        enc = self.enclosure
        return enc.t_start, enc.t_end, enc.lower_min[:, d], enc.upper_max[:, d]

    def cut(self, mask: np.ndarray) -> "RobotTube":
        """The tube with each interval of ``mask`` (at least two samples long) cut in
        :data:`~.motion.MOTION_SPLIT` pieces, ``alpha`` followed again on the cuts only."""
        points = list(self.state.points)
        i0 = np.array(points)
        length = np.append(i0[1:] - i0[:-1], 0)
        split = mask & (length >= 2)
        if not split.any():
            return self
        cuts = {int(a + (b * q) // MOTION_SPLIT) for a, b in zip(i0[split], length[split])
                for q in range(1, MOTION_SPLIT)}
        with reference.numpy_math():
            enc, state = cut_enclosure(self.tube, sorted(set(points) | cuts), self.state)
        return RobotTube(self.tube, enc, state)

    def finer(self, span: float) -> "RobotTube":
        """The tube cut until every bounded interval is at most ``span`` seconds long (or
        one sample)."""
        tube = self
        while True:
            length = tube.enclosure.t_end - tube.enclosure.t_start
            long = np.isfinite(length) & (length > span)
            cut = tube.cut(long)
            if cut is tube:
                return tube
            tube = cut


def robot_tube(tube: TubeDesign, certificate: Certificate) -> RobotTube:
    """A certified tube's enclosure, ready to cut.

    Parameters
    ----------
    tube : TubeDesign
        The tube.
    certificate : Certificate
        Its certificate (the enclosure and the partition's state).

    Returns
    -------
    RobotTube
    """
    return RobotTube(tube, certificate.enclosure, certificate.state)


def _gaps(tubes: tuple[RobotTube, RobotTube], reach: float, dims: Sequence[int]):
    """The merged partition of two tubes and the largest gap on each of its intervals."""
    a_t0, _, a_lo, a_hi = tubes[0].boxes(dims)
    b_t0, _, b_lo, b_hi = tubes[1].boxes(dims)
    starts = np.union1d(a_t0, b_t0)
    # the interval of each partition holding each merged interval (partitions start at 0)
    ia = np.searchsorted(a_t0, starts, side="right") - 1
    ib = np.searchsorted(b_t0, starts, side="right") - 1
    gaps = np.maximum(b_lo[ib] - a_hi[ia], a_lo[ia] - b_hi[ib]) - reach
    best = np.argmax(gaps, axis=1)
    return starts, ia, ib, gaps[np.arange(gaps.shape[0]), best], best


def pair_margin(names: tuple[str, str], tubes: tuple[RobotTube, RobotTube],
                reaches: tuple[float, float], dims: Sequence[int],
                max_intervals: int = MOTION_INTERVALS) -> PairMargin:
    """The certified separation of two robots' bodies for every ``t >= 0``.

    Where the two boxes are not apart, both tubes' intervals there are cut (as the moving
    obstacles' certificate does, :mod:`.motion`) until the pair is proven, the intervals
    are single samples, or the merged partition has ``max_intervals`` intervals.

    Parameters
    ----------
    names : (str, str)
        The robots' names.
    tubes : (RobotTube, RobotTube)
        Their enclosed tubes (each partition covers ``[0, inf)``).
    reaches : (float, float)
        Each body's radius around its reference point (plus an axle offset), state units.
    dims : sequence of int
        The body's state dimensions (the same for both).
    max_intervals : int
        The refinement budget.

    Returns
    -------
    PairMargin
        ``passed`` when on every interval of the merged partitions the two boxes are apart
        along some body dimension by more than ``sum(reaches)``.
    """
    reach = reaches[0] + reaches[1]
    while True:
        starts, ia, ib, sep, best = _gaps(tubes, reach, dims)
        bad = sep <= ROUNDING_MARGIN
        if not bad.any() or starts.size > max_intervals:
            break
        cut = tuple(t.cut(np.isin(np.arange(t.enclosure.t_start.size), i[bad]))
                    for t, i in zip(tubes, (ia, ib)))
        if all(c is t for c, t in zip(cut, tubes)):
            break
        tubes = cut
    ends = np.append(starts[1:], np.inf)
    k = int(np.argmin(sep))
    margin = float(sep[k])
    a = b = k                          # the run of intervals not proven around the narrowest
    while margin <= ROUNDING_MARGIN and a > 0 and bad[a - 1]:
        a -= 1
    while margin <= ROUNDING_MARGIN and b + 1 < bad.size and bad[b + 1]:
        b += 1
    return PairMargin(tuple(names), margin > ROUNDING_MARGIN, margin, float(starts[a]),
                      float(ends[b]), int(np.asarray(dims)[best[k]]), int(starts.size),
                      float(starts[k]))
