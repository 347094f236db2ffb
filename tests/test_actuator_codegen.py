"""The actuator clamp of ``[actuator] input_bound`` in the model, the reference and the
generated code: ``u`` never beyond the bound, ``STATUS_INPUT_CLAMPED``
when law (13) asked for more, the double C and the Python bit-identical to the CasADi
model; without ``[actuator]`` no piece, table or status is added."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
from functools import lru_cache

import numpy as np
import pytest
from conftest import arena_toml, designed
from sampling import random_points
from codegen_helpers import COMPILERS, CLib, compile_shared, flags, write
from test_model_equivalence import casadi_outputs

from stt_codegen.codegen.functions import clamped_control, deployed_functions
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.design.search import design_tube
from stt_codegen.runtime.compiled import load_python_module
from stt_codegen.spec.loader import parse_spec
from stt_codegen.tube import reference as R
from stt_codegen.tube.model import build_model
from stt_codegen.tube.parameters import (STATUS_INPUT_CLAMPED, STATUS_OFF_PERIOD, STATUS_OK,
                                         STATUS_OUTSIDE_TUBE, step_status)

POINTS = 2000


@lru_cache(maxsize=None)
def bounded():
    """A 2-D arena design with the clamp (the tube of the spec without ``[actuator]``, so
    that these tests do not depend on the bound-aware search).

    The bound is derived from the design, not pinned (law (13)'s ``|u|`` scales with the
    default gain): per input, the median of law (13)'s ``|u_i|`` over the test points
    inside the tube, to two significant digits, so that about half of those points ask
    for more in each input and both statuses OK and INPUT_CLAMPED occur."""
    spec = parse_spec(arena_toml("clamped", extra="[[obstacles]]\nlower = [2.0, 2.0]\n"
                                 "upper = [3.0, 3.0]\n"))
    free = design_tube(spec).tube
    p = _points(free)
    u_law = R.law_step(free, p["x"], p["t"], p["dt"], p["alpha"])[0]
    inside = R.controller_step(free, p["x"], p["t"], p["dt"], p["alpha"])[2] != 0.0
    median = np.median(np.abs(u_law[inside]), axis=0)
    bound = tuple(float(f"{m:.2g}") for m in median)
    return spec, dataclasses.replace(free, input_bound=bound)


def _statuses(model_outputs) -> np.ndarray:
    _, _, inside, within = model_outputs
    return np.where(inside[:, 0] == 0.0, STATUS_OUTSIDE_TUBE,
                    np.where(within[:, 0] == 0.0, STATUS_INPUT_CLAMPED, STATUS_OK))


def _points(tube):
    p = random_points(tube, POINTS, seed=3)
    # a tenth of the points outside the tube in one dimension (clamped e, and u clamped)
    rng = np.random.default_rng(4)
    g_l, g_u, _, _ = R.adaptive_tube(tube, p["t"], p["alpha"])
    out = rng.random(POINTS) < 0.1
    p["x"][out, 0] = g_u[out, 0] + rng.uniform(0.01, 1.0, out.sum())
    return p


def test_without_actuator_nothing_is_added():
    spec, tube, _ = designed("omnirobot-s1")
    assert tube.input_bound is None
    assert "saturate" not in [f.name() for f in deployed_functions(build_model(tube))]
    assert build_model(tube)["controller_step"].n_out() == 3
    files = generate_files(spec, tube, Options(("c", "python"), "double"))
    assert not any(b"INPUT_BOUND" in data or b"CLAMPED" in data for data in files.values())


def test_model_and_reference_clamp_and_report_it():
    _, tube = bounded()
    p = _points(tube)
    step = casadi_outputs(build_model(tube)["controller_step"], p)
    u_ref, next_ref, status_ref = R.law_status(tube, p["x"], p["t"], p["dt"], p["alpha"])
    timed = R.controller_status(tube, p["x"], p["t"], p["dt"], p["alpha"])[2]
    u_law = R.law_step(tube, p["x"], p["t"], p["dt"], p["alpha"])[0]
    bound = np.array(tube.input_bound)
    assert np.all(np.abs(step[0]) <= bound) and np.all(np.abs(u_ref) <= bound)
    # the clamp moves exactly the entries beyond the bound, to the bound
    beyond = np.abs(u_law) > bound
    assert 0.2 < beyond.any(axis=1).mean() < 0.9
    limit = np.broadcast_to(bound, u_law.shape)
    assert np.array_equal(u_ref[beyond], np.sign(u_law[beyond]) * limit[beyond])
    assert np.array_equal(u_ref[~beyond], u_law[~beyond])
    assert np.array_equal(_statuses(step), status_ref)
    assert set(status_ref) == {STATUS_OK, STATUS_OUTSIDE_TUBE, STATUS_INPUT_CLAMPED}
    # the step's status: OFF_PERIOD in place of OK and INPUT_CLAMPED off the period
    assert np.array_equal(timed, step_status(status_ref, p["dt"], tube.rate_hz))
    assert set(timed) == {STATUS_OK, STATUS_OUTSIDE_TUBE, STATUS_INPUT_CLAMPED,
                          STATUS_OFF_PERIOD}
    inside = status_ref != STATUS_OUTSIDE_TUBE
    assert np.array_equal(status_ref[inside] == STATUS_INPUT_CLAMPED, beyond[inside].any(axis=1))
    assert np.all(np.abs(step[0] - u_ref) <= 1e-12 * np.maximum(1.0, np.abs(u_ref)))
    assert np.all(np.abs(step[1] - next_ref) <= 1e-12 * np.maximum(1.0, np.abs(next_ref)))


@pytest.mark.skipif(not COMPILERS, reason="no C compiler")
def test_double_c_and_python_equal_the_model_bit_for_bit(tmp_path):
    spec, tube = bounded()
    files = generate_files(spec, tube, Options(("c", "python"), "double"))
    folder = write(tmp_path / "double", files)
    lib = CLib(compile_shared(folder, spec.c_name, COMPILERS[0], "double"), spec.c_name, 2,
               "double")
    p = _points(tube)
    got = lib.evaluate(p)
    model = build_model(tube)
    step = casadi_outputs(model["controller_step"], p)
    control = casadi_outputs(clamped_control(model), p)
    assert np.array_equal(got["u"], step[0]) and np.array_equal(got["alpha_next"], step[1])
    assert np.array_equal(got["control_u"], control[0])
    assert np.array_equal(got["status"], step_status(_statuses(step), p["dt"], tube.rate_hz))
    assert np.array_equal(got["control_status"], _statuses(step))
    assert np.all(np.abs(got["u"]) <= np.array(tube.input_bound))
    mod = load_python_module(files[f"{spec.c_name}.py"], spec.c_name)
    rows = [mod.step(p["x"][i], p["t"][i], p["dt"][i], p["alpha"][i]) for i in range(POINTS)]
    assert np.array_equal(np.array([r[0] for r in rows]), step[0])
    assert np.array_equal(np.array([r[2] for r in rows]), got["status"])
    controls = [mod.control(p["x"][i], p["t"][i], p["alpha"][i]) for i in range(POINTS)]
    assert np.array_equal(np.array([c[0] for c in controls]), control[0])
    assert mod.STATUS_INPUT_CLAMPED == STATUS_INPUT_CLAMPED
    assert mod.INPUT_BOUND == list(tube.input_bound)


@pytest.mark.skipif(not COMPILERS, reason="no C compiler")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_selftest_covers_the_clamp_status(precision, tmp_path):
    spec, tube = bounded()
    files = generate_files(spec, tube, Options(("c",), precision))
    import json
    vectors = json.loads(files[f"{spec.c_name}_vectors.json"])
    assert STATUS_INPUT_CLAMPED in vectors["status"] and STATUS_OK in vectors["status"]
    folder = write(tmp_path / precision, files)
    cc = COMPILERS[-1]
    build = subprocess.run([cc, *flags(precision), f"{spec.c_name}.c",
                            f"{spec.c_name}_selftest.c", "-o", "selftest", "-lm"],
                           cwd=folder, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run(["./selftest"], cwd=folder, capture_output=True, text=True)
    assert run.returncode == 0 and " 0 failed" in run.stdout, run.stdout[-2000:]
    header = files[f"{spec.c_name}.h"].decode()
    assert "#define CLAMPED_STATUS_INPUT_CLAMPED 3" in header
    assert f"#define CLAMPED_INPUT_BOUND_0 {tube.input_bound[0]!r}" in header


@pytest.mark.skipif(shutil.which("cppcheck") is None,
                    reason="cppcheck missing: install the Debian package cppcheck")
def test_the_clamp_adds_no_misra_deviation(tmp_path):
    """omnirobot-s1 with a clamp: cppcheck's MISRA C:2012 findings are still only the
    listed deviations (the bound table is one more const table, rule 8.9)."""
    from test_codegen_misra import DEVIATIONS
    spec, tube, _ = designed("omnirobot-s1")
    tube = dataclasses.replace(tube, input_bound=(2.0, 2.0, 1.0))
    prefix = spec.c_name
    files = generate_files(spec, tube, Options(("c",), "single"))
    folder = write(tmp_path, {k: v for k, v in files.items() if k in (f"{prefix}.c",
                                                                       f"{prefix}.h")})
    proc = subprocess.run(["cppcheck", "--enable=all", "--addon=misra", "--std=c99",
                           "--suppress=missingIncludeSystem", "--quiet",
                           "--template={file}:{line}:{id}", f"{prefix}.c"],
                          cwd=folder, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    findings = [line.split(":") for line in proc.stderr.splitlines() if line.count(":") >= 2]
    bound_table = False
    for name, line, check in findings:
        text = (folder / name).read_text().splitlines()[int(line) - 1]
        assert any(d[0] == check and re.search(d[1], text) for d in DEVIATIONS), (check, text)
        bound_table |= "_INPUT_BOUND[" in text
    assert bound_table           # the table was analysed, and is the listed 8.9 deviation
