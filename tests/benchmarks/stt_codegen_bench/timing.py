"""Per-call timing of Python callables, round-robin so that implementations compared in
one run share the machine's state (frequency, cache, load) as far as possible."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence

__all__ = ["MIN_BATCH_SECONDS", "python_batch", "round_robin"]

#: Smallest duration of one timed batch, seconds.
MIN_BATCH_SECONDS = 0.2


def calibrate(fn: Callable[[int], None], min_seconds: float = MIN_BATCH_SECONDS) -> int:
    """The smallest power of two ``b`` such that ``fn(b)`` (``b`` calls) takes at least
    ``min_seconds``."""
    calls = 1
    while True:
        begin = time.perf_counter()
        fn(calls)
        if time.perf_counter() - begin >= min_seconds or calls >= 1 << 24:
            return calls
        calls *= 2


def round_robin(batches: dict[str, Callable[[], float]], repeats: int) -> dict[str, float]:
    """Median over ``repeats`` rounds of each batch's seconds per call.

    Parameters
    ----------
    batches : dict of str to callable
        ``name -> run()``; ``run()`` performs one timed batch and returns its seconds per
        call. Each round runs every batch once, in the given order.
    repeats : int
        Rounds, >= 1.

    Returns
    -------
    dict of str to float
        ``name -> median seconds per call``.
    """
    samples: dict[str, list[float]] = {name: [] for name in batches}
    for _ in range(repeats):
        for name, run in batches.items():
            samples[name].append(run())
    return {name: statistics.median(v) for name, v in samples.items()}


def python_batch(step: Callable, inputs: Sequence[tuple]) -> Callable[[], float]:
    """A batch runner for :func:`round_robin`: calls ``step(*inputs[k])`` cycling over the
    inputs, as many times as :func:`calibrate` says; returns seconds per call.

    Parameters
    ----------
    step : callable
        The function timed.
    inputs : sequence of tuple
        Argument tuples, cycled over.

    Returns
    -------
    callable
        ``run() -> float``: one batch, seconds per call.
    """
    count = len(inputs)

    def run_calls(calls: int) -> None:
        for k in range(calls):
            step(*inputs[k % count])

    calls = calibrate(run_calls)

    def run() -> float:
        begin = time.perf_counter()
        run_calls(calls)
        return (time.perf_counter() - begin) / calls
    return run
