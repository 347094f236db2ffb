"""The length of a tube's route: what a robot drives at the least, to compare a reach time
with the straight-line time at the robot's top speed along the same route.

A reach tube of reach segments (:class:`~stt_codegen.tube.parameters.ReachSegment`) moves
its box from one via box to the next; its *route* is the polyline from the initial state
through the centre of each segment's end box (the last the target box). A point kept in
the tube travels at least about this far (the boxes are small beside the legs); the
benchmark ``bench agv`` and the AGV's tests divide it by ``v_max`` for the straight-line
time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..tube.parameters import TubeDesign

__all__ = ["route_length"]


def route_length(tube: TubeDesign, start: Sequence[float]) -> float:
    """The length of the polyline from ``start`` through the centres of the end boxes of
    ``tube``'s reach segments, in order.

    Parameters
    ----------
    tube : TubeDesign
        A designed tube (its ``segments``).
    start : sequence of float, shape (n,)
        The initial state (``Spec.initial_state``), state units.

    Returns
    -------
    float
        State units (metres for a position); a segment that holds its box (a wait) adds 0.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> spec = stt.load_spec("crossing-moving")
    >>> design = stt.design_tube(spec)
    >>> round(route_length(design.tube, spec.initial_state), 2)
    5.4
    """
    here = tuple(float(v) for v in start)
    total = 0.0
    for seg in tube.segments:
        centre = tuple(0.5 * (a + b) for a, b in zip(seg.lower_to, seg.upper_to))
        total += math.dist(here, centre)
        here = centre
    return total
