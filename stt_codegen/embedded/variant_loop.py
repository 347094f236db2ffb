"""Building and running a controller variant's closed loop on the emulated Cortex-M4F.

What the cascade's (:mod:`.cascade_loop`) and the look-ahead variant's
(:mod:`.look_ahead_loop`) firmware runs share: the generated single-precision C and the
closed-loop program are built into one ELF and run under QEMU (the whole run, which prints
the controller's inputs at :data:`~stt_codegen.embedded.deploy.COUNT_FRACTIONS` of
``t_c``); then the first order's replay program
(:func:`~stt_codegen.embedded.programs.replay_source`) calls ``P_step`` at these inputs,
each call a measured region (exact counts of emulated instructions).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

from ..design.result import Design
from ..errors import ToolchainError
from .deploy import COUNT_FRACTIONS, function_profile
from .budget import step_budget
from .programs import (ClosedLoopOutput, judge_printed, parse_closed_loop, replay_source,
                       steps_of)
from .target import build_elf, elf_sizes, run_qemu

__all__ = ["run_report", "run_variant_loop"]


def run_variant_loop(design: Design, files: dict[str, str], prefix: str,
                     program: Callable[[list[int]], str], state_size: int,
                     timeout: float = 600.0) -> tuple[ClosedLoopOutput, dict]:
    """Build and run a variant's closed loop and count its step's instructions.

    Parameters
    ----------
    design : Design
        The design (its spec, tube and rate).
    files : dict of str to str
        The single-precision controller's ``<prefix>.h`` and ``<prefix>.c``.
    prefix : str
        The controller's C prefix.
    program : callable
        ``replay -> C text`` of the closed-loop program, which prints the inputs of the
        steps ``replay``.
    state_size : int
        Entries of the plant's state in the program's ``X`` and ``S`` lines.
    timeout : float
        Seconds per QEMU run.

    Returns
    -------
    output : ClosedLoopOutput
        The run's summary, printed states and replay inputs.
    measured : dict
        ``instructions_per_step`` (list), ``measured_times`` (s),
        ``instructions_by_function`` and ``flash_bytes_controller``.

    Raises
    ------
    MissingTool
        The Arm toolchain or QEMU is missing (names the Debian packages).
    ToolchainError
        A build or a run failed.
    """
    n = design.spec.dimension
    with tempfile.TemporaryDirectory(prefix="stt-variant-m4-") as name:
        folder = Path(name)
        for file, text in files.items():
            (folder / file).write_text(text)
        steps = steps_of(design.spec, design.tube)
        replay = sorted({min(steps - 1, int(round(f * steps))) for f in COUNT_FRACTIONS})
        loop = folder / "closed_loop.c"
        loop.write_text(program(replay))
        full = build_elf([folder / f"{prefix}.c", loop], [folder], folder / "full", name="loop")
        run = run_qemu(full.elf, timeout=timeout)
        try:
            output = parse_closed_loop(run.stdout, n, state_size)
        except ValueError:
            raise ToolchainError(f"the closed loop exited with {run.exit_code} without a "
                                 f"summary:\n{run.stdout[-2000:]}{run.stderr[-2000:]}") from None
        inputs = [output.replay_inputs[k] for k in sorted(output.replay_inputs)]
        steps_c = folder / "steps.c"
        steps_c.write_text(replay_source(
            design.spec, design.tube, [v[2] for v in inputs], [v[0] for v in inputs],
            [1.0 / design.tube.rate_hz] * len(inputs), [v[1] for v in inputs],
            what="closed-loop inputs", prefix=prefix))
        measured = build_elf([folder / f"{prefix}.c", steps_c], [folder], folder / "measured",
                             {"STT_MEASURE": None}, name="measured")
        counted = run_qemu(measured.elf, timeout=timeout, count_instructions=True)
        sizes = elf_sizes(full.objects[0])
    return output, {"instructions_per_step": list(counted.instructions or []),
                    **step_budget(list(counted.instructions or []), design.tube.rate_hz),
                    "measured_times": [float(v[0]) for v in inputs],
                    "instructions_by_function": function_profile(counted.functions or []),
                    "flash_bytes_controller": sizes}


def run_report(design: Design, output: ClosedLoopOutput) -> dict:
    """What every variant's firmware run reports of its closed loop.

    Parameters
    ----------
    design : Design
    output : ClosedLoopOutput
        The run's (:func:`run_variant_loop`).

    Returns
    -------
    dict
        ``satisfied`` (the program's verdict, and every task met and every moving obstacle
        missed at the printed steps: :func:`~stt_codegen.embedded.programs.judge_printed`,
        whose ``tasks`` and ``moving_clearance`` are included), ``reach_time`` (s or
        None), ``min_clearance``, ``max_abs_u``, and the numbers of steps
        ``outside_position``, ``invalid`` and ``input_clamped``.
    """
    summary = output.summary
    judged = judge_printed(design.spec, output.states, design.tube.rate_hz)
    return {"satisfied": bool(summary["satisfied"]) and judged.pop("met"), **judged,
            "reach_time": summary["reach_time"] if summary["reached"] else None,
            "min_clearance": summary["min_clearance"], "max_abs_u": summary["max_abs_u"],
            "outside_position": summary["outside_tube_steps"],
            "invalid": summary["invalid_steps"],
            "input_clamped": summary["input_clamped_steps"]}
