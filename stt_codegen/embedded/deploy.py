"""``stt-codegen embedded SPEC``: the single-precision controller on an emulated Cortex-M4F.

Pipeline (:func:`run_embedded`, for a design): generate the single-precision C
(``generate_files(..., Options(("c",), "single"))``), then build for the Cortex-M4F
(``-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard``, newlib, ``-O2``) and run under
``qemu-system-arm -machine mps2-an386`` with semihosting:

1. the generated self-test (``P_selftest.c``): ``vectors_passed`` / ``vectors_failed``
   from its last line;
2. the replay program at the self-test's vectors: outputs compared with the double numpy
   reference; ``max_rel_error_u`` is ``max_k |u_k - u_ref,k|_inf / |u_ref,k|_inf`` over the
   vectors (normwise), and ``error_to_bound`` the largest ``|error| / bound`` of
   :mod:`stt_codegen.codegen.tolerance` (single) for ``u``, ``alpha_next``, the tube;
3. the closed-loop program (:func:`~stt_codegen.embedded.programs.closed_loop_source`),
   compared with the host simulation ``simulate(design, backend="c")`` (double
   controller, same plant and disturbance): ``max_state_deviation``;
4. the replay program at the controller inputs the closed loop met at a few steps,
   each step a measured region: ``instructions_per_step`` (exact count of emulated
   instructions, QEMU ``-singlestep -d exec,nochain`` trace, from the return of
   ``stt_measure_begin`` to the call of ``stt_measure_end``: the call of ``P_step`` with
   its argument set-up, the typed API's checks, the body and every libm call), and where
   they go (``instructions_detail["by_function"]``: mean exclusive instructions and
   entries per function, from the same trace and the ELF's symbol table);
   the painted stack of these steps is ``stack_bytes_measured``.

Footprint of the controller object ``P.o`` alone (:func:`~stt_codegen.embedded.measure`,
before ``--gc-sections``: the whole API, ``P_tube``/``P_control``/``P_alpha_step`` included)
and of what the closed-loop ELF keeps of it (``flash_bytes_linked``, from the map file).
``stack_bytes`` is the static worst case of ``P_step`` over the linked ELF, libm included
(:func:`~stt_codegen.embedded.footprint.elf_stack_bound`).
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np

from ..tube import reference as R
from ..codegen import tolerance as T
from ..codegen.generate import generate_files
from ..codegen.options import Options
from ..design.result import Design, require_design
from ..spec.variants import require_variant
from ..errors import SpecError, ToolchainError
from ..runtime.plants import check_seed
from ..tube.parameters import TubeDesign
from .footprint import elf_stack_bound, linked_sizes, measure
from .budget import step_budget
from .programs import (closed_loop_source, judge_printed, parse_closed_loop, parse_replay,
                       replay_source, steps_of)
from .target import TARGET_WORDS, build_elf, run_checked
from .toolchain import missing_message

__all__ = ["COUNT_FRACTIONS", "ToolsMissing", "compare_outputs", "function_profile",
           "run_embedded", "selftest_on_target"]

#: Steps whose instructions are counted: evenly spread over [0, t_c) (fractions of t_c).
COUNT_FRACTIONS = (0.0, 0.2, 0.4, 0.6, 0.8, 0.999)


class ToolsMissing(ToolchainError):
    """The cross toolchain or QEMU is missing; the message names the Debian packages."""


def _selftest_counts(stdout: str) -> tuple[int, int]:
    m = re.search(r"^(\d+) passed, (\d+) failed$", stdout, re.MULTILINE)
    if m is None:
        raise ToolchainError(f"self-test printed no 'N passed, N failed' line:\n{stdout[-2000:]}")
    return int(m.group(1)), int(m.group(2))


def selftest_on_target(files: dict[str, bytes], prefix: str, out_dir: str | Path | None,
                       timeout: float) -> tuple[Path, Path, int, int]:
    """Write a generation into ``<build folder>/generated``, build its self-test for the
    Cortex-M4F and run it under QEMU; the tools are checked before anything is written.

    Parameters
    ----------
    files : dict of str to bytes
        The generated files (``generate_files``), C included.
    prefix : str
        The C prefix (``<prefix>.c``, ``<prefix>_selftest.c``).
    out_dir : str or Path or None
        The build folder; ``None``: a new temporary one.
    timeout : float
        Seconds for the QEMU run.

    Returns
    -------
    out, generated : Path
        The build folder and the folder of the generated files in it.
    passed, failed : int
        The self-test's last line.

    Raises
    ------
    ToolsMissing
        A tool is not installed (the message names the Debian packages).
    ToolchainError
        The build or the run failed, or the self-test printed no summary.
    """
    message = missing_message()
    if message:
        raise ToolsMissing(message)
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="stt-embedded-"))
    gen = out / "generated"
    gen.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (gen / name).write_bytes(data)
    st = build_elf([gen / f"{prefix}.c", gen / f"{prefix}_selftest.c"], [gen],
                   out / "selftest", name="selftest")
    passed, failed = _selftest_counts(run_checked(st.elf, timeout).stdout)
    return out, gen, passed, failed


def compare_outputs(design: TubeDesign, x, t, dt, alpha, out) -> dict:
    """Errors of float outputs ``out`` (a ReplayOutput) against the double reference.

    Returns ``max_rel_error_u`` (normwise per vector, see the module docstring),
    ``max_abs_error_u`` and ``error_to_bound`` (largest ratio of the error to the
    single-precision bound, per output), ``status_mismatches``.

    Parameters
    ----------
    design : TubeDesign
        The design whose double-precision reference (:mod:`stt_codegen.tube.reference`) is
        the yardstick.
    x : array_like, shape (N, n)
        The states given to the program, state units.
    t : array_like, shape (N,)
        Times, s.
    dt : array_like, shape (N,)
        Sampling periods, s.
    alpha : array_like, shape (N, 2n)
        The adaptive law's ``alpha``.
    out : ReplayOutput
        What the single-precision program computed at those inputs
        (:func:`stt_codegen.embedded.programs.parse_replay`).

    Returns
    -------
    dict
        ``max_rel_error_u`` (float), ``max_abs_error_u`` (float, input units),
        ``error_to_bound`` (dict ``u``, ``alpha_next``, ``gamma`` -> float; at most 1 where
        the single-precision bounds hold) and ``status_mismatches`` (int).
    """
    x, alpha = np.atleast_2d(x), np.atleast_2d(alpha)
    u, a_next, status = R.controller_status(design, x, t, dt, alpha)
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    unit = T.UNIT_SINGLE
    tol_u = T.u_bound(design, x, alpha, g_l, g_u, u, unit)
    tol_a = T.alpha_bound(design, alpha, a_next, unit)
    tol_g = np.broadcast_to(T.gamma_bound(design, alpha, unit), g_l.shape)
    du = np.abs(out.u - u)
    norm = np.maximum(np.max(np.abs(u), axis=1), np.finfo(float).tiny)
    return {
        "max_rel_error_u": float(np.max(np.max(du, axis=1) / norm)),
        "max_abs_error_u": float(du.max()),
        "error_to_bound": {
            "u": float(np.max(du / tol_u)),
            "alpha_next": float(np.max(np.abs(out.alpha_next - a_next) / tol_a)),
            "gamma": float(max(np.max(np.abs(out.gamma_L - g_l) / tol_g),
                               np.max(np.abs(out.gamma_U - g_u) / tol_g))),
        },
        "status_mismatches": int(np.sum(out.status != status)),
    }


def run_embedded(design: Design, out_dir: Path | None = None, *,
                 seed: int = 0, count_fractions=COUNT_FRACTIONS, compare_host: bool = True,
                 timeout: float = 600.0) -> dict:
    """Build, run and measure the single-precision controller of a design on QEMU.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube` (its spec gives the name, the plant and the
        closed loop's task).
    out_dir : Path, optional
        Build folder (generated C, programs, objects, ELFs); a temporary one by default.
    seed : int
        Disturbance seed of the closed loop (and of the host simulation compared with it),
        in ``[0, 2**32)``.
    count_fractions : sequence of float
        Times (fractions of ``t_c``) of the steps whose instructions are counted.
    compare_host : bool
        Also run ``simulate(design, backend="c", seed=seed)`` and report the deviation.
    timeout : float
        Seconds per QEMU run.

    Returns
    -------
    dict
        The report (JSON-ready); ``ok`` is true when every vector passed and the closed
        loop is satisfied.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.
    SpecError
        ``seed`` is not an integer in ``[0, 2**32)`` (field ``seed``); a MuJoCo plant
        (field ``plant.model``: its closed loop runs on the host only).
    ToolsMissing
        A tool is not installed (the message names the Debian packages).
    ToolchainError
        A build or run failed.
    """
    design = require_design(design, "run_embedded")
    spec, tube = design.spec, design.tube
    if spec.mujoco is not None:
        raise SpecError("plant.model", "the firmware's closed loop needs the plant's equations; "
                                       "a MuJoCo plant runs on the host (stt-codegen simulate)")
    # another variant has its own program (role firmware): stt-codegen embedded picks it
    require_variant(spec, "first-order", "law (13)'s firmware loop (run_embedded; "
                                         "stt-codegen embedded runs each variant's own)")
    seed = check_seed(seed)
    prefix = spec.c_name
    # 1. the generated self-test
    out, gen, passed, failed = selftest_on_target(
        generate_files(spec, tube, Options(("c",), "single")), prefix, out_dir, timeout)
    lib = gen / f"{prefix}.c"
    n = spec.dimension

    def run(elf, **kw):
        return run_checked(elf, timeout, **kw)

    # 2. the vectors again, outputs compared with the reference
    vec = _vectors(gen / f"{prefix}_vectors.json")
    rp_dir = out / "replay"
    rp_dir.mkdir(exist_ok=True)
    (rp_dir / "vectors.c").write_text(replay_source(spec, tube, *vec, what="test vectors"))
    rp = build_elf([lib, rp_dir / "vectors.c"], [gen], rp_dir / "build", name="vectors")
    rp_out = parse_replay(run(rp.elf).stdout, n)
    errors = compare_outputs(tube, *vec, rp_out)

    # 3. the closed loop
    steps = steps_of(spec, tube)
    replay_steps = sorted({min(steps - 1, int(round(f * steps))) for f in count_fractions})
    cl_dir = out / "closed_loop"
    cl_dir.mkdir(exist_ok=True)
    (cl_dir / f"{prefix}_closed_loop.c").write_text(
        closed_loop_source(spec, tube, seed=seed, replay=replay_steps))
    cl = build_elf([lib, cl_dir / f"{prefix}_closed_loop.c"], [gen], cl_dir / "build",
                   name="closed_loop")
    cl_run = run(cl.elf)
    loop = parse_closed_loop(cl_run.stdout, n)
    s = loop.summary
    closed = {
        "closed_loop_satisfied": bool(s["satisfied"]) and cl_run.exit_code == 0,
        "reached": bool(s["reached"]),
        "reach_time": s["reach_time"] if s["reached"] else None,
        "min_clearance": s["min_clearance"] if spec.unsafe_sets else None,
        "collision": bool(s["collision"]),
        "left_state_space": bool(s["left_state_space"]),
        "outside_tube_steps": s["outside_tube_steps"],
        "steps": s["steps"],
        "max_abs_u": s["max_abs_u"],
    }
    # tasks and moving obstacles: judged on the target's printed states (docs/tasks.md)
    judged = judge_printed(spec, loop.states, tube.rate_hz)
    closed["closed_loop_satisfied"] &= judged.pop("met")
    closed.update(judged)

    # 4. instructions and stack of single steps at closed-loop inputs
    ks = sorted(loop.replay_inputs)
    t_r = np.array([loop.replay_inputs[k][0] for k in ks])
    a_r = np.array([loop.replay_inputs[k][1] for k in ks])
    x_r = np.array([loop.replay_inputs[k][2] for k in ks])
    dt_r = np.full(len(ks), np.float32(1.0 / tube.rate_hz))
    (cl_dir / "steps.c").write_text(replay_source(spec, tube, x_r, t_r, dt_r, a_r,
                                                  what="closed-loop inputs"))
    cnt = build_elf([lib, cl_dir / "steps.c"], [gen], cl_dir / "count", name="steps",
                    defines={"STT_MEASURE": None})
    cnt_run = run(cnt.elf, count_instructions=True)
    counts = list(cnt_run.instructions or [])
    by_function = function_profile(cnt_run.functions or [])
    cnt_out = parse_replay(cnt_run.stdout, n)

    fp = measure(cl.objects[:1], cl.su_files[:1], entry=f"{prefix}_step")
    elf_stack = elf_stack_bound(cl.elf, f"{prefix}_step")
    linked = linked_sizes(cl.map_file, cl.objects[0])
    report = {
        "spec": spec.name,
        "target": TARGET_WORDS,
        "precision": "single",
        "flash_bytes": fp.text + fp.rodata,
        "flash_detail": {"text": fp.text, "rodata": fp.rodata, "data": fp.data,
                         "note": "the controller object P.o before --gc-sections (all four "
                                 "API functions); .data is 0 (no mutable state) and not added"},
        "flash_bytes_linked": linked["text"] + linked["rodata"],
        "ram_bytes": fp.ram_bytes,
        "stack_bytes": elf_stack["bytes"],
        "stack_chain": list(elf_stack["chain"]),
        "stack_detail": {
            "su_bytes": fp.stack_bytes, "su_chain": list(fp.stack_chain),
            "su_excluded": list(fp.unresolved),
            "note": "stack_bytes: static bound of P_step over the linked ELF, libm included "
                    "(frames from each function's prologue, calls from bl/b.w); su_bytes: "
                    "-fstack-usage of P.o only (libm counted as 0)"},
        "stack_bytes_measured": int(cnt_out.stack.max()) if cnt_out.stack is not None else None,
        "vectors_passed": passed,
        "vectors_failed": failed,
        **errors,
        **closed,
        "instructions_per_step": int(round(float(np.mean(counts)))) if counts else None,
        **step_budget(counts, design.tube.rate_hz),
        "instructions_detail": {
            "steps": ks, "t": [float(v) for v in t_r], "counts": counts,
            "how": "exact count of emulated Thumb-2 instructions of one P_step call (argument "
                   "set-up, API checks, body, libm) at the closed loop's inputs, QEMU "
                   "-singlestep -d exec,nochain trace; not cycles",
            "by_function": by_function},
    }
    if compare_host:
        from ..runtime.simulate import simulate
        host = simulate(design, backend="c", seed=seed)
        tr = host.trajectory
        dev = max(float(np.max(np.abs(x - tr.x[k]))) for k, x in loop.states.items())
        report["host_satisfied"] = host.satisfied
        report["host_reach_time"] = host.reach_time
        report["max_state_deviation"] = dev
    report["ok"] = failed == 0 and report["closed_loop_satisfied"]
    report["build_dir"] = str(out)
    return report


def function_profile(regions: list[dict[str, list[int]]]) -> dict[str, dict[str, float]]:
    """Mean over the counted steps of each function's exclusive instructions and entries.

    Parameters
    ----------
    regions : list of dict
        :attr:`~stt_codegen.embedded.target.RunResult.functions` of the counting run.

    Returns
    -------
    dict
        ``{function: {"instructions": mean, "entries": mean}}`` (rounded to 0.1), most
        instructions first (ties by name); the instructions add up to the mean count per
        step. ``entries`` counts executions of the function's first instruction (its
        calls). Inlined bodies count in the function they were inlined into.
    """
    if not regions:
        return {}
    names = sorted({name for region in regions for name in region})
    mean = {name: [sum(r.get(name, [0, 0])[k] for r in regions) / len(regions)
                   for k in (0, 1)] for name in names}
    order = sorted(names, key=lambda name: (-mean[name][0], name))
    return {name: {"instructions": round(mean[name][0], 1), "entries": round(mean[name][1], 1)}
            for name in order}


def _vectors(path: Path):
    import json
    data = json.loads(path.read_text())
    return (np.array(data["x"]), np.array(data["t"]), np.array(data["dt"]),
            np.array(data["alpha"]))
