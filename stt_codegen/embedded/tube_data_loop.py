"""``stt-codegen embedded SPEC --tube-data``: the tube as data on the Cortex-M4F.

The single-precision C with the tube as data (:mod:`stt_codegen.codegen.tube_data`) is
cross-built and run under QEMU (:mod:`~stt_codegen.embedded.target`): its self-test on the
spec's own tube (``P_design_tube``), then a program (``templates/embedded_tube_data.c.j2``)
whose every switch and step is a measured region, on the spec's tube and on a *cost tube*
(:func:`cost_tube`): the spec's tube cut into the capacity's reach segments, with
``open_windows`` circumvent windows open at once. The controller's step does not read the
tracked obstacles: they reach it only through the tubes the replanner makes
(docs/sensing.md); what a step costs is set by the active tube's segments and open
windows, and what a switch costs by the new tube's rows (``P_tube_check`` reads each).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..codegen.fileset import file_context
from ..codegen.api import design_files
from ..codegen.options import Options
from ..codegen.render import c_real, render
from ..codegen.tables import design_table_rows
from ..codegen.tube_data import TubeCapacity, require_tube_data
from ..design.result import Design
from ..errors import ToolchainError
from ..spec.variants import variant_of
from ..tube.parameters import (LOWER, SMOOTHSTEP, UPPER, Circumvent, ReachSegment, Status,
                               TubeDesign)
from ..runtime.data_controller import pack_tube
from .deploy import selftest_on_target
from .footprint import measure
from .target import TARGET_WORDS, build_elf, run_checked

__all__ = ["OPEN_WINDOWS", "cost_tube", "run_tube_data"]

#: Circumvent windows open at once in the cost tube: 16 obstacles circumvented together.
OPEN_WINDOWS = 16
#: Steps measured on each tube.
STEPS = 5
#: The statuses of a step whose state is strictly inside its tube (a spec with
#: ``[actuator]`` may clamp the command: the program holds the state still while the tube
#: moves on).
INSIDE = (int(Status.OK), int(Status.INPUT_CLAMPED), int(Status.OFF_PERIOD))


def literal(value: float) -> str:
    """A single-precision C literal of ``value``."""
    return c_real(value, True)


def cost_tube(tube: TubeDesign, capacity: TubeCapacity,
              open_windows: int = OPEN_WINDOWS) -> tuple[TubeDesign, float]:
    """The tube a step's cost is measured on, and the time (its own) where it is measured.

    The spec's reach tube cut into ``capacity.segments`` smoothstep segments of equal
    length along the straight line from its first box to its last; ``open_windows``
    circumvents (0.01 state units high) spread over the first two dimensions' bounds, every
    window open on ``[0.7, 0.9] t_c``. It is well formed, not certified: it measures cost.

    Parameters
    ----------
    tube : TubeDesign
        The spec's tube.
    capacity : TubeCapacity
        Its segments; ``open_windows`` must fit ``capacity.windows``.
    open_windows : int, optional
        The windows open at the measured time.

    Returns
    -------
    TubeDesign, float
        The cost tube and the measured time, s (0.8 ``t_c``, in its last segment).
    """
    t_c = tube.prescribed_time
    first, last = tube.segments[0], tube.segments[-1]
    lo = np.array(first.lower_from), np.array(last.lower_to)
    hi = np.array(first.upper_from), np.array(last.upper_to)
    cuts = np.linspace(0.0, t_c, capacity.segments + 1)
    segments = tuple(ReachSegment(
        float(cuts[k]), float(cuts[k + 1]),
        tuple(lo[0] + (lo[1] - lo[0]) * k / capacity.segments),
        tuple(hi[0] + (hi[1] - hi[0]) * k / capacity.segments),
        tuple(lo[0] + (lo[1] - lo[0]) * (k + 1) / capacity.segments),
        tuple(hi[0] + (hi[1] - hi[0]) * (k + 1) / capacity.segments), SMOOTHSTEP)
        for k in range(capacity.segments))
    dims = min(2, tube.dimension)
    circumvents = tuple(
        Circumvent(j, j % dims, LOWER if (j // dims) % 2 == 0 else UPPER, 0.7 * t_c,
                   0.9 * t_c, 0.01,
                   tube.state_lower[j % dims] if (j // dims) % 2 == 0
                   else tube.state_upper[j % dims], 1.0)
        for j in range(open_windows))
    return dataclasses.replace(tube, segments=segments, circumvents=circumvents), 0.8 * t_c


def run_tube_data(design: Design, capacity: TubeCapacity, out_dir: str | Path | None = None,
                  timeout: float = 120.0) -> dict:
    """The tube as data on the Cortex-M4F: self-test, switches and steps counted, flash.

    Parameters
    ----------
    design : Design
        A first-order design (the spec's C with the tube as data).
    capacity : TubeCapacity
        The data form's capacity (at least :data:`OPEN_WINDOWS` windows).
    out_dir : str or Path, optional
        Build folder, kept; default a temporary one.
    timeout : float, optional
        Seconds per QEMU run.

    Returns
    -------
    dict
        ``spec``, ``target``, ``capacity``, ``vectors_passed``, ``vectors_failed``,
        ``flash_bytes``, ``ram_bytes`` of ``P.o``, ``stack_bytes_run`` (static worst case of
        ``P_run`` within ``P.o``, without libm), ``switch_design`` and
        ``switch_cost`` (``{"result", "instructions"}``), ``steps_design`` and
        ``steps_cost`` (``{"statuses", "instructions"}``, lists), ``cost_tube``
        (``segments``, ``open_windows``), ``wire`` (the cost tube packed on the host,
        :func:`~stt_codegen.runtime.data_controller.pack_tube`, copied into a
        ``P_tube_data`` on the target: ``bytes``, ``check`` its ``P_tube_check``,
        ``same_steps`` whether its steps' ``u`` equal the compiled tube's bit for bit),
        ``ok``.

    Raises
    ------
    ToolchainError
        The Arm toolchain or QEMU is missing (``ToolsMissing``, the message names the
        Debian packages) or failed.
    SpecError
        The spec's variant has no tube as data, the capacity holds fewer windows than
        :data:`OPEN_WINDOWS`, or the spec's tube does not fit it (field ``tube_data``).
    """
    from ..errors import SpecError
    require_tube_data(design.spec, ("embedded",))
    if capacity.windows < OPEN_WINDOWS:
        raise SpecError("tube_data", f"the cost tube opens {OPEN_WINDOWS} windows: a capacity "
                                     f"of at least {OPEN_WINDOWS} windows is needed")
    spec, tube = design.spec, design.tube
    prefix = spec.c_name
    out, gen, passed, failed = selftest_on_target(
        design_files(design, Options(("c",), "single", capacity)), prefix, out_dir, timeout)
    start = variant_of(spec).entry("initial_state")

    def state(point) -> list[str]:
        # the plant's state whose tube point is ``point`` (a base: the axle behind it at
        # the spec's heading)
        return [literal(v) for v in start(dataclasses.replace(
            spec, initial_state=tuple(float(p) for p in point)))]

    lib = gen / f"{prefix}.c"
    wide, open_at = cost_tube(tube, capacity)
    wire_bytes = bytes(pack_tube(wide, capacity, "single"))
    program = render(
        "embedded_tube_data.c.j2", filename="tube_data.c", **file_context(spec, "single"),
        capacity=capacity, n=tube.dimension, zero=literal(0.0),
        n_state=f"{prefix.upper()}_N_STATE", n_input=f"{prefix.upper()}_N_INPUT",
        wide=design_table_rows(wide, literal, True), steps=list(range(STEPS)),
        x_design=state(tube.initial_state),
        x_switch=state(0.5 * (a + b) for a, b in zip(wide.segments[0].lower_from,
                                                     wide.segments[0].upper_from)),
        x_cost=state(_reach_centre(wide, open_at)),
        switch_at=literal(1.0), open_at=literal(open_at), period=literal(1.0 / tube.rate_hz),
        wire=[f"0x{b:02x}u" for b in wire_bytes])
    (out / "tube_data.c").write_text(program)
    prog = build_elf([lib, out / "tube_data.c"], [gen], out / "program", name="tube_data")
    res = run_checked(prog.elf, timeout, count_instructions=True)
    printed = [line.split() for line in res.stdout.strip().splitlines()]
    lines = [w for w in printed if not w[0].startswith("wire-")]
    wire = {w[0]: int(w[1]) for w in printed if w[0].startswith("wire-")}
    counts = list(res.instructions or [])
    if len(lines) != len(counts) or len(counts) != 2 * STEPS + 2:
        raise ToolchainError(f"tube_data: {len(lines)} lines and {len(counts)} counted regions "
                             f"(expected {2 * STEPS + 2}):\n{res.stdout}")
    results = [int(w[1]) for w in lines]
    fp = measure(prog.objects[:1], prog.su_files[:1], entry=f"{prefix}_run")
    report = {
        "spec": spec.name,
        "target": TARGET_WORDS,
        "capacity": capacity.to_json(),
        "vectors_passed": passed, "vectors_failed": failed,
        "flash_bytes": fp.flash_bytes, "ram_bytes": fp.ram_bytes,
        "stack_bytes_run": fp.stack_bytes,
        "switch_design": {"result": results[0], "instructions": counts[0]},
        "steps_design": {"statuses": results[1:1 + STEPS], "instructions": counts[1:1 + STEPS]},
        "switch_cost": {"result": results[1 + STEPS], "instructions": counts[1 + STEPS]},
        "steps_cost": {"statuses": results[2 + STEPS:], "instructions": counts[2 + STEPS:]},
        "cost_tube": {"segments": capacity.segments, "open_windows": OPEN_WINDOWS,
                      "measured_at": open_at},
        "wire": {"bytes": len(wire_bytes),
                 "check": wire.get("wire-check"), "same_steps": wire.get("wire-same") == 1},
    }
    report["ok"] = bool(failed == 0 and passed > 0 and results[0] == 0
                        and report["wire"]["check"] == 0 and report["wire"]["same_steps"]
                        and results[1 + STEPS] == 0
                        and all(s in INSIDE for s in results[1:1 + STEPS] + results[2 + STEPS:]))
    return report


def _reach_centre(tube: TubeDesign, t: float) -> list[float]:
    """The centre of the reach tube of eq. (4) at ``t`` (the numpy oracle)."""
    from ..tube import reference
    with reference.numpy_math():
        lower, upper = reference.reach_tube(tube, np.array([t]), False)[:2]
    return [float(v) for v in 0.5 * (np.ravel(lower) + np.ravel(upper))]
