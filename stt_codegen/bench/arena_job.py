"""One arena, every method: the unit of work of ``stt-codegen bench arenas``.

:func:`run_arena` is a plain top-level function of picklable arguments returning plain
data, so that it runs unchanged in a local process pool or on a Dask worker.

Methods (:data:`METHODS`):

* ``stt-paper``: :func:`~stt_codegen.design.search.design_tube` with ``tube.method =
  "paper"`` (the paper's single reach tube with circumvents, and its continuous-time
  certificate), then the generated C controller (backend ``c``) in closed loop; the time
  reported is the design's (:attr:`~stt_codegen.design.result.Design.design_time_s`);
* ``stt``: the same with the default ``tube.method = "auto"`` (via points when the
  paper's design fails); when it returns the paper's tube the closed loop is not run
  twice;
* ``astar``: :func:`~.astar.plan_astar` then :func:`~.tracker.track`;
* ``rrtstar``: :func:`~.rrtstar.plan_rrtstar` then :func:`~.tracker.track` (only when
  OMPL is installed).

Every method runs on the same arena with the same disturbance (seed = arena index), the
same sampling rate and the same judge, :func:`stt_codegen.runtime.simulate.simulate`.
"""

from __future__ import annotations

import re
import time
from typing import Any

from ..errors import DesignError
from ..runtime.simulate import SimulationResult
from .arenas import generate_arena

METHODS = ("stt-paper", "stt", "astar", "rrtstar")
#: Names of the certificate's properties (:mod:`stt_codegen.design.certificate`), as they appear
#: in design errors.
CERTIFICATE_PROPERTIES = ("non-empty", "initial state inside", "inside state space",
                          "avoids obstacle", "inside target after t_c")
#: Human-readable method names for tables.
LABELS = {"stt-paper": "STT paper only (C controller)", "stt": "STT auto (C controller)",
          "astar": "A* + tracker", "rrtstar": "RRT* + tracker"}


def design_failure(message: str) -> str:
    """A short category of a :class:`~stt_codegen.errors.DesignError` message.

    Categories: ``design: no free passage for via points``,
    ``design: obstacle next to target``, ``design: no room beside obstacle``,
    ``design: bound too fast for the sampling rate``, ``design: <certificate property>``
    (e.g. ``avoids obstacle``, ``non-empty``, ``inside target after t_c``),
    ``design: other``.
    """
    if "no via-point path" in message:
        return "design: no free passage for via points"
    if "comes within" in message:
        return "design: obstacle next to target"
    if "cannot be circumvented" in message:
        return "design: no room beside obstacle"
    first = message.split("; ")[0]
    if "moves" in first and "tube widths" in first:
        return "design: bound too fast for the sampling rate"
    found = re.search(r"(" + "|".join(map(re.escape, CERTIFICATE_PROPERTIES)) + r")[ \d]*fails",
                      first)
    return f"design: {found.group(1)}" if found else "design: other"


def closed_loop_failure(result: SimulationResult) -> str:
    """Why a closed-loop run fails Definition 2.1 (empty when it satisfies it)."""
    if result.satisfied:
        return ""
    if result.collision:
        return "collision"
    if result.left_state_space:
        return "left the arena"
    if not result.reached:
        return "target not reached by t_c"
    return "other"  # pragma: no cover - satisfied is exactly the three above


def _outcome(seconds: float, reason: str, result: SimulationResult | None) -> dict[str, Any]:
    return {"success": not reason, "seconds": seconds, "reason": reason,
            "reach_time": None if result is None else result.reach_time,
            "clearance": None if result is None else result.min_obstacle_clearance}


def _run_stt(spec, index: int, method: str, runs: dict) -> dict[str, Any]:
    """Design with ``tube.method = method`` and run the C controller; ``runs`` caches the
    closed loop of a tube already simulated (same tube, same seed: same run)."""
    from dataclasses import replace

    from ..design.search import design_tube
    from ..runtime.simulate import simulate
    spec = replace(spec, tube=replace(spec.tube, method=method))
    begin = time.perf_counter()
    try:
        design = design_tube(spec)
    except DesignError as exc:
        return _outcome(time.perf_counter() - begin, design_failure(str(exc)), None)
    if design.tube not in runs:
        runs[design.tube] = simulate(spec, design.tube, backend="c", seed=index)
    result = runs[design.tube]
    return _outcome(design.design_time_s, closed_loop_failure(result), result)


def _run_baseline(spec, plan, index: int) -> dict[str, Any]:
    from .tracker import track
    if plan.path is None:
        return _outcome(plan.seconds, plan.reason, None)
    result = track(spec, plan.path, seed=index)
    return _outcome(plan.seconds, closed_loop_failure(result), result)


def run_arena(seed: int, index: int, methods: tuple[str, ...] = METHODS) -> dict[str, Any]:
    """Run every method on arena ``index`` of ``seed``.

    Parameters
    ----------
    seed, index : int
        Which arena (see :func:`~.arenas.generate_arena`).
    methods : tuple of str
        Subset of :data:`METHODS`.

    Returns
    -------
    dict
        ``{"index", "name", "methods": {method: {"success" (bool), "seconds"
        (design or planning time, s), "reason" (failure category, "" on success),
        "reach_time" (s or None), "clearance" (m or None)}}}``.
    """
    arena = generate_arena(seed, index)
    spec = arena.to_spec()
    out: dict[str, Any] = {}
    runs: dict = {}
    for method in methods:
        if method in ("stt-paper", "stt"):
            out[method] = _run_stt(spec, index, "paper" if method == "stt-paper" else "auto",
                                   runs)
        elif method == "astar":
            from .astar import plan_astar
            out[method] = _run_baseline(spec, plan_astar(spec), index)
        elif method == "rrtstar":
            from .rrtstar import plan_rrtstar
            out[method] = _run_baseline(spec, plan_rrtstar(spec, seed=1 + 100_003 * seed + index), index)
        else:
            raise ValueError(f"unknown method {method!r}")
    return {"index": index, "name": arena.name, "methods": out}
