"""A replanned tube that goes on with the active tube's move: a switch without a stop.

A new tube starts from the active tube's box at the switch ``t_s``. Made from rest (its
first move's rate is 0 at its start), it asks the robot to stop there and start again.
:func:`continuing` makes the same tube keep the active move instead: its first segment is
the active tube's segment at the switch, in the new tube's time (it started before 0),
and the new tube's first move starts at 0 from where that segment ends, blending with it
(a blended corner, docs/design.md). At 0 both tubes are the same box, and the tube's
rate is the active one's: the robot keeps its speed through the switch and turns as the
two moves add. The tube is certified again (:func:`~.search.check_tube`), as any tube.
"""

from __future__ import annotations

from dataclasses import replace

from ..tube.parameters import ReachSegment, TubeDesign
from .gain import with_gain
from .result import Design
from .search import check_tube
from .sensed_path import MAX_SEGMENTS

__all__ = ["END_GAP", "continuing", "going_on"]

#: How much later than the active segment the new first move must end, s: its ends stay
#: increasing in the tube as data in single precision too (its check refuses equal ones).
END_GAP = 1e-3


def _held(segment: ReachSegment) -> bool:
    return (segment.lower_from == segment.lower_to
            and segment.upper_from == segment.upper_to)


def going_on(active: TubeDesign, at: float) -> ReachSegment | None:
    """The one segment of ``active`` moving at ``at``, in the time of a tube starting
    there; ``None`` when it holds its box or two segments move."""
    segments = active.segments
    k = next((i for i, s in enumerate(segments) if at < s.end), None)
    if k is None or not segments[k].start < at or _held(segments[k]):
        return None
    if k + 1 < len(segments) and segments[k + 1].start < at:
        return None
    return replace(segments[k], start=segments[k].start - at, end=segments[k].end - at)


def continuing(active: TubeDesign, at: float, new: Design, spec=None) -> Design | None:
    """``new``'s tube with ``active``'s move at ``at`` going on, certified; or ``None``.

    Parameters
    ----------
    active : TubeDesign
        The active tube.
    at : float
        The switch in the active tube's time, s.
    new : Design
        A certified tube from the active tube's box at the switch (its time 0 at the
        switch; a via tube whose first segment moves from 0).
    spec : Spec, optional
        The spec the tube is certified against (``new.spec`` by default; an evasion's
        adds the sensed obstacles' reachable sets).

    Returns
    -------
    Design or None
        ``None`` where there is no move to go on with (the active tube holds its box, or
        two of its segments move it at ``at``), where the new first move does not end
        :data:`END_GAP` after the active one (three segments would move at once), where
        one more segment would not fit in the tube as data
        (:data:`~.sensed_path.MAX_SEGMENTS`), or where the tube is not certified.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.design.sensed_blend import continuing
    >>> hall = stt.design_tube(stt.load_spec("hall-crossing"))
    >>> continuing(hall.tube, 25.0, hall) is None   # after t_c: no move to go on with
    True
    """
    going = going_on(active, at)
    if going is None:
        return None
    spec = new.spec if spec is None else spec
    first = new.tube.segments[0]
    if (first.start != 0.0 or _held(first) or first.end - going.end < END_GAP
            or len(new.tube.segments) >= MAX_SEGMENTS):
        return None
    first = replace(first, lower_from=going.lower_to, upper_from=going.upper_to)
    tube = replace(new.tube, segments=(going, first, *new.tube.segments[1:]))
    try:
        found = check_tube(tube, spec)
    except ValueError:
        return None
    if not found.passed:
        return None
    return Design(with_gain(tube, found.min_width, spec), new.method, found,
                  new.design_time_s, spec=spec, motion=new.motion)
