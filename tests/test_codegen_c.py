"""Generated C: builds warning-free with gcc and clang, matches CasADi and the reference."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from codegen_helpers import COMPILERS, built, files_of, flags, self_test, write
from conftest import CASES, designed, model_of
from sampling import random_points
from test_model_equivalence import casadi_outputs

from stt_codegen.tube import reference as R
from stt_codegen.codegen import tolerance as T
from stt_codegen.codegen.functions import clamped_control
from stt_codegen.design.samples import sample_tube
from stt_codegen.tube.parameters import Status, step_status

POINTS = 10_000
DOUBLE_TOL = 1e-12

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("codegen-c"))


@pytest.fixture(scope="module")
def points():
    return {case: random_points(designed(case)[1], POINTS, seed=11) for case in CASES}


def _close(got, ref, name):
    bad = np.abs(got - ref) > DOUBLE_TOL * np.maximum(1.0, np.abs(ref))
    assert not bad.any(), (f"{name}: {bad.sum()} entries differ, worst "
                           f"{np.max(np.abs(got - ref) / np.maximum(1, np.abs(ref))):.3e}")


@pytest.mark.parametrize("case", CASES)
def test_double_matches_reference_and_casadi_exactly(case, root, points):
    _, design, _ = designed(case)
    p = points[case]
    lib = built(case, "double", COMPILERS[0], root)
    got = lib.evaluate(p)
    t, a, x, dt = p["t"], p["alpha"], p["x"], p["dt"]
    g_l, g_u, g_l_dot, g_u_dot = R.adaptive_tube(design, t, a)
    u, alpha_next, inside = R.controller_step(design, x, t, dt, a)
    for name, ref in (("gamma_L", g_l), ("gamma_U", g_u), ("gamma_L_dot", g_l_dot),
                      ("gamma_U_dot", g_u_dot), ("u", u), ("control_u", u),
                      ("alpha_next", alpha_next), ("alpha_step", alpha_next)):
        _close(got[name], ref, name)
    # the step's OFF_PERIOD where dt is not the period; P_control takes no dt
    assert np.all(inside == 1.0)
    assert np.array_equal(got["status"], step_status(np.zeros(len(t), int), dt, design.rate_hz))
    assert Status.OK in got["status"] and Status.OFF_PERIOD in got["status"]
    assert np.all(got["control_status"] == 0) and np.all(got["tube_status"] == 0)
    # CasADi's VM, same libm, -ffp-contract=off: bit for bit.
    model = model_of(case)
    step = casadi_outputs(model["controller_step"], p)
    tube = casadi_outputs(model["tube"], p)
    control = casadi_outputs(clamped_control(model), p)
    assert np.array_equal(got["u"], step[0]) and np.array_equal(got["alpha_next"], step[1])
    assert np.array_equal(got["control_u"], control[0])
    for k, name in enumerate(("gamma_L", "gamma_U", "gamma_L_dot", "gamma_U_dot")):
        assert np.array_equal(got[name], tube[k]), name


@pytest.mark.parametrize("case", CASES)
def test_single_within_the_stated_bound(case, root, points):
    _, design, _ = designed(case)
    p = {k: v.astype(np.float32).astype(np.float64) for k, v in points[case].items()}
    lib = built(case, "single", COMPILERS[-1], root)
    got = lib.evaluate(p)
    t, a, x, dt = p["t"], p["alpha"], p["x"], p["dt"]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, a)
    u, alpha_next, inside = R.controller_step(design, x, t, dt, a)
    unit = T.UNIT_SINGLE
    tol_g = T.gamma_bound(design, a, unit)
    tol_u = T.u_bound(design, x, a, g_l, g_u, u, unit)
    tol_a = T.alpha_bound(design, a, alpha_next, unit)
    ratios = {}
    for name, ref, tol in (("gamma_L", g_l, tol_g), ("gamma_U", g_u, tol_g), ("u", u, tol_u),
                           ("control_u", u, tol_u), ("alpha_next", alpha_next, tol_a),
                           ("alpha_step", alpha_next, tol_a)):
        err = np.abs(got[name] - ref)
        assert np.all(np.isfinite(got[name])), name
        ratios[name] = float(np.max(err / tol))
        assert ratios[name] <= 1.0, (name, ratios[name])
    certain = T.status_certain(design, x, a, g_l, g_u, unit)
    assert certain.mean() > 0.9
    law = np.where(inside == 1.0, Status.OK, Status.OUTSIDE_TUBE)
    assert np.all(got["status"][certain] == step_status(law, dt, design.rate_hz)[certain])
    assert np.all(got["control_status"][certain] == law[certain])
    # the bound is not vacuous: the errors use a real part of it somewhere
    assert max(ratios.values()) > 1e-3, ratios


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("cc", COMPILERS)
def test_strict_build_and_self_test_pass(cc, precision, tmp_path):
    case = "omnirobot-s1" if cc == "gcc" else "omnirobot-s3"
    spec, _, _ = designed(case)
    folder = write(tmp_path, files_of(case, precision))
    last = self_test(folder, spec.c_name, cc, precision)
    assert int(last.split()[0]) >= 56 * 10 + 7


@pytest.mark.parametrize("precision", ["double", "single"])
def test_no_mutable_state_and_only_libm(precision, tmp_path):
    spec, _, _ = designed("omnirobot-s2")
    folder = write(tmp_path, files_of("omnirobot-s2", precision))
    prefix = spec.c_name
    subprocess.run([COMPILERS[0], *flags(precision), "-c", f"{prefix}.c"], cwd=folder, check=True)
    size = subprocess.run(["size", "-A", f"{prefix}.o"], cwd=folder, capture_output=True,
                          text=True, check=True).stdout
    sections = {line.split()[0]: int(line.split()[1]) for line in size.splitlines()[2:]
                if len(line.split()) >= 2 and line.split()[1].isdigit()}
    assert sections.get(".data", 0) == 0 and sections.get(".bss", 0) == 0, size
    syms = subprocess.run(["nm", "-u", f"{prefix}.o"], cwd=folder, capture_output=True,
                          text=True, check=True).stdout.split()
    undefined = sorted(s for s in syms if s != "U")
    libm_d = {"exp", "log", "log1p", "tanh", "pow", "sqrt", "fabs"}
    allowed = libm_d if precision == "double" else {f + "f" for f in libm_d}
    assert set(undefined) <= allowed, undefined
    defined = subprocess.run(["nm", "-g", "--defined-only", f"{prefix}.o"], cwd=folder,
                             capture_output=True, text=True, check=True).stdout.split()
    exported = sorted(s for s in defined if s.startswith(prefix))
    assert exported == [f"{prefix}_{n}" for n in ("alpha_step", "control", "step", "tube")]


@pytest.mark.parametrize("precision", ["double", "single"])
def test_invalid_inputs_and_outside_tube(precision, root):
    case = "omnirobot-s1"
    _, design, _ = designed(case)
    lib = built(case, precision, COMPILERS[0], root)
    n = design.dimension
    samples = sample_tube(design)
    k = int(np.searchsorted(samples.t, 2.0))
    t, dt = float(samples.t[k]), 1e-3
    a = lib.arr(samples.alpha[k])
    g_l, g_u, _, _ = R.adaptive_tube(design, t, a.astype(float))
    mid = lib.arr((g_l[0] + g_u[0]) / 2)
    step = lib.f["step"]
    for x, tt, d, code in ((mid, t, dt, 0), (mid + lib.arr(g_u[0] - g_l[0]), t, dt, 1),
                           (mid, float("nan"), dt, 2), (mid, t, 0.0, 2), (mid, t, -dt, 2),
                           (mid, t, float("inf"), 2), (lib.arr([np.nan] * n), t, dt, 2)):
        u, nxt = lib.arr(np.ones(n)), lib.arr(None, 2 * n)
        assert step(lib.ptr(x), tt, d, lib.ptr(a), lib.ptr(u), lib.ptr(nxt)) == code
        assert np.all(np.isfinite(u))
        if code == 2:
            assert np.all(u == 0) and np.array_equal(nxt, a)
        if code == 1:
            assert np.all(np.isfinite(nxt)) and np.abs(u).max() > 0
    # in-place update: alpha_next may alias alpha
    a2, u, nxt = a.copy(), lib.arr(None, n), lib.arr(None, 2 * n)
    step(lib.ptr(mid), t, dt, lib.ptr(a), lib.ptr(u), lib.ptr(nxt))
    step(lib.ptr(mid), t, dt, lib.ptr(a2), lib.ptr(u), lib.ptr(a2))
    assert np.array_equal(a2, nxt)
    # NULL outputs are refused, optional derivative outputs may be NULL
    assert step(lib.ptr(mid), t, dt, lib.ptr(a), None, lib.ptr(nxt)) == 2
    gl, gu = lib.arr(None, n), lib.arr(None, n)
    assert lib.f["tube"](t, lib.ptr(a), lib.ptr(gl), lib.ptr(gu), None, None) == 0


@pytest.mark.parametrize("precision", ["double", "single"])
def test_fast_math_refused_with_a_clear_error(precision, tmp_path):
    spec, _, _ = designed("omnirobot-s1")
    folder = write(tmp_path, files_of("omnirobot-s1", precision))
    for cc in COMPILERS:
        proc = subprocess.run([cc, "-std=c99", "-Ofast", "-c", f"{spec.c_name}.c"], cwd=folder,
                              capture_output=True, text=True)
        assert proc.returncode != 0 and "must not be compiled with -ffast-math" in proc.stderr, (
            cc, proc.stderr[-1000:])


@pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None,
                    reason="arm-none-eabi-gcc missing: install the Debian package gcc-arm-none-eabi")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_strict_build_for_cortex_m4(precision, tmp_path):
    spec, _, _ = designed("omnirobot-s1")
    folder = write(tmp_path, files_of("omnirobot-s1", precision))
    proc = subprocess.run(["arm-none-eabi-gcc", *flags(precision), "-mcpu=cortex-m4",
                           "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-mthumb", "-c",
                           f"{spec.c_name}.c", f"{spec.c_name}_selftest.c"],
                          cwd=folder, capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr


@pytest.mark.parametrize("obstacles", [0, 1, 6])
def test_strict_build_for_any_number_of_circumvents(obstacles, tmp_path):
    """No circumvent, one per bound, several per bound: strict build and self-test."""
    from stt_codegen_bench.scaling import synthetic_design
    from stt_codegen.codegen.generate import generate_files
    from stt_codegen.codegen.options import Options

    class _Spec:
        name, c_name, source_hash = "synthetic", "synthetic", "0" * 64
        delay = jitter = 0.0
        compensate_delay = False

    design = synthetic_design(obstacles, 2, windows="open")
    for precision in ("double", "single"):
        folder = write(tmp_path / precision, generate_files(_Spec(), design,
                                                            Options(("c",), precision)))
        exe = folder / "selftest"
        proc = subprocess.run([COMPILERS[0], *flags(precision), "synthetic.c",
                               "synthetic_selftest.c", "-o", str(exe), "-lm"], cwd=folder,
                              capture_output=True, text=True)
        assert proc.returncode == 0 and proc.stderr == "", proc.stderr
        run = subprocess.run([str(exe)], capture_output=True, text=True)
        assert run.returncode == 0 and run.stdout.strip().endswith(" 0 failed"), run.stdout[-2000:]
