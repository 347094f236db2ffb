"""``stt-codegen bench scaling``: code size, generation time and step cost against the
number of obstacles and the state dimension, and whether a step pays for every obstacle
or only for the active ones.

Random specs with hundreds of obstacles do not design (the arena fills up), so the
designs are built directly (:func:`synthetic_design`): a :class:`~stt_codegen.tube.parameters.TubeDesign`
on ``[0, 5]^n`` from ``x(0) = 0.25`` to the target box ``[4.55, 4.95]^n`` with ``m``
synthetic :class:`~stt_codegen.tube.parameters.Circumvent` s (seeded: dimension and side at random,
window centre in ``[0.5, 8.5]`` s, half-width in ``[0.3, 1]`` s, height in ``[0.2, 1]`` m),
the bundled specs' tube parameters and 1 kHz. They are not certified: they only have the
size and structure of real designs, which is what code size and step cost depend on.

The *active-window* experiment builds three designs with the same ``m`` circumvents that
differ only in their windows: all open during the whole recorded run ``[0, t_c)``, all
closed (windows after ``t_c + 10`` s), and the random windows above. The generated step
evaluates only the open windows, so the closed design is much cheaper.

The *sparse-window* experiment compares a design with :data:`SPARSE_SMALL` circumvents and
one with :data:`SPARSE_LARGE`, both with windows spread evenly over ``[0.5, 8.5]`` s so
that at most :data:`MAX_SIMULTANEOUS` are open at a time: instructions per step (ratio
large / small) and the size of the object's code (``.text``; only the tables grow).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from stt_codegen.errors import SpecError
from stt_codegen.tube.parameters import LOWER, UPPER, Circumvent, TubeDesign, paper_segments
from .harness import BenchError, build_harness
from .report import machine, machine_line, seconds_text, table
from .timing import MIN_BATCH_SECONDS

__all__ = ["format_scaling_report", "run_scaling_bench", "synthetic_design"]

#: Obstacles in the dimension sweep (the case study's count).
DIMENSION_SWEEP_OBSTACLES = 4
#: Obstacles of the active-window experiment.
ACTIVE_EXPERIMENT_OBSTACLES = 100
#: Circumvents of the sparse-window experiment, and the most windows open at one time.
SPARSE_SMALL = 10
SPARSE_LARGE = 1000
MAX_SIMULTANEOUS = 16
REPEATS = 5
ARENA_SIZE = 5.0


def synthetic_design(obstacles: int, dimension: int, windows: str = "random",
                     seed: int = 0) -> TubeDesign:
    """A design of the size of a real one, with ``obstacles`` synthetic circumvents.

    Parameters
    ----------
    obstacles : int
        ``m >= 0``.
    dimension : int
        ``n >= 1``.
    windows : {"random", "open", "closed", "sparse"}
        ``"open"``: every window is ``[-1, t_c + 1]``; ``"closed"``: every window lies in
        ``[t_c + 10, t_c + 12]`` (never open before ``t_c``); ``"random"``: see the module
        docstring; ``"sparse"``: window ``j`` starts at ``0.5 + 8 j / m`` s and lasts
        ``min(1, 0.95 * 8 MAX_SIMULTANEOUS / m)`` s (at most :data:`MAX_SIMULTANEOUS` open). With ``"open"`` and ``"closed"`` the heights are scaled by 0.05 so that
        the closed loop stays inside the tube (the computation graph is the same).
    seed : int
        Seeds the random circumvents (dimension, side, window, height).

    Returns
    -------
    TubeDesign
        The design (not certified: only its size matters).

    Raises
    ------
    SpecError
        Negative counts, zero dimension or an unknown ``windows``.
    """
    if obstacles < 0:
        raise SpecError("obstacles", f"must be non-negative, got {obstacles}")
    if dimension < 1:
        raise SpecError("dimensions", f"must be at least 1, got {dimension}")
    if windows not in ("random", "open", "closed", "sparse"):
        raise SpecError("windows", f"unknown window mode {windows!r}")
    t_c = 9.0
    rng = np.random.default_rng([seed, obstacles, dimension])
    circumvents = []
    for j in range(obstacles):
        i = int(rng.integers(dimension))
        side = LOWER if rng.random() < 0.5 else UPPER
        center, radius = rng.uniform(0.5, 8.5), rng.uniform(0.3, 1.0)
        if windows == "open":
            center, radius = t_c / 2, t_c / 2 + 1.0
        elif windows == "closed":
            center, radius = t_c + 11.0, 1.0
        elif windows == "sparse":
            radius = 0.5 * min(1.0, 0.95 * 8.0 * MAX_SIMULTANEOUS / obstacles)
            center = 0.5 + 8.0 * j / obstacles + radius
        height = float(rng.uniform(0.2, 1.0))
        if windows in ("open", "closed"):  # keep x(0) and the run inside the tube
            height *= 0.05
        base = 0.0 if side == LOWER else ARENA_SIZE
        circumvents.append(Circumvent(j, i, side, float(center - radius),
                                      float(center + radius), height, base, 0.1))
    circumvents.sort(key=lambda c: (c.dimension, c.side, c.obstacle))
    n = dimension
    return TubeDesign(
        name=f"synthetic_m{obstacles}_n{dimension}", prescribed_time=t_c,
        state_lower=(0.0,) * n, state_upper=(ARENA_SIZE,) * n,
        segments=paper_segments((0.05,) * n, (0.45,) * n, (4.55,) * n, (4.95,) * n, t_c),
        initial_state=(0.25,) * n, circumvents=tuple(circumvents), smoothness=50.0,
        theta0=0.01, kappa=5.0, mu=1.0, gain=0.2, rate_hz=1000.0)


def measure(design: TubeDesign, compile_timeout: float, callgrind: bool = True,
            callgrind_steps: int = 200) -> dict[str, Any]:
    """Generation time, sizes, time and instructions per step of one design.

    Returns
    -------
    dict
        ``obstacles``, ``dimension``, ``generate_s``, ``compile_s``, ``source_bytes``,
        ``object_bytes``, ``text_bytes`` (code only), ``seconds_per_step`` (median of :data:`REPEATS` compiled-loop
        runs of about 0.2 s), ``instructions_per_step`` (callgrind, or None),
        ``operations`` (of the CasADi ``controller_step``), ``outside_tube_inputs``;
        or, when the build fails, ``error``.
    """
    from stt_codegen.codegen.emit import count_operations
    from stt_codegen.tube.model import build_model
    row: dict[str, Any] = {"obstacles": len(design.circumvents), "dimension": design.dimension}
    try:
        harness = build_harness(design, compile_timeout=compile_timeout)
    except BenchError as exc:
        row["error"] = str(exc).splitlines()[0]
        return row
    try:
        _, _, _, outside = harness.record()
        probe = harness.time_step(200, 1)[0]
        steps = max(200, int(MIN_BATCH_SECONDS / max(probe, 1e-9)))
        counts = count_operations(build_model(design)["controller_step"])
        row.update({
            "generate_s": harness.generate_seconds, "compile_s": harness.compile_seconds,
            "source_bytes": harness.source_bytes, "object_bytes": harness.object_bytes,
            "text_bytes": _text_bytes(harness.folder),
            "seconds_per_step": float(np.median(harness.time_step(steps, REPEATS))),
            "instructions_per_step": (harness.instructions_per_step(callgrind_steps)
                                      if callgrind else None),
            "operations": {"arithmetic": counts.arithmetic,
                           "transcendental": counts.transcendental, "total": counts.total},
            "outside_tube_inputs": outside})
    finally:
        harness.cleanup()
    return row


def _text_bytes(folder) -> int | None:
    """``.text`` of the generated controller's object file in a harness folder (``size -A``)."""
    import subprocess
    objects = sorted(p for p in folder.glob("*.o") if p.name != "harness.o")
    if not objects:
        return None
    try:
        out = subprocess.run(["size", "-A", str(objects[0])], capture_output=True, text=True,
                             timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    sizes = [int(line.split()[1]) for line in out.splitlines()
             if line.startswith(".text") and len(line.split()) >= 2]
    return sum(sizes) if sizes else None


def sparse_window_experiment(compile_timeout: float = 900.0, callgrind: bool = True,
                             small: int = SPARSE_SMALL, large: int = SPARSE_LARGE) -> dict:
    """Step cost and code size of ``small`` vs ``large`` circumvents, at most
    :data:`MAX_SIMULTANEOUS` windows open at a time (``windows="sparse"``, n = 2).

    Returns
    -------
    dict
        ``rows`` (:func:`measure` of each) and ``instruction_ratio`` (large / small, None
        without callgrind).
    """
    rows = [measure(synthetic_design(m, 2, windows="sparse"), compile_timeout, callgrind)
            for m in (small, large)]
    ok = all("error" not in r for r in rows)
    ratio = None
    if ok and rows[0].get("instructions_per_step") and rows[1].get("instructions_per_step"):
        ratio = rows[1]["instructions_per_step"] / rows[0]["instructions_per_step"]
    return {"rows": rows, "instruction_ratio": ratio}



def run_scaling_bench(obstacles: list[int], dimensions: list[int],
                      compile_timeout: float = 900.0, active_obstacles: int | None = None,
                      callgrind: bool = True, sparse: tuple | None = None) -> dict[str, Any]:
    """Measure :func:`measure` for every obstacle count (at ``n = 2``), every dimension
    (at :data:`DIMENSION_SWEEP_OBSTACLES` obstacles) and the active-window experiment.

    Parameters
    ----------
    obstacles, dimensions : list of int
        Obstacle counts (each >= 0) of the obstacle sweep and dimensions (each >= 1) of the
        dimension sweep.
    compile_timeout : float
        Seconds allowed per compilation; a design that takes longer is reported with an
        ``error``.
    active_obstacles : int, optional
        Circumvents of the active-window experiment (default
        :data:`ACTIVE_EXPERIMENT_OBSTACLES`; 0 skips it).
    callgrind : bool
        Also count instructions per step under callgrind.
    sparse : (int, int), optional
        Circumvent counts of :func:`sparse_window_experiment` (default
        ``(SPARSE_SMALL, SPARSE_LARGE)``; ``(0, 0)`` skips it).

    Returns
    -------
    dict
        ``machine``, ``obstacle_sweep``, ``dimension_sweep``, ``active_windows`` (rows of
        :func:`measure` with a ``windows`` key), ``sparse_windows`` (or None) and
        ``conclusion`` (a sentence).

    Raises
    ------
    SpecError
        A negative obstacle count (field ``obstacles``) or a dimension below 1
        (``dimensions``).
    """
    for m in obstacles:
        if m < 0:
            raise SpecError("obstacles", f"must be non-negative, got {m}")
    for n in dimensions:
        if n < 1:
            raise SpecError("dimensions", f"must be at least 1, got {n}")
    active = ACTIVE_EXPERIMENT_OBSTACLES if active_obstacles is None else active_obstacles
    report: dict[str, Any] = {"machine": machine(), "obstacle_sweep": [],
                              "dimension_sweep": [], "active_windows": []}
    for m in obstacles:
        report["obstacle_sweep"].append(measure(synthetic_design(m, 2), compile_timeout, callgrind))
    for n in dimensions:
        report["dimension_sweep"].append(
            measure(synthetic_design(DIMENSION_SWEEP_OBSTACLES, n), compile_timeout, callgrind))
    if active:
        for mode in ("open", "random", "closed"):
            row = measure(synthetic_design(active, 2, windows=mode), compile_timeout, callgrind)
            row["windows"] = mode
            report["active_windows"].append(row)
    small, large = (SPARSE_SMALL, SPARSE_LARGE) if sparse is None else sparse
    report["sparse_windows"] = (sparse_window_experiment(compile_timeout, callgrind, small, large)
                                if small and large else None)
    report["conclusion"] = _conclusion(report["active_windows"])
    return report


def _conclusion(rows: list[dict[str, Any]]) -> str:
    by_mode = {r["windows"]: r for r in rows if "error" not in r}
    if "open" not in by_mode or "closed" not in by_mode:
        return "active-window experiment not run"
    key = ("instructions_per_step" if by_mode["open"].get("instructions_per_step")
           else "seconds_per_step")
    ratio = by_mode["closed"][key] / by_mode["open"][key]
    verdict = ("every circumvent is evaluated at every step whether its window is open "
               "or not: the cost grows with all obstacles" if ratio > 0.5 else
               "closed windows are cheaper: the cost depends on the active windows")
    return (f"with {by_mode['open']['obstacles']} circumvents, all windows closed costs "
            f"{ratio:.2f} x all windows open ({key.replace('_', ' ')}): {verdict}")


def _row_cells(r: dict[str, Any], first: str) -> list[str]:
    if "error" in r:
        return [first, "-", "-", "-", "-", "-", "-", "-", r["error"]]
    ir = r.get("instructions_per_step")
    ops = r["operations"]
    return [first, f"{r['generate_s']:.2f} s", f"{r['compile_s']:.2f} s",
            f"{r['source_bytes'] / 1024:.0f} KiB", f"{r['object_bytes'] / 1024:.0f} KiB",
            seconds_text(r["seconds_per_step"]), "-" if ir is None else f"{ir:.0f}",
            f"{ops['arithmetic']} / {ops['transcendental']}",
            str(r["outside_tube_inputs"])]


def format_scaling_report(report: dict[str, Any]) -> str:
    """The human-readable tables of :func:`run_scaling_bench`'s result.

    Parameters
    ----------
    report : dict
        The result of :func:`run_scaling_bench`.

    Returns
    -------
    str
        One table per sweep and the machine line.
    """
    header = ["{}", "generate", "compile -O2", "C source", "object", "time/step",
              "instr/step", "model arith / transc.", "outside"]
    out = []
    for key, label, col in (("obstacle_sweep", "obstacles (n = 2)", "obstacles"),
                            ("dimension_sweep",
                             f"state dimension ({DIMENSION_SWEEP_OBSTACLES} obstacles)",
                             "dimension")):
        if report[key]:
            out.append(label)
            out.append(table([col] + header[1:], [_row_cells(r, str(r[col]))
                                                  for r in report[key]]))
    if report["active_windows"]:
        m = report["active_windows"][0]["obstacles"]
        out.append(f"active windows ({m} circumvents, n = 2)")
        out.append(table(["windows"] + header[1:],
                         [_row_cells(r, r["windows"]) for r in report["active_windows"]]))
    out.append(report["conclusion"])
    sparse = report.get("sparse_windows")
    if sparse:
        rows = sparse["rows"]
        out.append(f"sparse windows (at most {MAX_SIMULTANEOUS} open at a time, n = 2)")
        out.append(table(["circumvents"] + header[1:],
                         [_row_cells(r, str(r["obstacles"])) for r in rows]))
        ratio = sparse["instruction_ratio"]
        texts = [r.get("text_bytes") for r in rows]
        out.append(f"{rows[1]['obstacles']} vs {rows[0]['obstacles']} circumvents: "
                   + (f"{ratio:.2f} x the instructions per step" if ratio else
                      "instructions not measured")
                   + f"; code (.text) {texts[1]} vs {texts[0]} bytes")
    out.append("generate: CasADi model + C text + test vectors; compile: the generated .c "
               "alone; object: text + data + bss (all four API functions, tables included); "
               "model arith / transc.: operations of the CasADi model's controller_step (every "
               "circumvent; the generated step evaluates the open ones only); "
               "outside: recorded closed-loop inputs (of 9000) outside the synthetic tube")
    out.append(machine_line(report["machine"]))
    return "\n".join(out)
