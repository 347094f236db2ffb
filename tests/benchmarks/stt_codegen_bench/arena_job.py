"""One arena, every method: the unit of work of ``stt-codegen bench arenas``.

:func:`plan_arena` (designs and plans, timed) and :func:`loop_arena` (closed loops) are
plain top-level functions of picklable arguments returning picklable data, so that they
run unchanged in a local process pool or on a Dask worker; the bench runs the first over
every arena, then the second, so that no compiler or simulation runs beside a timed
design; :func:`run_arena` is both for one arena.

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
same sampling rate and the same judge, :func:`stt_codegen.runtime.simulate.run_closed_loop`.
"""

from __future__ import annotations

import re
import time
from typing import Any

from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import SimulationResult
from .arenas import arena_spec

__all__ = ["LABELS", "METHODS", "closed_loop_failure", "design_failure", "loop_arena",
           "plan_arena", "run_arena"]

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
    ``design: gain cannot follow the tube`` (the paper's method, :func:`stt_codegen.design.
    tracking.unfollowable`), ``design: bound too fast for the sampling rate``,
    ``design: <certificate property>``
    (e.g. ``avoids obstacle``, ``non-empty``, ``inside target after t_c``),
    ``design: other``.

    Parameters
    ----------
    message : str
        The error's message.

    Returns
    -------
    str
        The category.
    """
    if "no via-point path" in message:
        return "design: no free passage for via points"
    if "comes within" in message:
        return "design: obstacle next to target"
    if "cannot be circumvented" in message:
        return "design: no room beside obstacle"
    if "is proved only to |e|" in message:
        return "design: gain cannot follow the tube"
    first = message.split("; ")[0]
    if "moves" in first and "tube widths" in first:
        return "design: bound too fast for the sampling rate"
    found = re.search(r"(" + "|".join(map(re.escape, CERTIFICATE_PROPERTIES)) + r")[ \d]*fails",
                      first)
    return f"design: {found.group(1)}" if found else "design: other"


def closed_loop_failure(result: SimulationResult) -> str:
    """Why a closed-loop run fails Definition 2.1 (empty when it satisfies it).

    Parameters
    ----------
    result : SimulationResult
        The judged run.

    Returns
    -------
    str
        ``""``, ``"collision"``, ``"left the arena"`` or ``"target not reached by t_c"``.
    """
    if result.satisfied:
        return ""
    if result.collision:
        return "collision"
    if result.left_state_space:
        return "left the arena"
    if not result.reached:
        return "target not reached by t_c"
    return "other"  # pragma: no cover - satisfied is exactly the three above


def _outcome(seconds: float, reason: str, result: SimulationResult | None,
             tube: bool = False) -> dict[str, Any]:
    return {"success": not reason, "seconds": seconds, "reason": reason,
            "reach_time": None if result is None else result.reach_time,
            "clearance": None if result is None else result.min_obstacle_clearance,
            # the largest |u_i| over the run and the inputs, and integral |u|^2 dt
            "peak_u": None if result is None else max(result.max_abs_u),
            "effort": None if result is None else result.control_effort,
            # the state's normalized error in its tube (a baseline has no tube)
            "max_abs_e": result.max_abs_e if tube and result is not None else None}


def _plan_stt(spec, method: str) -> dict[str, Any]:
    """Design with ``tube.method = method``: ``{"seconds", "tube"}`` or ``{"seconds",
    "reason"}``."""
    from dataclasses import replace

    from stt_codegen.design.search import design_tube
    spec = replace(spec, tube=replace(spec.tube, method=method))
    begin = time.perf_counter()
    try:
        design = design_tube(spec)
    except DesignError as exc:
        return {"seconds": time.perf_counter() - begin, "reason": design_failure(str(exc))}
    return {"seconds": design.design_time_s, "tube": design.tube}


def plan_arena(seed: int, index: int, methods: tuple[str, ...] = METHODS) -> dict[str, Any]:
    """Phase 1 of :func:`run_arena`: every method's design or plan, timed.

    Nothing else runs in the worker meanwhile (no compiler, no closed loop), so the times
    of the methods are comparable and not inflated by the bench's own simulations.

    Parameters
    ----------
    seed, index : int
        Which arena (``"paper"`` of :func:`~.arenas.make_arena`).
    methods : tuple of str
        Subset of :data:`METHODS`.

    Returns
    -------
    dict
        ``{"index", "plans": {method: {"seconds", and "tube" (STT), "plan" (baselines)
        or "reason" (failure category)}}}``; picklable.

    Raises
    ------
    ValueError
        A method not in :data:`METHODS`.
    """
    spec = arena_spec("paper", seed, index)
    plans: dict[str, Any] = {}
    for method in methods:
        if method in ("stt-paper", "stt"):
            plans[method] = _plan_stt(spec, "paper" if method == "stt-paper" else "auto")
        elif method == "astar":
            from .astar import plan_astar
            plan = plan_astar(spec)
            plans[method] = {"seconds": plan.seconds, "plan": plan}
        elif method == "rrtstar":
            from .rrtstar import plan_rrtstar
            plan = plan_rrtstar(spec, seed=1 + 100_003 * seed + index)
            plans[method] = {"seconds": plan.seconds, "plan": plan}
        else:
            raise ValueError(f"unknown method {method!r}")
    return {"index": index, "plans": plans}


def loop_arena(seed: int, index: int, plans: dict[str, Any]) -> dict[str, Any]:
    """Phase 2 of :func:`run_arena`: the closed loop of every method's design or plan.

    STT tubes run the generated C controller (backend ``c``); a tube that two methods share
    (``auto`` returning the paper's tube) runs once. Baseline paths run the tracker.

    Parameters
    ----------
    seed, index : int
        Which arena (``"paper"`` of :func:`~.arenas.make_arena`), as given to :func:`plan_arena`.
    plans : dict
        ``plans`` of :func:`plan_arena` for this arena.

    Returns
    -------
    dict
        ``{"index", "name", "methods": {method: {"success" (bool), "seconds"
        (design or planning time, s), "reason" (failure category, "" on success),
        "reach_time" (s or None), "clearance" (m or None), "peak_u" (the largest
        ``|u_i|`` over the run and the inputs, m/s, or None), "effort" (``integral
        |u|^2 dt``, m^2/s, or None), "max_abs_e" (the largest ``|e_i|`` of the state in its
        tube, STT methods; ``None`` for the baselines)}}}``; the last five are ``None``
        without a closed loop.
    """
    from stt_codegen.runtime.simulate import run_closed_loop
    from .tracker import track
    spec = arena_spec("paper", seed, index)
    out: dict[str, Any] = {}
    runs: dict = {}
    for method, planned in plans.items():
        if "reason" in planned:
            out[method] = _outcome(planned["seconds"], planned["reason"], None)
        elif "tube" in planned:
            tube = planned["tube"]
            if tube not in runs:
                runs[tube] = run_closed_loop(spec, tube, backend="c", seed=index)
            out[method] = _outcome(planned["seconds"], closed_loop_failure(runs[tube]),
                                   runs[tube], tube=True)
        else:
            plan = planned["plan"]
            if plan.path is None:
                out[method] = _outcome(plan.seconds, plan.reason, None)
            else:
                result = track(spec, plan.path, seed=index)
                out[method] = _outcome(plan.seconds, closed_loop_failure(result), result)
    return {"index": index, "name": spec.name, "methods": out}


def run_arena(seed: int, index: int, methods: tuple[str, ...] = METHODS) -> dict[str, Any]:
    """Run every method on arena ``index`` of ``seed``: :func:`plan_arena` (same
    parameters), then :func:`loop_arena` (same result). The bench runs the two phases over
    all arenas in turn.

    Parameters
    ----------
    seed : int
        Arena seed, >= 0.
    index : int
        Arena index, >= 0.
    methods : tuple of str, optional
        Subset of :data:`METHODS`.

    Returns
    -------
    dict
        As :func:`loop_arena`.
    """
    return loop_arena(seed, index, plan_arena(seed, index, methods)["plans"])
