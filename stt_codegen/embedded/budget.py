"""The controller step's share of the sampling period on the Cortex-M4F, from the
emulator's instruction counts (issue of the timing contract: the step must finish well
within the period it is called at).

QEMU counts instructions, not cycles. On the Cortex-M4F most Thumb-2 instructions take one
cycle or more (loads 2, floating-point divisions and square roots 14, branches 1-3), so
``instructions / clock`` is a lower bound of the step's time at that clock, and the share
is a lower bound of the period's share; a margin of several times is needed before the
figure says the step fits (docs/embedded.md, "Timing contract").
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["CLOCK_HZ", "budget_words", "step_budget"]

#: The clock the share is stated at: an STM32F4's (Cortex-M4F) 168 MHz.
CLOCK_HZ = 168e6


def step_budget(counts: Sequence[int], rate_hz: float, clock_hz: float = CLOCK_HZ) -> dict:
    """The largest instruction count of the measured steps and its share of the period.

    Parameters
    ----------
    counts : sequence of int
        Instructions of each measured call of the step.
    rate_hz : float
        The controller's rate, Hz (the period is ``1 / rate_hz``).
    clock_hz : float
        The clock the share is stated at, Hz.

    Returns
    -------
    dict
        ``instructions_worst`` (the largest count, ``None`` without counts),
        ``steps_measured``, ``clock_hz``, ``step_time_lower_s`` (the worst count over the
        clock: a lower bound of its time) and ``period_share_lower`` (that over the
        period); ``None`` values without counts.

    Examples
    --------
    >>> round(step_budget([2100, 2300], 1000.0)["period_share_lower"], 6)   # 2300 / 168e6 * 1000
    0.01369
    """
    worst = max(counts) if len(counts) else None
    time = None if worst is None else worst / clock_hz
    return {"instructions_worst": worst, "steps_measured": len(counts), "clock_hz": clock_hz,
            "step_time_lower_s": time,
            "period_share_lower": None if time is None else time * rate_hz}


def budget_words(report: dict) -> str:
    """The budget of a report (:func:`step_budget`'s keys) as one phrase."""
    if report.get("instructions_worst") is None:
        return "no step measured"
    return (f"worst {report['instructions_worst']} instructions over "
            f"{report['steps_measured']} measured steps: >= "
            f"{report['step_time_lower_s'] * 1e6:.3g} us at "
            f"{report['clock_hz'] / 1e6:g} MHz, >= {report['period_share_lower']:.2%} of the "
            "period")
