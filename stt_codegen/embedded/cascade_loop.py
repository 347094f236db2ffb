"""The cascade controller for a second-order plant on an emulated Cortex-M4F.

:func:`run_cascade_embedded` builds, for a design whose spec has a second-order
``plant.model``:

* the single-precision cascade C (:func:`stt_codegen.codegen.cascade_source.cascade_c_files`);
* a closed-loop program: the plant (:func:`stt_codegen.runtime.second_order_plants.second_order_rhs`
  printed by the emitter's C printer, in double), the disturbance of
  :class:`stt_codegen.runtime.plants.Disturbance` (same seed, same sinusoids), RK4 with
  :data:`stt_codegen.runtime.simulate.SUBSTEPS` substeps per period, judged on box
  obstacles, the state space, the target and the velocity bound;

and runs it under ``qemu-system-arm -machine mps2-an386`` twice: the whole run
(``satisfied``, reach time, clearance, peak ``|u|``, final state), then its steps
``0..MEASURED_STEPS``, each a measured region (``instructions_per_step``: exact
count of emulated instructions, the call of ``P_step`` with every libm call). The printed
cascade evaluates every segment and circumvent at every step, so its cost hardly depends
on ``t``.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from ..codegen.cascade_source import cascade_c_files
from ..codegen.emit import c_source
from ..design.result import Design
from ..errors import SpecError, ToolchainError
from ..runtime.simulate import SUBSTEPS
from ..runtime.plants import Disturbance
from ..runtime.second_order_plants import second_order_rhs
from .target import build_elf, elf_sizes, run_qemu

__all__ = ["MEASURED_STEPS", "run_cascade_embedded"]

#: Steps ``0..MEASURED_STEPS`` are counted (the first ones: the cost hardly depends on t).
MEASURED_STEPS = 4


def _d(value: float) -> str:
    text = repr(float(value))
    if not math.isfinite(float(value)):
        raise ValueError(f"non-finite constant {value!r}")
    return text if ("." in text or "e" in text or "inf" in text) else text + ".0"


def _array(name: str, values, kind: str = "double") -> str:
    flat = [_d(v) for v in np.ravel(values)]
    return f"static const {kind} {name}[{max(1, len(flat))}] = {{{', '.join(flat) or '0.0'}}};"


def closed_loop_program(design: Design, prefix: str, seed: int = 0) -> str:
    """The C text of the closed-loop program (see the module docstring).

    Raises
    ------
    SpecError
        A first-order spec (field ``plant.model``), or an obstacle that is not a box
        (field ``obstacles``: the program judges boxes only).
    """
    spec = design.spec
    order = spec.second_order
    if order is None:
        raise SpecError("plant.model", "the spec describes a first-order plant")
    n = spec.dimension
    boxes = []
    for j, unsafe in enumerate(spec.unsafe_sets):
        if unsafe.kind != "box":
            raise SpecError(f"obstacles[{j}]", "the embedded cascade loop judges box "
                                               "obstacles only")
        boxes.append((list(unsafe.dims), unsafe.shape.lower, unsafe.shape.upper))
    dist = Disturbance(n, spec.disturbance_amplitude, seed)
    steps = int(math.ceil(spec.prescribed_time * design.tube.rate_hz - 1e-9))
    plant = c_source(second_order_rhs(order.model, n)).strip()
    bound = order.velocity_bound or (math.inf,) * n
    lines = [
        f"/* Closed loop of the cascade controller {prefix} on the {order.model} plant "
        "(stt_codegen.embedded.cascade_loop). */",
        "#include <math.h>", "#include <stdio.h>", "#include <string.h>",
        '#include "stt_target.h"', f'#include "{prefix}.h"', "",
        f"#define N {n}", f"#define TERMS {dist.weights.shape[1]}", f"#define OBSTACLES {len(boxes)}",
        "#ifndef STEPS", f"#define STEPS {steps}", "#endif", f"#define SUBSTEPS {SUBSTEPS}", "",
        plant, "",
        _array("PARAMS", order.parameters), _array("X0", spec.initial_state),
        _array("V0", order.initial_velocity),
        _array("SS_LO", spec.state_space.lower), _array("SS_HI", spec.state_space.upper),
        _array("TG_LO", spec.target_set.lower), _array("TG_HI", spec.target_set.upper),
        _array("V_MAX", [b if math.isfinite(b) else 1e300 for b in bound]),
        _array("W_C", dist.weights), _array("W_OMEGA", dist.frequencies),
        _array("W_PHI", dist.phases),
        _array("OB_LO", [[dict(zip(d, lo)).get(i, -1e300) for i in range(n)]
                         for d, lo, _ in boxes] or [0.0]),
        _array("OB_HI", [[dict(zip(d, hi)).get(i, 1e300) for i in range(n)]
                         for d, _, hi in boxes] or [0.0]),
        f"static const double RATE_HZ = {_d(design.tube.rate_hz)};",
        f"static const double T_C = {_d(spec.prescribed_time)};",
        f"static const double W_AMP = {_d(dist.amplitude)};",
        "",
        "static void rhs(double t, const double* s, const float* uf, double* ds) {",
        "  double w[N], u[N];",
        "  int i, k;",
        "  for (i = 0; i < N; ++i) {",
        "    double acc = 0.0;",
        "    for (k = 0; k < TERMS; ++k) {",
        "      acc += W_C[i * TERMS + k] * sin(W_OMEGA[i * TERMS + k] * t + W_PHI[i * TERMS + k]);",
        "    }",
        "    w[i] = W_AMP * acc;",
        "    u[i] = (double)uf[i];",
        "  }",
        "  second_order_rhs(s, s + N, u, w, PARAMS, ds, ds + N);",
        "}",
        "",
        "static double clearance(const double* x) {",
        "  double best = 1e300;",
        "  int j, i;",
        "  for (j = 0; j < OBSTACLES; ++j) {",
        "    double out = 0.0, depth = 1e300;",
        "    for (i = 0; i < N; ++i) {",
        "      double lo = OB_LO[j * N + i], hi = OB_HI[j * N + i];",
        "      double gap = (x[i] < lo) ? lo - x[i] : ((x[i] > hi) ? x[i] - hi : 0.0);",
        "      double in = (x[i] - lo < hi - x[i]) ? x[i] - lo : hi - x[i];",
        "      out += gap * gap;",
        "      if (in < depth) { depth = in; }",
        "    }",
        "    {",
        "      double d = (out > 0.0) ? sqrt(out) : -depth;",
        "      if (d < best) { best = d; }",
        "    }",
        "  }",
        "  return best;",
        "}",
        "",
        "int main(void) {",
        "  double s[2 * N], k1[2 * N], k2[2 * N], k3[2 * N], k4[2 * N], tmp[2 * N];",
        "  float xf[2 * N], alpha[2 * N], alpha_next[2 * N], u[N], r[N];",
        "  double max_u[N], min_clear = 1e300, h = 1.0 / (RATE_HZ * SUBSTEPS);",
        "  long reach = -1, outside_p = 0, outside_v = 0, invalid = 0;",
        "  int left = 0, fast = 0, i, m;",
        "  long k;",
        "  for (i = 0; i < N; ++i) { s[i] = X0[i]; s[N + i] = V0[i]; max_u[i] = 0.0; }",
        "  for (i = 0; i < 2 * N; ++i) { alpha[i] = 0.0f; }",
        "  for (k = 0; k <= STEPS; ++k) {",
        "    double t = (double)k / RATE_HZ;",
        "    int in_target = 1, code;",
        "    for (i = 0; i < N; ++i) {",
        "      xf[i] = (float)s[i]; xf[N + i] = (float)s[N + i];",
        "      if (s[i] < TG_LO[i] || s[i] > TG_HI[i]) { in_target = 0; }",
        "      if (fabs(s[N + i]) >= V_MAX[i] && t <= T_C + 1e-12) { fast = 1; }",
        "    }",
        "    if (in_target && reach < 0 && t <= T_C + 1e-12) { reach = k; }",
        "#ifdef MEASURE",
        "    stt_measure_begin();",
        "#endif",
        f"    code = {prefix}_step(xf, (float)t, (float)(1.0 / RATE_HZ), alpha, u, "
        "alpha_next, r);",
        "#ifdef MEASURE",
        "    stt_measure_end();",
        "#endif",
        "    if (code == 1) { ++outside_p; } else if (code == 4) { ++outside_v; }",
        "    else if (code == 2) { ++invalid; }",
        "    for (i = 0; i < N; ++i) { if (fabs((double)u[i]) > max_u[i]) { max_u[i] = fabs((double)u[i]); } }",
        "    if (k == STEPS) { break; }",
        "    for (m = 0; m < SUBSTEPS; ++m) {",
        "      double tm = t + m * h;",
        "      rhs(tm, s, u, k1);",
        "      for (i = 0; i < 2 * N; ++i) { tmp[i] = s[i] + h / 2 * k1[i]; }",
        "      rhs(tm + h / 2, tmp, u, k2);",
        "      for (i = 0; i < 2 * N; ++i) { tmp[i] = s[i] + h / 2 * k2[i]; }",
        "      rhs(tm + h / 2, tmp, u, k3);",
        "      for (i = 0; i < 2 * N; ++i) { tmp[i] = s[i] + h * k3[i]; }",
        "      rhs(tm + h, tmp, u, k4);",
        "      for (i = 0; i < 2 * N; ++i) { s[i] = s[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]); }",
        "      if (tm + h <= T_C + 1e-12) {",
        "        double c = clearance(s);",
        "        if (c < min_clear) { min_clear = c; }",
        "        for (i = 0; i < N; ++i) { if (s[i] < SS_LO[i] || s[i] > SS_HI[i]) { left = 1; } }",
        "      }",
        "    }",
        "    memcpy(alpha, alpha_next, sizeof(alpha));",
        "  }",
        "  printf(\"closed loop: satisfied=%d reach_step=%ld steps=%ld min_clearance=%.9g \"",
        "         \"outside_position=%ld outside_velocity=%ld invalid=%ld left=%d fast=%d max_abs_u=\",",
        "         (reach >= 0 && min_clear > 0.0 && !left && !fast) ? 1 : 0, reach, (long)STEPS,",
        "         min_clear, outside_p, outside_v, invalid, left, fast);",
        "  for (i = 0; i < N; ++i) { printf(i ? \",%.9g\" : \"%.9g\", max_u[i]); }",
        "  printf(\" final=\");",
        "  for (i = 0; i < N; ++i) { printf(i ? \",%.17g\" : \"%.17g\", s[i]); }",
        "  printf(\"\\n\");",
        "  return 0;",
        "}",
        "",
    ]
    return "\n".join(lines)


def _summary(stdout: str) -> dict:
    line = next((ln for ln in stdout.splitlines() if ln.startswith("closed loop: ")), None)
    if line is None:
        raise ToolchainError(f"no 'closed loop:' line in the program's output:\n{stdout[-2000:]}")
    out: dict = {}
    for item in line[len("closed loop: "):].split():
        key, value = item.split("=", 1)
        out[key] = ([float(v) for v in value.split(",")] if key in ("max_abs_u", "final")
                    else float(value) if key == "min_clearance" else int(value))
    return out


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
        ``satisfied`` (bool), ``reach_time`` (s or None), ``min_clearance`` (state units),
        ``max_abs_u`` (per input), ``final_state``, ``outside_position``,
        ``outside_velocity`` (steps), ``instructions_per_step`` (list over the measured
        steps), ``flash_bytes_controller`` (text + data of the controller object).

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
    prefix = f"{design.spec.c_name}_cascade"
    files = cascade_c_files(design.tube, stage, prefix, "single")
    with tempfile.TemporaryDirectory(prefix="stt-cascade-m4-") as name:
        folder = Path(name)
        for file, text in files.items():
            (folder / file).write_text(text)
        loop = folder / "closed_loop.c"
        loop.write_text(closed_loop_program(design, prefix, seed))
        sources = [folder / f"{prefix}.c", loop]
        full = build_elf(sources, [folder], folder / "full", name="loop")
        run = run_qemu(full.elf, timeout=timeout)
        if run.exit_code != 0:
            raise ToolchainError(f"the closed loop exited with {run.exit_code}:\n"
                                 f"{run.stdout[-2000:]}{run.stderr[-2000:]}")
        summary = _summary(run.stdout)
        measured = build_elf(sources, [folder], folder / "measured",
                             {"MEASURE": None, "STEPS": MEASURED_STEPS}, name="measured")
        counted = run_qemu(measured.elf, timeout=timeout, count_instructions=True)
        controller_object = full.objects[0]
        sizes = elf_sizes(controller_object)
    dt = 1.0 / design.tube.rate_hz
    return {"satisfied": bool(summary["satisfied"]),
            "reach_time": summary["reach_step"] * dt if summary["reach_step"] >= 0 else None,
            "min_clearance": summary["min_clearance"], "max_abs_u": summary["max_abs_u"],
            "final_state": summary["final"], "outside_position": summary["outside_position"],
            "outside_velocity": summary["outside_velocity"], "invalid": summary["invalid"],
            "instructions_per_step": list(counted.instructions or []),
            "flash_bytes_controller": sizes}
