"""The look-ahead controller of a differential-drive base on an emulated Cortex-M4F.

:func:`run_look_ahead_embedded` builds, for a design whose spec has ``plant.model =
"differential-drive"``:

* the single-precision look-ahead C
  (:func:`stt_codegen.codegen.look_ahead_source.look_ahead_c_files`);
* the closed-loop program :func:`closed_loop_program`, rendered from
  ``templates/look_ahead_closed_loop.c.j2``: the base's kinematics
  (:func:`stt_codegen.runtime.differential_drive.base_rhs` printed by the emitter's C
  printer, in double) with its wheel errors and the host's slip (same seed, same
  sinusoids), RK4 with :data:`stt_codegen.runtime.simulate.SUBSTEPS` substeps per period,
  and, shared with the other variants' programs, the judgement on the spec's obstacles,
  state space and target, here of the look-ahead point;

and runs it under ``qemu-system-arm -machine mps2-an386``, then counts the step's
instructions at the closed loop's inputs (:func:`~.variant_loop.run_variant_loop`).
"""

from __future__ import annotations

from ..codegen.emit import c_source
from ..codegen.look_ahead_source import look_ahead_c_files
from ..codegen.render import render
from ..design.result import Design
from ..errors import SpecError
from ..spec.variants import require_variant
from ..runtime.differential_drive import base_rhs
from ..runtime.plants import Disturbance
from ..runtime.state_split import initial_state
from .programs import c_double, loop_context
from .variant_loop import run_report, run_variant_loop

__all__ = ["closed_loop_program", "run_look_ahead_embedded"]


def closed_loop_program(design: Design, prefix: str, seed: int = 0,
                        decimate: int = 10, replay: list[int] = ()) -> str:
    """The C text of the closed-loop program (``templates/look_ahead_closed_loop.c.j2``),
    with the arguments of :func:`stt_codegen.embedded.cascade_loop.closed_loop_program` for
    a differential-drive design.

    Parameters
    ----------
    design : Design
        Of a differential-drive spec.
    prefix : str
        The look-ahead C's prefix.
    seed, decimate, replay
        As :func:`stt_codegen.embedded.cascade_loop.closed_loop_program` (``seed``: the
        slip's).

    Returns
    -------
    str
        The C source; it prints ``X`` lines (the base's state), ``S`` lines and a ``closed
        loop:`` summary.

    Raises
    ------
    SpecError
        Not a differential-drive spec, or a base on MuJoCo (field ``plant.model``).
    """
    spec = design.spec
    require_variant(spec, "look-ahead", "the look-ahead law's closed loop")
    drive = spec.drive
    if spec.mujoco is not None:
        raise SpecError("plant.model", "the firmware's closed loop needs the plant's equations; "
                                       "a MuJoCo plant runs on the host (stt-codegen simulate)")
    slip = Disturbance(3, 1.0, seed)
    context = dict(loop_context(spec, design.tube, seed=seed, decimate=decimate,
                                replay=replay),
                   P=prefix, U=prefix.upper(),
                   x0=[c_double(v) for v in initial_state(spec)],
                   axle_offset=c_double(drive.axle_offset),
                   wheel_error=[c_double(v) for v in drive.wheel_radius_error],
                   track_width=c_double(drive.track_width),
                   slip_amp=[c_double(v) for v in drive.slip],
                   w_c=[[c_double(v) for v in r] for r in slip.weights],
                   w_omega=[[c_double(v) for v in r] for r in slip.frequencies],
                   w_phi=[[c_double(v) for v in r] for r in slip.phases],
                   plant_rhs=c_source(base_rhs()).strip())
    return render("look_ahead_closed_loop.c.j2", **context)


def run_look_ahead_embedded(design: Design, seed: int = 0, timeout: float = 600.0) -> dict:
    """Build and run the look-ahead controller's closed loop on the emulated Cortex-M4F.

    Parameters
    ----------
    design : Design
        Of a differential-drive spec.
    seed : int
        Slip seed.
    timeout : float
        Seconds per QEMU run.

    Returns
    -------
    dict
        ``satisfied`` (reached, no collision, stayed in the state space, every task met
        and every moving obstacle missed at the printed steps), ``reach_time`` (s or
        None), ``min_clearance`` (m, of the look-ahead point from the inflated
        obstacles), ``max_abs_u`` (``v``, ``omega``), ``final_state`` (``x, y, theta``),
        the numbers of steps ``outside_position``, ``invalid``, ``input_clamped``,
        ``instructions_per_step`` (list over the measured steps), ``measured_times`` (s),
        ``instructions_by_function``, ``flash_bytes_controller``.

    Raises
    ------
    SpecError
        As :func:`closed_loop_program`.
    MissingTool
        The Arm toolchain or QEMU is missing (names the Debian packages).
    ToolchainError
        A build or a run failed.
    """
    prefix = design.spec.c_name
    files = look_ahead_c_files(design.tube, design.look_ahead, prefix, "single")
    output, measured = run_variant_loop(
        design, files, prefix, lambda replay: closed_loop_program(design, prefix, seed,
                                                                  replay=replay),
        3, timeout)
    return {**run_report(design, output),
            "final_state": output.states[max(output.states)].tolist(), **measured}
