"""Summaries, tables and machine description shared by the ``bench`` subcommands."""

from __future__ import annotations

import os
import platform
import subprocess
from collections import Counter
from typing import Any

import numpy as np

__all__ = ["machine", "machine_line", "seconds_text", "summarize", "table"]


def machine() -> dict[str, Any]:
    """The machine a benchmark ran on: CPU model, CPUs usable, OS, Python, C compiler.

    Returns
    -------
    dict
        ``cpu`` (model name), ``cpus`` (usable by this process), ``system``, ``python`` and
        ``cc`` (the first line of ``cc --version``, or ``"unknown"``).
    """
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:  # pragma: no cover - not Linux
        pass
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        cpus = os.cpu_count() or 1
    try:
        cc = subprocess.run(["cc", "--version"], capture_output=True, text=True,
                            timeout=10).stdout.splitlines()[0]
    except (OSError, IndexError, subprocess.SubprocessError):
        cc = "unknown"
    return {"cpu": cpu, "cpus": cpus, "system": f"{platform.system()} {platform.release()}",
            "python": platform.python_version(), "cc": cc}


def machine_line(info: dict[str, Any]) -> str:
    """One line describing :func:`machine`'s output.

    Parameters
    ----------
    info : dict
        From :func:`machine`.

    Returns
    -------
    str
        ``machine: <cpu>, <cpus> CPUs, <system>, Python <version>, <cc>``.
    """
    return (f"machine: {info['cpu']}, {info['cpus']} CPUs, {info['system']}, "
            f"Python {info['python']}, {info['cc']}")


def summarize(outcomes: list[dict[str, Any]]) -> dict[str, Any]:
    """Success rate, time statistics and failures by reason of one method.

    Parameters
    ----------
    outcomes : list of dict
        Per arena, ``{"success": bool, "seconds": float, "reason": str}``, for the
        arenas with a closed loop ``"peak_u"`` and ``"effort"`` (floats) and, for a tube
        controller, ``"max_abs_e"`` (the state's largest normalized error in its tube).

    Returns
    -------
    dict
        ``runs``, ``successes``, ``success_rate`` (0..1), ``time_median_s`` and
        ``time_p95_s`` (design or planning time over all runs, failed ones included,
        seconds), ``failures`` (reason -> count, most frequent first) and the control
        effort over the ``effort_runs`` satisfied runs: ``peak_u_median``,
        ``peak_u_p95`` (the largest ``|u_i|`` of a run) and ``effort_median``,
        ``effort_p95`` (its ``integral |u|^2 dt``), ``None`` without such runs;
        and, over the satisfied runs that report it, ``max_abs_e_median`` and
        ``max_abs_e_max`` (``None`` without any).
    """
    seconds = np.array([o["seconds"] for o in outcomes], dtype=float)
    successes = sum(bool(o["success"]) for o in outcomes)
    failures = Counter(o["reason"] for o in outcomes if not o["success"])
    errors = np.array([o["max_abs_e"] for o in outcomes
                       if o["success"] and o.get("max_abs_e") is not None], dtype=float)
    return {
        "max_abs_e_median": float(np.median(errors)) if errors.size else None,
        "max_abs_e_max": float(errors.max()) if errors.size else None,
        "runs": len(outcomes),
        "successes": successes,
        "success_rate": successes / len(outcomes) if outcomes else 0.0,
        "time_median_s": float(np.median(seconds)) if len(seconds) else None,
        "time_p95_s": float(np.percentile(seconds, 95)) if len(seconds) else None,
        "failures": dict(sorted(failures.items(), key=lambda kv: (-kv[1], kv[0]))),
        **_effort(outcomes),
    }


def _effort(outcomes: list[dict[str, Any]]) -> dict[str, Any]:
    """Median and p95 of the peak ``|u|`` and of ``integral |u|^2 dt`` over the satisfied
    runs (``peak_u``, ``effort`` of each outcome; older outcomes without them count
    none)."""
    done = [o for o in outcomes if o["success"] and o.get("peak_u") is not None]
    peak = np.array([o["peak_u"] for o in done], dtype=float)
    effort = np.array([o["effort"] for o in done], dtype=float)

    def stat(values: np.ndarray, q: float) -> float | None:
        return float(np.percentile(values, q)) if values.size else None

    return {"effort_runs": len(done),
            "peak_u_median": stat(peak, 50), "peak_u_p95": stat(peak, 95),
            "effort_median": stat(effort, 50), "effort_p95": stat(effort, 95)}


def table(header: list[str], rows: list[list[str]]) -> str:
    """A plain-text table with columns padded to their widest cell (Markdown-compatible).

    Parameters
    ----------
    header : list of str
        Column titles.
    rows : list of list of str
        Cells, one list per row, as many as the header.

    Returns
    -------
    str
        The table, lines separated by newlines.
    """
    widths = [max(len(str(c)) for c in column) for column in zip(header, *rows)]

    def line(cells):
        return "| " + " | ".join(str(c).ljust(w) for c, w in zip(cells, widths)) + " |"

    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    return "\n".join([line(header), sep] + [line(r) for r in rows])


def seconds_text(value: float | None) -> str:
    """A duration with a sensible unit (ns, us, ms, s).

    Parameters
    ----------
    value : float or None
        Seconds.

    Returns
    -------
    str
        Three significant digits and the unit (``"1.23 ms"``), or ``"-"`` for ``None``.
    """
    if value is None:
        return "-"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if abs(value) >= scale:
            return f"{value / scale:.3g} {unit}"
    return f"{value / 1e-9:.3g} ns"
