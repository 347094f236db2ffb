"""``stt-codegen bench drive``: a differential-drive base beside a holonomic base on random
offices (docs/differential-drive.md, docs/performance.md).

Office ``k`` of seed ``S`` is arena ``k`` of the kinds ``"office-drive"`` and
``"office-holonomic"`` of :func:`~.arenas.make_arena` (the same room, obstacles and start;
the two bases and their plants are described there). On every office, in one run, both
specs are designed and run with the generated C on their own plants, with the same seed.

The design time is :attr:`~stt_codegen.design.result.Design.design_time_s` (the design and
its certificate, in process); compare the two methods' figures within one run.
"""

from __future__ import annotations

import numpy as np

from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import parse_spec

from .arenas import make_arena

__all__ = ["format_office_report", "run_office_bench"]

METHODS = ("drive", "holonomic")


def _run(text: str, seed: int) -> dict:
    try:
        spec = parse_spec(text)
        design = design_tube(spec)
    except (DesignError, SpecError) as exc:
        return {"satisfied": False, "reason": f"no design: {str(exc)[:100]}", "seconds": None}
    result = simulate(design, backend="c", seed=seed)
    return {"satisfied": bool(result.satisfied), "seconds": design.design_time_s,
            "reach_time": result.reach_time, "clearance": result.min_obstacle_clearance,
            "peak_u": [float(v) for v in result.max_abs_u],
            "reason": "" if result.satisfied else ("collision" if result.collision else
                                                   "left the tube" if not result.stayed_in_tube
                                                   else "target not reached")}


def run_office_bench(count: int, seed: int) -> dict:
    """Both bases on ``count`` offices, sequentially (each design timed in process).

    Parameters
    ----------
    count : int
        Number of offices, >= 1.
    seed : int
        Office seed, >= 0.

    Returns
    -------
    dict
        ``count``, ``seed``, per method ``satisfied`` (count), ``design_median_s`` and
        ``design_p95_s`` (over the designed offices), ``ratio`` (the drive's median over
        the holonomic base's) and ``offices`` (per office and method: ``satisfied``,
        ``seconds``, ``reach_time``, ``clearance``, ``peak_u``, ``reason``).

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``) or a negative seed.
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    offices = [{"index": k, **{m: _run(make_arena(f"office-{m}", seed, k), k) for m in METHODS}}
               for k in range(count)]
    out: dict = {"count": count, "seed": seed, "offices": offices}
    for m in METHODS:
        times = [o[m]["seconds"] for o in offices if o[m]["seconds"] is not None]
        out[m] = {"satisfied": sum(o[m]["satisfied"] for o in offices),
                  "design_median_s": float(np.median(times)) if times else None,
                  "design_p95_s": float(np.percentile(times, 95)) if times else None}
    a, b = out["drive"]["design_median_s"], out["holonomic"]["design_median_s"]
    out["ratio"] = a / b if a and b else None
    return out


def format_office_report(report: dict) -> str:
    """The table of both bases and one line per failed run.

    Parameters
    ----------
    report : dict
        :func:`run_office_bench`'s result.

    Returns
    -------
    str
    """
    lines = [f"{report['count']} offices, seed {report['seed']}, generated C, one run",
             "| base | satisfied | design median | design p95 |", "|---|---|---|---|"]
    for m in METHODS:
        r = report[m]
        med = "-" if r["design_median_s"] is None else f"{1e3 * r['design_median_s']:.1f} ms"
        p95 = "-" if r["design_p95_s"] is None else f"{1e3 * r['design_p95_s']:.1f} ms"
        lines.append(f"| {m} | {r['satisfied']}/{report['count']} | {med} | {p95} |")
    if report["ratio"] is not None:
        lines.append(f"design median, drive / holonomic: {report['ratio']:.2f}")
    for office in report["offices"]:
        for m in METHODS:
            if not office[m]["satisfied"]:
                lines.append(f"  office {office['index']} {m}: {office[m]['reason']}")
    return "\n".join(lines)
