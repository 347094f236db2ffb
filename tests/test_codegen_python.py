"""Generated Python: bit-identical to CasADi's evaluation, within 1e-12 of the reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from codegen_helpers import files_of
from conftest import CASES, designed, model_of
from sampling import random_points
from test_model_equivalence import casadi_outputs

from stt_codegen.tube import reference as R
from stt_codegen.tube.parameters import step_status
from stt_codegen.runtime.compiled import load_python_module
from stt_codegen.codegen.functions import clamped_control

POINTS = 1_500


def module_of(case):
    spec, _, _ = designed(case)
    source = files_of(case, "double")[f"{spec.c_name}.py"]
    imports = [line for line in source.decode().splitlines() if line.startswith(("import ", "from "))]
    assert imports == ["import math", "import math"]  # the wrapper's and the emitted part's
    return load_python_module(source, spec.c_name)


@pytest.mark.parametrize("case", CASES)
def test_bit_identical_to_casadi_and_close_to_reference(case):
    _, design, _ = designed(case)
    mod = module_of(case)
    p = random_points(design, POINTS, seed=5)
    rows = [mod.step(p["x"][i], p["t"][i], p["dt"][i], p["alpha"][i]) for i in range(POINTS)]
    u = np.array([r[0] for r in rows])
    nxt = np.array([r[1] for r in rows])
    # inside: OK at the period, OFF_PERIOD off it
    assert np.array_equal([r[2] for r in rows],
                          step_status(np.full(POINTS, mod.STATUS_OK), p["dt"], design.rate_hz))
    tubes = [mod.tube(p["t"][i], p["alpha"][i]) for i in range(POINTS)]
    controls = np.array([mod.control(p["x"][i], p["t"][i], p["alpha"][i])[0] for i in range(POINTS)])
    model = model_of(case)
    step = casadi_outputs(model["controller_step"], p)
    tube = casadi_outputs(model["tube"], p)
    assert np.array_equal(u, step[0]) and np.array_equal(nxt, step[1])
    assert np.array_equal(controls, casadi_outputs(clamped_control(model), p)[0])
    for k in range(4):
        assert np.array_equal(np.array([tb[k] for tb in tubes]), tube[k])
    u_ref, nxt_ref, _ = R.controller_step(design, p["x"], p["t"], p["dt"], p["alpha"])
    for got, ref in ((u, u_ref), (nxt, nxt_ref)):
        assert np.all(np.abs(got - ref) <= 1e-12 * np.maximum(1.0, np.abs(ref)))


def test_status_codes_and_input_checks():
    mod = module_of("omnirobot-s1")
    _, design, _ = designed("omnirobot-s1")
    n = mod.N
    alpha = [0.0] * mod.N_ALPHA
    g_l, g_u, _, _, status = mod.tube(0.0, alpha)
    assert status == 0
    mid = [(a + b) / 2 for a, b in zip(g_l, g_u)]
    assert mod.step(mid, 0.0, 1e-3, alpha)[2] == mod.STATUS_OK
    outside = list(mid)
    outside[0] = g_u[0] + 1.0
    u, nxt, status = mod.step(outside, 0.0, 1e-3, alpha)
    assert status == mod.STATUS_OUTSIDE_TUBE and all(math.isfinite(v) for v in u + nxt)
    for args in ((mid, math.nan, 1e-3), (mid, 0.0, 0.0), (mid, 0.0, -1.0), (mid, 0.0, math.inf),
                 ([math.nan] * n, 0.0, 1e-3), (mid[:-1], 0.0, 1e-3), ("abc", 0.0, 1e-3)):
        u, nxt, status = mod.step(*args, alpha)
        assert status == mod.STATUS_INVALID_INPUT and u == [0.0] * n and nxt == alpha
    assert mod.control(mid, math.inf, alpha) == ([0.0] * n, mod.STATUS_INVALID_INPUT)
    assert mod.alpha_step(0.0, 0.0, alpha) == (alpha, mod.STATUS_INVALID_INPUT)
    assert mod.tube(math.nan, alpha)[-1] == mod.STATUS_INVALID_INPUT
