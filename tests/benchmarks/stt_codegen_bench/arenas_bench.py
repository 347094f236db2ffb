"""``stt-codegen bench arenas``: the tube controller and two planner-plus-tracker baselines
on the same random arenas, side by side in one run (the paper's Table I, redone)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from stt_codegen.errors import SpecError
from stt_codegen.system import atomic_write
from .arena_job import LABELS, METHODS, loop_arena, plan_arena
from .arenas import make_arena
from .parallel import run_parallel
from .report import machine, machine_line, seconds_text, summarize, table
from .rrtstar import ompl_available

__all__ = ["available_methods", "format_arenas_report", "run_arenas_bench", "write_specs"]


def available_methods() -> tuple[tuple[str, ...], dict[str, str]]:
    """The methods that can run here, and why the others cannot (method -> reason).

    Returns
    -------
    methods : tuple of str
        The runnable methods of :data:`~.arena_job.METHODS`, in its order.
    skipped : dict of str to str
        Method -> the reason it cannot run (``rrtstar`` without OMPL).
    """
    skipped = {}
    why = ompl_available()
    if why:
        skipped["rrtstar"] = why
    return tuple(m for m in METHODS if m not in skipped), skipped


def write_specs(folder: Path, count: int, seed: int) -> list[Path]:
    """Write arenas ``0 .. count - 1`` of ``seed`` as spec files ``arena-S-K.toml``.

    Parameters
    ----------
    folder : pathlib.Path
        An existing folder.
    count : int
        Number of arenas, >= 1.
    seed : int
        Arena seed, >= 0.

    Returns
    -------
    list of pathlib.Path
        The files written, in arena order.

    Raises
    ------
    SpecError
        The folder does not exist (field ``specs``).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise SpecError("specs", f"folder {str(folder)!r} does not exist")
    paths = []
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    for k in range(count):
        path = folder / f"arena-{seed}-{k}.toml"
        text = make_arena("paper", seed, k).encode("utf-8")
        atomic_write(path, text, field="specs")
        paths.append(path)
    return paths


def run_arenas_bench(count: int, seed: int, workers: int | None = None,
                     scheduler: str | None = None, methods: tuple[str, ...] | None = None,
                     progress: bool = True) -> dict[str, Any]:
    """Run every available method on ``count`` arenas of ``seed``.

    Parameters
    ----------
    count : int
        Number of arenas, >= 1.
    seed : int
        Arena seed, >= 0.
    workers : int, optional
        Local processes (default: the usable CPUs).
    scheduler : str, optional
        Dask scheduler address; then the jobs run on that cluster.
    methods : tuple of str, optional
        Subset of :data:`~.arena_job.METHODS`; default every available one.
    progress : bool
        tqdm progress bar on standard error.

    Returns
    -------
    dict
        ``{"count", "seed", "machine", "workers", "scheduler", "skipped" (method ->
        reason), "methods" (method -> :func:`~.report.summarize`), "arenas" (per-arena
        results of :func:`~.arena_job.loop_arena`)}``.

    Raises
    ------
    SpecError
        Bad count, seed, workers, scheduler, or an unknown method.
    """
    make_arena("paper", seed)  # validates the seed
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    usable, skipped = available_methods()
    if methods is None:
        methods = usable
    for m in methods:
        if m not in METHODS:
            raise SpecError("methods", f"unknown method {m!r} (known: {', '.join(METHODS)})")
        if m in skipped:
            raise SpecError("methods", f"{m} cannot run: {skipped[m]}")
    # two phases: the timed designs and plans, then the closed loops (which compile C):
    # a design is never timed while a compiler or a simulation runs beside it
    calls = [(seed, k, tuple(methods)) for k in range(count)]
    planned = run_parallel(plan_arena, calls, workers=workers, scheduler=scheduler,
                           progress=progress, description="designs")
    arenas = run_parallel(loop_arena, [(seed, p["index"], p["plans"]) for p in planned],
                          workers=workers, scheduler=scheduler, progress=progress,
                          description="closed loops")
    summary = {m: summarize([a["methods"][m] for a in arenas]) for m in methods}
    return {"count": count, "seed": seed, "machine": machine(),
            "workers": None if scheduler else workers, "scheduler": scheduler,
            "skipped": skipped, "methods": summary, "arenas": arenas}


def format_arenas_report(report: dict[str, Any]) -> str:
    """The human-readable table of :func:`run_arenas_bench`'s result.

    Parameters
    ----------
    report : dict
        The result of :func:`run_arenas_bench`.

    Returns
    -------
    str
        The success and time table, the control-effort table and the machine line.
    """
    rows, effort = [], []
    for method, s in report["methods"].items():
        failures = ", ".join(f"{r} ({n})" for r, n in s["failures"].items()) or "-"
        error = ("-" if s["max_abs_e_max"] is None else
                 f"{s['max_abs_e_median']:.3g} / {s['max_abs_e_max']:.3g}")
        rows.append([LABELS[method], f"{s['successes']}/{s['runs']}",
                     f"{100 * s['success_rate']:.1f} %", seconds_text(s["time_median_s"]),
                     seconds_text(s["time_p95_s"]), error, failures])
        effort.append([LABELS[method], str(s.get("effort_runs", 0)),
                       *(_figure(s.get(key)) for key in ("peak_u_median", "peak_u_p95",
                                                         "effort_median", "effort_p95"))])
    lines = [f"{report['count']} arenas (seed {report['seed']}): 5 m x 5 m, four 1 m x 1 m "
             "obstacles, t_c = 9 s, single integrator, |w_i| <= 0.1 m/s, 1 kHz",
             table(["method", "satisfied", "rate", "time median", "time p95",
                    "max abs(e) median / max", "failures by reason"], rows),
             "time: STT = design_tube (search + continuous-time certificate); "
             "baselines = planning (grid/planner construction + search).",
             "max abs(e): per satisfied run, the largest normalized error of the state in "
             "its tube (1 = the tube's wall; the baselines have no tube).",
             "",
             table(["method", "satisfied runs", "peak |u| median", "peak |u| p95",
                    "effort median", "effort p95"], effort),
             "control effort over the satisfied runs: peak |u| = the largest |u_i| of a run "
             "(m/s); effort = integral of |u|^2 dt over [0, t_c] (m^2/s)."]
    for method, why in report["skipped"].items():
        lines.append(f"skipped {LABELS[method]}: {why}")
    lines.append(machine_line(report["machine"]))
    return "\n".join(lines)


def _figure(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
