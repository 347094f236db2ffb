"""``stt-codegen bench step SPEC``: the cost of one controller step, five ways, one run.

On the same machine, in one run, on the same inputs (the closed-loop trajectory recorded
by the C harness, see :mod:`.harness`):

* ``C, compiled loop``: ``<prefix>_step`` called from the compiled harness (no Python);
* ``C via ctypes``: the same library called from Python (backend ``c``);
* ``generated Python``: the generated module's ``step`` on lists of floats;
* ``CasADi Function``: the model's ``controller_step`` evaluated by CasADi from Python;
* ``numpy reference``: :func:`stt_codegen.tube.reference.controller_step` on one state.

Times are medians over rounds that run every implementation in turn; ratios to the
compiled C loop are the headline. Also reported: the operation counts of the step
(:func:`stt_codegen.codegen.emit.count_operations`) and the instructions of one C step under
``valgrind --tool=callgrind`` (deterministic). As a check that the same thing is timed,
the largest ``|u - u_C|`` of each implementation on 64 of the inputs is reported.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .harness import BenchError, build_harness
from .report import machine, machine_line, seconds_text, table
from .timing import python_batch, round_robin

__all__ = ["format_step_report", "run_step_bench"]

#: Compiled-loop steps per timed run, and rounds of the round-robin.
DEFAULT_STEPS = 100_000
ROUNDS = 7
CHECK_POINTS = 64


def run_step_bench(spec_arg: str, steps: int | None = None, rounds: int = ROUNDS,
                   callgrind: bool = True) -> dict[str, Any]:
    """Measure one controller step of ``spec_arg``'s design five ways.

    Parameters
    ----------
    spec_arg : str
        Bundled case name or spec file.
    steps : int, optional
        Compiled-loop calls per timed run (default :data:`DEFAULT_STEPS`), >= 1.
    rounds : int
        Round-robin rounds, >= 1.
    callgrind : bool
        Also count instructions with valgrind (skipped, with a reason, when not installed).

    Returns
    -------
    dict
        ``spec``, ``machine``, ``inputs`` (recorded instants), ``outside_tube_inputs``,
        ``operations`` (arithmetic, transcendental, logic, total), ``instructions_per_step``
        (or None and ``callgrind_skipped``), and ``implementations``: a list of
        ``{"name", "seconds_per_step", "ratio_to_c", "max_abs_u_difference"}``.

    Raises
    ------
    SpecError, DesignError
        Bad spec or no design.
    BenchError
        The harness could not be built or run.
    """
    from stt_codegen.runtime.backends import make_controller
    from stt_codegen.runtime.compiled import GeneratedPythonController
    from stt_codegen.design.search import design_tube
    from stt_codegen.codegen.emit import count_operations
    from stt_codegen.errors import SpecError
    from stt_codegen.tube.model import build_model
    from stt_codegen.tube.reference import controller_step
    from stt_codegen.spec.loader import load_spec

    steps = DEFAULT_STEPS if steps is None else steps
    if steps < 1:
        raise SpecError("steps", f"must be at least 1, got {steps}")
    spec = load_spec(spec_arg)
    design = design_tube(spec).tube
    harness = build_harness(design)
    try:
        t, x, alpha, outside = harness.record()
        dt = 1.0 / design.rate_hz
        stride = max(1, len(t) // 512)
        picks = range(0, len(t), stride)
        model = build_model(design)
        function = model["controller_step"]
        module = GeneratedPythonController(design).module
        c_ctypes = make_controller("c", design)
        impls = {
            "C via ctypes (from Python)": (c_ctypes.step,
                                           [(x[k], t[k], dt, alpha[k]) for k in picks]),
            "generated Python": (module.step, [(list(map(float, x[k])), float(t[k]), dt,
                                                list(map(float, alpha[k]))) for k in picks]),
            "CasADi Function (from Python)": (function,
                                              [(x[k], t[k], dt, alpha[k]) for k in picks]),
            "numpy reference": (lambda *a: controller_step(design, *a),
                                [(x[k][None, :], t[k], dt, alpha[k][None, :]) for k in picks]),
        }
        batches = {"C, compiled loop": lambda: harness.time_step(steps, 1)[0]}
        batches.update({name: python_batch(fn, inputs) for name, (fn, inputs) in impls.items()})
        medians = round_robin(batches, rounds)

        check = np.linspace(0, len(t) - 1, CHECK_POINTS).astype(int)
        u_c = np.array([c_ctypes.step(x[k], t[k], dt, alpha[k])[0] for k in check])
        outputs = {
            "C, compiled loop": u_c,
            "C via ctypes (from Python)": u_c,
            "generated Python": np.array([module.step(list(map(float, x[k])), float(t[k]), dt,
                                                      list(map(float, alpha[k])))[0]
                                          for k in check]),
            "CasADi Function (from Python)": np.array(
                [np.array(function(x[k], t[k], dt, alpha[k])[0]).ravel() for k in check]),
            "numpy reference": np.array([controller_step(design, x[k][None, :], t[k], dt,
                                                         alpha[k][None, :])[0][0]
                                         for k in check]),
        }
        base = medians["C, compiled loop"]
        rows = [{"name": name, "seconds_per_step": sec, "ratio_to_c": sec / base,
                 "max_abs_u_difference": float(np.max(np.abs(outputs[name] - u_c)))}
                for name, sec in medians.items()]
        counts = count_operations(function)
        result: dict[str, Any] = {
            "spec": spec.name, "machine": machine(), "inputs": int(len(t)),
            "outside_tube_inputs": int(outside), "compiled_loop_steps": steps,
            "rounds": rounds,
            "operations": {"arithmetic": counts.arithmetic,
                           "transcendental": counts.transcendental,
                           "logic": counts.logic, "total": counts.total},
            "instructions_per_step": None, "implementations": rows}
        if callgrind:
            try:
                result["instructions_per_step"] = harness.instructions_per_step()
            except BenchError as exc:
                result["callgrind_skipped"] = str(exc)
        return result
    finally:
        harness.cleanup()


def format_step_report(report: dict[str, Any]) -> str:
    """The human-readable tables of :func:`run_step_bench`'s result.

    Parameters
    ----------
    report : dict
        The result of :func:`run_step_bench`.

    Returns
    -------
    str
        The time-per-step table, the operation counts and the machine line.
    """
    rows = [[r["name"], seconds_text(r["seconds_per_step"]), f"{r['ratio_to_c']:.3g}x",
             f"{r['max_abs_u_difference']:.1e}"] for r in report["implementations"]]
    ops = report["operations"]
    ir = report["instructions_per_step"]
    lines = [f"controller step of {report['spec']} ({report['inputs']} recorded closed-loop "
             f"inputs, {report['outside_tube_inputs']} outside the tube; median of "
             f"{report['rounds']} rounds)",
             table(["implementation", "time per step", "vs C loop", "max |u - u_C|"], rows),
             f"operations per step: {ops['arithmetic']} arithmetic, {ops['transcendental']} "
             f"transcendental, {ops['logic']} logic ({ops['total']} instructions of the "
             "CasADi algorithm, data moves included)",
             ("instructions per C step (callgrind): "
              + (f"{ir:.0f}" if ir is not None else f"skipped: {report.get('callgrind_skipped')}")),
             machine_line(report["machine"])]
    return "\n".join(lines)
