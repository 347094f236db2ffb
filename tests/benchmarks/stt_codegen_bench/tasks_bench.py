"""``stt-codegen bench tasks``: timed reach tasks, STT against sequential A* with waiting.

On each random problem (kind ``"tasks"`` of :func:`~.arenas.make_arena`: 2-3 timed reach
goals, the first with two alternatives, four static obstacles, 0-4 moving obstacles):

* **STT**: :func:`~stt_codegen.design.search.design_tube` (via legs through the tasks'
  boxes, every task certified for every ``t``), then the generated C controller (backend
  ``c``) in closed loop; time: the design's ``design_time_s``.
* **A* + tracker**: :func:`~.task_baseline.plan_timed` (legs on the static grid, each
  waiting at its start until it is clear of the moving obstacles in space-time) then
  :func:`~.task_baseline.track_timed`; time: the planning (grid, searches and timing).

Both closed loops are :func:`~stt_codegen.runtime.simulate.run_closed_loop` with the
same disturbance seed (the problem's index) and judge: *satisfied* means every task met in
its window, the target reached by ``t_c``, no collision (with a moving obstacle: where it
is at that time), the state space kept. Effort is
``integral |u|^2 dt`` over the run (m^2/s). All in one process, problem after problem, the
timed design or plan never beside a compiler or a simulation.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from stt_codegen.errors import DesignError, SpecError
from .arenas import arena_spec
from .task_baseline import plan_timed, track_timed

__all__ = ["METHODS", "format_tasks_report", "run_tasks_bench"]

METHODS = ("stt", "astar")
LABELS = {"stt": "STT (C controller)", "astar": "sequential A* + waiting + tracker"}


def run_task_problem(seed: int, index: int) -> dict[str, Any]:
    """Both methods on problem ``index`` of ``seed`` (module notes).

    Returns
    -------
    dict
        ``{"index", "tasks" (count), "moving" (moving obstacles), "methods": {method:
        {"satisfied", "seconds", "reason" ("" when satisfied), "effort" (m^2/s or None),
        "choices" (alternative per task or None), and for STT with moving obstacles "motion" (how the tube was
        found, ``Design.motion``)}}}``.
    """
    from stt_codegen.design.search import design_tube
    from stt_codegen.runtime.simulate import run_closed_loop
    spec = arena_spec("tasks", seed, index)
    out: dict[str, Any] = {}
    try:
        design = design_tube(spec)
    except DesignError as exc:
        out["stt"] = {"satisfied": False, "seconds": None, "reason": f"no design: "
                      f"{exc.kind.value if exc.kind else 'design'}", "effort": None,
                      "choices": None}
    else:
        seconds = design.design_time_s
        result = run_closed_loop(spec, design.tube, backend="c", seed=index)
        out["stt"] = _outcome(seconds, result, list(design.task_choices))
        out["stt"]["motion"] = design.motion
    plan = plan_timed(spec)
    if plan.legs is None:
        out["astar"] = {"satisfied": False, "seconds": plan.seconds, "reason": plan.reason,
                        "effort": None, "choices": None}
    else:
        out["astar"] = _outcome(plan.seconds, track_timed(spec, plan, seed=index),
                                list(plan.choices))
    return {"index": index, "tasks": len(spec.tasks), "moving": len(spec.moving_obstacles),
            "methods": out}


def _outcome(seconds: float, result, choices: list[int]) -> dict[str, Any]:
    missed = [t.task for t in result.tasks if not t.met]
    reason = ("" if result.satisfied else
              f"missed {', '.join(missed)}" if missed else
              "collision" if result.collision else
              "left the state space" if result.left_state_space else "target not reached")
    return {"satisfied": bool(result.satisfied), "seconds": seconds, "reason": reason,
            "effort": result.control_effort, "choices": choices}


def run_tasks_bench(count: int, seed: int, progress: bool = False) -> dict[str, Any]:
    """Run :func:`run_task_problem` on problems ``0 .. count - 1`` of ``seed`` and sum up.

    Parameters
    ----------
    count : int
        At least 1.
    seed : int
        Non-negative.
    progress : bool
        Print one line per problem to standard error.

    Returns
    -------
    dict
        ``{"count", "seed", "problems" (per problem), "with_moving" (problems with at
        least one moving obstacle), "summary": {method: {"satisfied"
        (count), "rate", "seconds_median", "seconds_p95" (design or planning, s),
        "effort_median" (over its satisfied runs, m^2/s)}}, "stt_misses_baseline"
        (indices where the baseline is satisfied and STT is not)}``.

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``) or a negative seed (field ``seed``).
    """
    import sys
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    if seed < 0:
        raise SpecError("seed", f"must be non-negative, got {seed}")
    problems = []
    for k in range(count):
        problems.append(run_task_problem(seed, k))
        if progress:
            m = problems[-1]["methods"]
            print(f"problem {k}: " + ", ".join(f"{name} {'yes' if m[name]['satisfied'] else 'no'}"
                                                for name in METHODS), file=sys.stderr)
    summary = {}
    for name in METHODS:
        rows = [p["methods"][name] for p in problems]
        seconds = np.array([r["seconds"] for r in rows if r["seconds"] is not None])
        efforts = [r["effort"] for r in rows if r["satisfied"]]
        ok = sum(r["satisfied"] for r in rows)
        summary[name] = {
            "satisfied": ok, "rate": ok / count,
            "seconds_median": float(np.median(seconds)) if seconds.size else None,
            "seconds_p95": float(np.percentile(seconds, 95)) if seconds.size else None,
            "effort_median": float(np.median(efforts)) if efforts else None}
    misses = [p["index"] for p in problems
              if p["methods"]["astar"]["satisfied"] and not p["methods"]["stt"]["satisfied"]]
    return {"count": count, "seed": seed, "problems": problems,
            "with_moving": sum(p["moving"] > 0 for p in problems), "summary": summary,
            "stt_misses_baseline": misses}


def format_tasks_report(report: dict[str, Any]) -> str:
    """The report of :func:`run_tasks_bench` as a table.

    Parameters
    ----------
    report : dict
        The result of :func:`run_tasks_bench`.

    Returns
    -------
    str
        The table of methods (satisfied, design or planning time, control effort), the
        problems the baseline satisfies and STT does not, and the failures by reason.
    """
    lines = [f"bench tasks: {report['count']} problems of seed {report['seed']} "
             "(2-3 timed reach goals, the first with two alternatives, 4 static obstacles, "
             f"0-4 moving obstacles: {report['with_moving']} problems have some)",
             f"{'method':<36}{'satisfied':>10}{'time median':>13}{'p95':>10}"
             f"{'effort median':>15}"]
    for name in METHODS:
        s = report["summary"][name]

        def ms(v):
            return "-" if v is None else f"{1000 * v:.1f} ms"
        effort = "-" if s["effort_median"] is None else f"{s['effort_median']:.3g}"
        lines.append(f"{LABELS[name]:<36}{s['satisfied']:>4}/{report['count']:<5}"
                     f"{ms(s['seconds_median']):>13}{ms(s['seconds_p95']):>10}{effort:>15}")
    misses = report["stt_misses_baseline"]
    lines.append("STT satisfied on every problem the baseline satisfies" if not misses else
                 f"the baseline satisfied, STT not: problems {misses}")
    failures: dict[str, dict[str, int]] = {}
    for p in report["problems"]:
        for name, r in p["methods"].items():
            if not r["satisfied"]:
                key = r["reason"].split(" (")[0]
                failures.setdefault(name, {}).setdefault(key, 0)
                failures[name][key] += 1
    for name, reasons in failures.items():
        lines.append(f"{LABELS[name]} failures: " + ", ".join(
            f"{k} {v}" for k, v in sorted(reasons.items())))
    return "\n".join(lines)
