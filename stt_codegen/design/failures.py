"""Why a tube design failed, as a value: callers branch on it, never on message text.

A :class:`~stt_codegen.errors.DesignError` raised by the design package carries one of
these in ``kind``; a :class:`~stt_codegen.design.result.TubeCheck` that did not pass
carries one too.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from enum import Enum

from ..errors import number_text
from ..spec.deadline import WINDOW_END

__all__ = ["FailureKind", "advice_text", "advice_wanted", "property_kind", "without_advice"]

_ADVICE: ContextVar[bool] = ContextVar("stt_codegen_refusal_advice", default=True)


@contextmanager
def without_advice() -> Iterator[None]:
    """Within the block, refusals skip the searches that name what works (a rate, a
    delay): a search that only asks whether a trial spec designs (the deadline's) needs
    the verdict, not the advice."""
    token = _ADVICE.set(False)
    try:
        yield
    finally:
        _ADVICE.reset(token)


def advice_wanted() -> bool:
    """Whether a refusal should search for what works (``False`` within
    :func:`without_advice`)."""
    return _ADVICE.get()


#: The unit each advice field is printed with (``DesignError.advice``).
ADVICE_UNITS = {"prescribed_time": " s", WINDOW_END: " s", "controller.delay": " s",
                "plant.axle_offset": " m", "actuator.reverse_speed": " m/s"}


def advice_text(name: str, value: float | bool) -> str:
    """One advice field as a refusal's message names it: ``prescribed_time = 31 s``,
    ``controller.compensate_delay = true``."""
    return f"{name} = " + ("true" if value is True else
                           f"{number_text(value)}{ADVICE_UNITS.get(name, '')}")


class FailureKind(Enum):
    """What made a tube (or the design search) fail.

    Tube check (a certificate property or a sampled-loop limit, in the order
    :func:`~stt_codegen.design.search.check_tube` reports them): ``SAMPLING_RATE``,
    ``NON_EMPTY``, ``INITIAL_ERROR``, ``INITIAL_STATE``, ``STATE_SPACE``, ``OBSTACLE``,
    ``TARGET``. Design search: ``OBSTACLE_AT_TARGET`` (an obstacle within the window
    inflation of the target box), ``NO_ROOM`` (no dimension leaves room beside an
    obstacle), ``SEARCH_BUDGET`` (candidate tubes or certificate work used up),
    ``NO_PASSAGE`` (no via-point path: the free passage is too narrow),
    ``WALLED_OFF`` (the start or the target is enclosed by obstacles), ``PLANT``
    (the spec's plant violates Assumption 2), ``INPUT_BOUND`` (no design within ``t_c``
    is proved to keep law (13) within ``[actuator] input_bound``), ``TRACKING``
    (``tube.method = "paper"``: every certified tube is one the gain cannot follow, its
    sampled-data proof bounds ``|e|`` above 0.7, :func:`~.tracking.unfollowable`),
    ``TASK`` (a timed task of ``[[tasks]]`` is not certified, or its plan has no time;
    docs/tasks.md). Moving obstacles (docs/moving-obstacles.md): ``MOVING_OBSTACLE``
    (the tube may meet one in space-time), ``SWEPT_AT_START`` (no design avoids them in
    space-time, and the region a moving obstacle sweeps meets the start or the target,
    so it cannot be avoided as a static box). ``FLEET``: no robot order gives every robot
    of a fleet a tube apart from the others', or a pair is not certified apart
    (docs/fleets.md). ``TIMING``: with ``[controller] delay`` or
    ``jitter``, no design's sampled-data proof holds with them (:mod:`~.timing`).
    """

    SAMPLING_RATE = "sampling rate"
    NON_EMPTY = "non-empty"
    INITIAL_ERROR = "initial error"
    INITIAL_STATE = "initial state inside"
    STATE_SPACE = "inside state space"
    OBSTACLE = "avoids obstacle"
    TARGET = "inside target after t_c"
    OBSTACLE_AT_TARGET = "obstacle at target"
    NO_ROOM = "no room beside obstacle"
    SEARCH_BUDGET = "search budget"
    NO_PASSAGE = "no via-point passage"
    WALLED_OFF = "walled off"
    PLANT = "plant assumption"
    INPUT_BOUND = "input bound"
    TASK = "task"
    MOVING_OBSTACLE = "avoids moving obstacle"
    SWEPT_AT_START = "swept region at start or target"
    TRACKING = "tracking"
    TIMING = "timing"
    FLEET = "fleet separation"


def property_kind(name: str) -> FailureKind:
    """The kind of a failed certificate property (``Margin.name``, e.g. ``avoids obstacle 2``).

    Parameters
    ----------
    name : str
        A certificate property's name (a :data:`~.certificate.report.PROPERTIES` entry, or
        one with an obstacle's or task's number appended).

    Returns
    -------
    FailureKind
        The kind a failure of that property is reported with.

    Raises
    ------
    ValueError
        ``name`` is no certificate property.
    """
    if name.startswith(FailureKind.MOVING_OBSTACLE.value):
        return FailureKind.MOVING_OBSTACLE
    if name.startswith(FailureKind.OBSTACLE.value):
        return FailureKind.OBSTACLE
    if name.startswith(FailureKind.TASK.value + " "):
        return FailureKind.TASK
    return FailureKind(name)
