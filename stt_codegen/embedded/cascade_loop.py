"""The cascade controller for a second-order plant on an emulated Cortex-M4F.

:func:`run_cascade_embedded` builds, for a design whose spec has a second-order
``plant.model``:

* the single-precision cascade C (:func:`stt_codegen.codegen.cascade_source.cascade_c_files`);
* the closed-loop program :func:`closed_loop_program`, rendered from
  ``templates/cascade_closed_loop.c.j2``: the plant
  (:func:`stt_codegen.runtime.second_order_plants.second_order_rhs` printed by the emitter's
  C printer, in double), and, shared with the first order's program
  (:func:`stt_codegen.embedded.programs.loop_context`), the disturbance of
  :class:`stt_codegen.runtime.plants.Disturbance` (same seed, same sinusoids), RK4 with
  :data:`stt_codegen.runtime.simulate.SUBSTEPS` substeps per period and the judgement on the
  spec's obstacles, state space and target; the velocity bound is judged too;

and runs it under ``qemu-system-arm -machine mps2-an386``: the whole run (``satisfied``,
reach time, clearance, peak ``|u|``, final state), which prints the controller's inputs
at the steps at :data:`~stt_codegen.embedded.deploy.COUNT_FRACTIONS` of ``t_c``; then
the first order's replay program (:func:`stt_codegen.embedded.programs.replay_source`)
calls ``P_step`` at these inputs, each call a measured region
(``instructions_per_step``: exact count of emulated instructions, the call of ``P_step``
with every libm call), as ``stt-codegen embedded`` measures the first-order step.
"""

from __future__ import annotations

import math

from ..codegen.cascade_source import cascade_c_files
from ..codegen.emit import c_source
from ..codegen.render import render
from ..design.result import Design
from ..errors import SpecError
from ..spec.variants import require_variant
from ..runtime.second_order_plants import second_order_rhs
from .programs import c_double, loop_context
from .variant_loop import run_report, run_variant_loop

__all__ = ["closed_loop_program", "run_cascade_embedded"]


def closed_loop_program(design: Design, prefix: str, seed: int = 0,
                        decimate: int = 10, replay: list[int] = ()) -> str:
    """The C text of the closed-loop program (``templates/cascade_closed_loop.c.j2``).

    Parameters
    ----------
    design : Design
        Of a spec with a second-order ``plant.model``.
    prefix : str
        The cascade C's prefix (``<prefix>.h``, ``<prefix>_step``).
    seed : int
        Disturbance seed (as ``simulate(..., seed=seed)``).
    decimate : int
        Print the state every ``decimate`` steps (and at the last one).
    replay : list of int
        Steps whose controller inputs are printed (``S`` lines), increasing.

    Returns
    -------
    str
        The C source; it prints ``X`` lines (the state ``[x1; x2]``), ``S`` lines and a
        ``closed loop:`` summary (:func:`stt_codegen.embedded.programs.parse_closed_loop`).

    Raises
    ------
    SpecError
        A first-order spec, or a MuJoCo plant (field ``plant.model``).
    """
    spec = design.spec
    order = spec.second_order
    require_variant(spec, "cascade", "the cascade's closed loop")
    if spec.mujoco is not None:
        raise SpecError("plant.model", "the firmware's closed loop needs the plant's equations; "
                                       "a MuJoCo plant runs on the host (stt-codegen simulate)")
    n = spec.dimension
    bound = order.velocity_bound or (math.inf,) * n
    context = dict(loop_context(spec, design.tube, seed=seed, decimate=decimate,
                                replay=replay),
                   P=prefix, U=prefix.upper(), plant=order.model,
                   x0=[c_double(v) for v in (*spec.initial_state, *order.initial_velocity)],
                   parameters=[c_double(v) for v in order.parameters],
                   velocity_bound=[c_double(v) for v in bound],
                   plant_rhs=c_source(second_order_rhs(order.model, n)).strip())
    return render("cascade_closed_loop.c.j2", **context)


def run_cascade_embedded(design: Design, seed: int = 0, timeout: float = 600.0) -> dict:
    """Build and run the cascade's closed loop on the emulated Cortex-M4F.

    Parameters
    ----------
    design : Design
        Of a spec with a second-order ``plant.model``.
    seed : int
        Disturbance seed.
    timeout : float
        Seconds per QEMU run.

    Returns
    -------
    dict
        ``satisfied`` (bool: reached, no collision, stayed in the state space, below the
        velocity bound, every task met and every moving obstacle missed at the printed
        steps), ``tasks`` and ``moving_clearance`` (with tasks, resp. moving obstacles:
        :func:`~stt_codegen.embedded.programs.judge_printed`), ``reach_time`` (s or None), ``min_clearance`` (state units),
        ``max_abs_u`` (per input), ``final_state`` (positions), ``final_velocity``, the
        numbers of steps with each status other than OK (``outside_position``,
        ``outside_velocity``, ``invalid``, ``input_clamped``),
        ``exceeded_velocity_bound``, ``instructions_per_step`` (list over the measured
        steps), ``measured_times`` (their ``t``, s), ``instructions_by_function`` (as
        ``stt-codegen embedded``'s ``instructions_detail.by_function``), ``flash_bytes_controller`` (text + data of the controller object).

    Raises
    ------
    SpecError
        As :func:`closed_loop_program`.
    MissingTool
        The Arm toolchain or QEMU is missing (names the Debian packages).
    ToolchainError
        A build or a run failed.
    """
    stage, _ = design.second_stage
    prefix = design.spec.c_name
    n = design.spec.dimension
    files = cascade_c_files(design.tube, stage, prefix, "single")
    output, measured = run_variant_loop(
        design, files, prefix, lambda replay: closed_loop_program(design, prefix, seed,
                                                                  replay=replay),
        2 * n, timeout)
    summary = output.summary
    final = output.states[max(output.states)]
    return {**run_report(design, output),
            "final_state": final[:n].tolist(), "final_velocity": final[n:].tolist(),
            "outside_velocity": summary["outside_velocity_tube_steps"],
            "exceeded_velocity_bound": bool(summary["exceeded_velocity_bound"]),
            **measured}
