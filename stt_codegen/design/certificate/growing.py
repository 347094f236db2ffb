"""The enclosure of a sampled tube, computed for as many sampling intervals as a check asks.

:func:`~.enclosures.enclose_tube` encloses ``gamma_L``, ``gamma_U`` on every sampling
interval; each interval's figures depend on that interval only (its ends and the samples
of ``alpha`` at them), so the enclosure of the first ``m`` intervals is the first ``m``
rows of the whole one, float for float. A check that follows the samples and may stop
early (the sampled cascade's certificate refuses most stages within its first second) asks
:class:`GrowingEnclosure` for the rows it reaches; the rows are computed once, in pieces
that at least double, and kept for every later check of the same tube. The rows are
computed with numpy's kernels (:func:`~stt_codegen.tube.reference.numpy_math`), as the
other certificates compute theirs, whatever context asks for them: rows computed in
different calls are then the same floats as one call's.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..samples import TubeSamples
from ...tube import reference
from ...tube.parameters import TubeDesign
from .enclosures import enclose, piece_ranges
from .report import Enclosure

__all__ = ["GrowingEnclosure"]


class GrowingEnclosure:
    """:func:`~.enclosures.enclose_tube` of ``design`` and ``samples``, row by row.

    Parameters
    ----------
    design : TubeDesign
    samples : TubeSamples
        The deployed tube at ``design``'s rate (:func:`~..samples.sample_tube`).

    Attributes
    ----------
    count : int
        Intervals of ``samples`` (``len(samples.t) - 1``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.design.samples import sample_tube
    >>> from stt_codegen.design.certificate import enclose_tube
    >>> from stt_codegen.tube.reference import numpy_math
    >>> tube = stt.design_tube(stt.load_spec("omnirobot-s1")).tube
    >>> samples = sample_tube(tube)
    >>> growing = GrowingEnclosure(tube, samples)
    >>> with numpy_math():
    ...     whole = enclose_tube(tube, samples)
    >>> bool((growing.first(50).upper_min == whole.upper_min[:50]).all())
    True
    """

    def __init__(self, design: TubeDesign, samples: TubeSamples) -> None:
        self.design, self.samples = design, samples
        self.count = len(samples.t) - 1
        self._rows: Enclosure | None = None

    def _part(self, start: int, stop: int) -> Enclosure:
        """:func:`~.enclosures.enclose_tube`'s rows ``start .. stop - 1``."""
        t0, t1 = self.samples.t[start:stop], self.samples.t[start + 1:stop + 1]
        a0, a1 = self.samples.alpha[start:stop], self.samples.alpha[start + 1:stop + 1]
        with reference.numpy_math():
            return enclose(self.design, piece_ranges(self.design, t0, t1),
                           np.minimum(a0, a1), np.maximum(a0, a1), t0, t1)

    def first(self, rows: int) -> Enclosure:
        """The enclosure of the first ``rows`` intervals (at most :attr:`count`).

        Parameters
        ----------
        rows : int

        Returns
        -------
        Enclosure
            ``rows`` intervals: the first rows of
            :func:`~.enclosures.enclose_tube`'s.
        """
        rows = min(rows, self.count)
        have = 0 if self._rows is None else len(self._rows.t_start)
        if self._rows is None or rows > have:
            stop = min(self.count, max(rows, 2 * have))
            part = self._part(have, stop)
            self._rows = part if self._rows is None else Enclosure(*(
                np.concatenate([getattr(self._rows, f.name), getattr(part, f.name)])
                for f in dataclasses.fields(Enclosure)))
        if rows == len(self._rows.t_start):
            return self._rows
        return Enclosure(*(getattr(self._rows, f.name)[:rows]
                           for f in dataclasses.fields(Enclosure)))
