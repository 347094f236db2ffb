"""A refusal for a deadline too short names the ``prescribed_time`` that is then certified.

When the tube moves too fast for the controller's rate (the certificate's
``SAMPLING_RATE`` or ``NON_EMPTY`` property, or the cascade's stage at no rate), a later
deadline is the knob that helps whatever the hardware: the search doubles ``t_c`` up to
:data:`~.grid.MAX_TIME_FACTOR` times it, then bisects on the two-digit grid (:mod:`.grid`)
down to neighbouring values, and names the smallest time on the grid at which the design
search certified the spec (where certification is monotone in ``t_c`` between the two).
Specs with parts fixed in absolute time (timed tasks whose windows end before ``t_c``,
moving obstacles, ``[target] any_of``: :func:`~stt_codegen.spec.deadline.fixed_in_time`)
are refused as they are: a later ``t_c`` does not move them. Task windows that end at
``t_c`` (and the obstacles that last until those tasks) move with it
(:func:`~stt_codegen.spec.deadline.with_deadline`); the advice then names the time under
``tasks.window_end`` too. A refusal that already
names a shorter ``controller.delay`` certified at the spec's rate (the cascade's,
:mod:`.cascade_gain`) is left as it is too: the delay is what fails, and the search for a
time would cost a design per trial.
"""

from __future__ import annotations

from collections.abc import Callable
from ..errors import DesignError, number_text
from ..spec.deadline import fixed_in_time, later_advice, moved_words, with_deadline
from ..spec.loader import Spec
from .failures import FailureKind, without_advice
from .grid import MAX_TIME_FACTOR, grid_index, grid_value, half_step_below, smallest_passing
from .result import Design

__all__ = ["SLOWER_HELPS", "certified_time", "deadline_refusal"]

#: The failures a later deadline (a slower tube) cures.
SLOWER_HELPS = (FailureKind.SAMPLING_RATE, FailureKind.NON_EMPTY)


def deadline_refusal(spec: Spec, error: DesignError,
                     search: Callable[[Spec], Design]) -> DesignError:
    """``error``, with the smallest ``prescribed_time`` that ``search`` certifies named
    when the failure is one a slower tube cures.

    Parameters
    ----------
    spec : Spec
        The spec refused.
    error : DesignError
        Its refusal.
    search : callable
        ``search(spec) -> Design``, the design search without this advice.

    Returns
    -------
    DesignError
        ``error`` itself when its kind is not in :data:`SLOWER_HELPS`, when the spec's
        times are absolute, when it names a certified ``controller.delay``, or when no
        time up to ``MAX_TIME_FACTOR t_c`` is certified;
        else a copy whose message ends with ``prescribed_time = T s is certified`` (``T``
        was designed and certified by ``search``).
    """
    if (error.kind not in SLOWER_HELPS or fixed_in_time(spec)
            or "controller.delay" in error.advice):
        return error
    time = certified_time(spec, search)
    if time is None:
        return error
    return DesignError(f"{error}; prescribed_time = {number_text(time)} s"
                       f"{moved_words(spec)} is certified", kind=error.kind,
                       tried=error.tried, advice={**error.advice, **later_advice(spec, time)})


def certified_time(spec: Spec, search: Callable[[Spec], Design]) -> float | None:
    """The smallest ``prescribed_time`` above the spec's that ``search`` certifies (the spec
    moved there by :func:`~stt_codegen.spec.deadline.with_deadline`), on the two-digit
    grid: doubling up to :data:`~.grid.MAX_TIME_FACTOR` times ``t_c``, then a bisection down
    to neighbouring grid values (:func:`~.grid.smallest_passing`), then the half step below
    the one found (:func:`~.grid.half_step_below`); each trial a design, its advice off.

    Parameters
    ----------
    spec : Spec
        The spec refused at its ``prescribed_time``.
    search : callable
        ``search(spec) -> Design``, raising :class:`DesignError` when it refuses.

    Returns
    -------
    float or None
        Seconds, a time ``search`` certified; ``None`` when none up to ``MAX_TIME_FACTOR
        t_c`` is.
    """
    def passes_at(value: float) -> bool:
        try:
            with without_advice():            # the verdict only
                search(with_deadline(spec, value))
        except DesignError:
            return False
        return True

    def passes(index: int) -> bool:
        return passes_at(grid_value(index))

    low = grid_index(spec.prescribed_time)
    factor, high = 2.0, None
    while factor <= MAX_TIME_FACTOR:         # doubling: a passing time, cheaply
        index = grid_index(factor * spec.prescribed_time)
        if passes(index):
            high = index
            break
        low, factor = index, 2.0 * factor
    if high is None:
        return None
    return half_step_below(passes_at, smallest_passing(passes, low, high),
                           spec.prescribed_time)
