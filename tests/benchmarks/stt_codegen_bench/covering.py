"""``stt-codegen bench covering``: covering many polygons by boxes, and designing around them.

The spec: ``count`` random convex polygons at one ``tolerance`` (kind ``"polygons"`` of
:func:`~.arenas.make_arena`: 3-7 vertices, radius 0.05-0.2 m, centres in ``[0.9, 4.1]^2``,
seeded, in the 5 m x 5 m arena with the start ``[0, 0.5]^2`` and the target
``[4.5, 5]^2``). Measured, in this process: the boxes of the covering, the CPU and wall
seconds of ``parse_spec`` (which covers every polygon) and of ``design_tube`` (search and
certificate). The tests count
the covering's work instead (``tests/test_covering.py``); this command gives the seconds.
"""

from __future__ import annotations

import time
from typing import Any

from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.spec.loader import parse_spec

from .arenas import DEFAULT_POLYGONS, DEFAULT_TOLERANCE, make_arena
from .report import machine, machine_line, table

__all__ = ["format_covering_report", "run_covering_bench"]


def _timed(fn):
    """``(result, cpu_seconds, wall_seconds)`` of ``fn()``."""
    cpu, wall = time.process_time(), time.perf_counter()
    result = fn()
    return result, time.process_time() - cpu, time.perf_counter() - wall


def run_covering_bench(seed: int = 0, count: int = DEFAULT_POLYGONS,
                       tolerance: float = DEFAULT_TOLERANCE) -> dict[str, Any]:
    """Cover and design the ``"polygons"`` arena of :func:`~.arenas.make_arena`, timed.

    Parameters
    ----------
    seed : int, optional
        Seed of the polygons.
    count : int, optional
        Number of polygons, >= 0.
    tolerance : float, optional
        Every polygon's covering tolerance, metres, > 0.

    Returns
    -------
    dict
        ``spec``, ``seed``, ``polygons``, ``tolerance``, ``boxes`` (obstacles after
        covering), ``covering`` and ``design`` (each ``cpu_s`` and ``wall_s``), ``designed``
        (bool), ``method``, ``certified`` and ``reason`` (of a refusal, else ``""``),
        ``machine``.

    Raises
    ------
    SpecError
        ``count`` negative or ``tolerance`` not positive.
    """
    if count < 0:
        raise SpecError("count", f"must be non-negative, got {count}")
    if not tolerance > 0:
        raise SpecError("tolerance", f"must be positive, got {tolerance}")
    text = make_arena("polygons", seed, polygons=count, tolerance=tolerance)
    spec, cover_cpu, cover_wall = _timed(lambda: parse_spec(text))
    reason, found = "", None

    def design():
        nonlocal reason
        try:
            return design_tube(spec)
        except DesignError as exc:
            reason = str(exc)
            return None

    found, design_cpu, design_wall = _timed(design)
    return {"spec": spec.name, "seed": seed, "polygons": count, "tolerance": tolerance,
            "boxes": len(spec.obstacles),
            "covering": {"cpu_s": cover_cpu, "wall_s": cover_wall},
            "design": {"cpu_s": design_cpu, "wall_s": design_wall},
            "designed": found is not None,
            "method": None if found is None else found.method,
            "certified": found is not None and bool(found.check.passed),
            "reason": reason, "machine": machine()}


def format_covering_report(report: dict[str, Any]) -> str:
    """The human-readable table of :func:`run_covering_bench`'s result.

    Parameters
    ----------
    report : dict
        The result of :func:`run_covering_bench`.

    Returns
    -------
    str
        The spec line, the CPU and wall time table, the outcome and the machine line.
    """
    cover, design = report["covering"], report["design"]
    outcome = (f"designed ({report['method']}), certified: "
               f"{'yes' if report['certified'] else 'no'}" if report["designed"]
               else f"no design: {report['reason']}")
    rows = [["covering (parse_spec)", f"{cover['cpu_s']:.2f} s", f"{cover['wall_s']:.2f} s"],
            ["design (design_tube)", f"{design['cpu_s']:.2f} s", f"{design['wall_s']:.2f} s"]]
    return "\n".join([
        f"{report['spec']}: {report['polygons']} polygons at tolerance {report['tolerance']:g}, "
        f"{report['boxes']} boxes",
        table(["step", "CPU", "wall"], rows), outcome, machine_line(report["machine"])])

