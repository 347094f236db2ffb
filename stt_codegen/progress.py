"""Progress of long work: the one event ``design_tube`` and ``verify`` report, and its reporter.

A caller passes ``progress=callback``; the work calls ``callback(Progress(...))`` at its
natural stages (the design's candidate tubes and certificates, the cascade's shapes, the
proofs of ``verify``). The fractions a reporter passes never decrease and the last one is
1. How long a design search takes is not known in advance (a candidate may pass at once or
after forty), so a design's fraction is a share of its budget: it can jump when a stage
ends early. The command line draws the events as a tqdm bar on a terminal (``cli``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

__all__ = ["Progress", "ProgressCallback", "Reporter", "report", "reporting"]


@dataclass(frozen=True)
class Progress:
    """One step of long work, as passed to a ``progress`` callback.

    Attributes
    ----------
    stage : str
        The stage now running, in words (``"candidate tubes"``, ``"lemma 3.3"``).
    fraction : float
        Share of the whole call done, in ``[0, 1]``; never decreases from one event to the
        next of one call, and the last event has 1.
    message : str
        A line for a person (``"lemma 3.3 (3/10)"``, ``"candidate tube 4 of at most
        40"``); ``str(event)`` is this.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> events = []
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"), progress=events.append)
    >>> events[-1].fraction, events[-1].stage
    (1.0, 'done')
    >>> all(a.fraction <= b.fraction for a, b in zip(events, events[1:]))
    True
    """

    stage: str
    fraction: float
    message: str

    def __str__(self) -> str:
        return self.message


#: What a ``progress=`` parameter takes.
ProgressCallback = Callable[[Progress], None]


class Reporter:
    """A ``progress`` callback (or ``None``) wrapped to pass non-decreasing fractions.

    Parameters
    ----------
    callback : callable or None
        Called with each :class:`Progress`; ``None`` reports nothing.
    """

    def __init__(self, callback: ProgressCallback | None) -> None:
        self.callback = callback
        self.done = 0.0

    def __call__(self, stage: str, fraction: float, message: str = "") -> None:
        """Report ``stage`` at ``fraction`` of the call (raised to the last one reported)."""
        self.done = min(1.0, max(self.done, float(fraction)))
        if self.callback is not None:
            self.callback(Progress(stage, self.done, message or stage))


_CURRENT: ContextVar[tuple[Reporter, float, float] | None] = ContextVar(
    "stt_codegen_progress", default=None)


@contextmanager
def reporting(callback: ProgressCallback | None, share: tuple[float, float] = (0.0, 1.0),
              final: str = "") -> Iterator[None]:
    """Make ``callback`` the receiver of :func:`report` within the block, or narrow the
    current receiver to a ``share`` of its range.

    Parameters
    ----------
    callback : callable or None
        A new receiver (a public function's ``progress``); ``None`` keeps the current one
        (a nested call reports into its caller's bar), narrowed to ``share``.
    share : (float, float)
        The part of the current range the block's fractions ``0..1`` map to.
    final : str
        If given, the stage reported at fraction 1 when the block ends normally.
    """
    outer = _CURRENT.get()
    if callback is not None:
        reporter, low, high = Reporter(callback), 0.0, 1.0
    elif outer is not None:
        reporter, low, high = outer
    else:
        yield
        return
    span = high - low
    token = _CURRENT.set((reporter, low + span * share[0], low + span * share[1]))
    try:
        yield
        if final:
            report(final, 1.0)
    finally:
        _CURRENT.reset(token)


def report(stage: str, fraction: float, message: str = "") -> None:
    """Report ``stage`` at ``fraction`` (0..1) of the current block of :func:`reporting`;
    nothing when no caller asked for progress.

    Parameters
    ----------
    stage : str
        The stage, in words.
    fraction : float
        Share of the current block done.
    message : str
        The line for a person (default ``stage``).
    """
    current = _CURRENT.get()
    if current is None:
        return
    reporter, low, high = current
    reporter(stage, low + (high - low) * min(1.0, max(0.0, fraction)), message)
