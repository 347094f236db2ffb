"""The cascade law for second-order plants: CasADi pieces against the numpy oracle, the
emitter's Python and C against CasADi, the generated files (docs/second-order.md)."""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import subprocess

import numpy as np
import pytest
from conftest import designed
from sampling import random_points
from test_emit_python import casadi_dense, same_double

from stt_codegen.codegen.cascade_source import cascade_c_files, cascade_python_file
from stt_codegen.codegen.emit import python_function
from stt_codegen.tube import cascade, cascade_reference
from stt_codegen.tube.parameters import E_MAX
from stt_codegen.tube.second_stage import SecondStage

CC = shutil.which("gcc") or shutil.which("clang")
STRICT = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow",
          "-Wconversion", "-Wdouble-promotion", "-Wcast-qual", "-Wstrict-prototypes",
          "-Wmissing-prototypes", "-Werror"]
TOLERANCE = 1e-12
STAGE = SecondStage(position_gain=0.02, velocity_gain=3.0, width_start=(1.5, 1.2, 0.9),
                    width_floor=(0.3, 0.25, 0.2), decay=2.0)


@pytest.fixture(scope="module")
def tube():
    return designed("omnirobot-s1")[1]


def _points(tube, count: int, seed: int, velocity_limit: float = 0.99):
    """Points strictly inside the position tube, ``x2`` with ``|e2| <= velocity_limit``."""
    p = random_points(tube, count, seed=seed)
    rng = np.random.default_rng(seed)
    first = dataclasses.replace(tube, gain=STAGE.position_gain)
    r, _, _ = cascade_reference.reference.law_step(first, p["x"], p["t"], p["dt"], p["alpha"])
    rho2 = cascade_reference.velocity_tube(STAGE, p["t"])
    p["x2"] = r + rho2 * rng.uniform(-velocity_limit, velocity_limit, r.shape)
    return p


def _casadi(function, p, names=("x", "x2", "t", "dt", "alpha")):
    count = len(p["t"])
    args = [np.atleast_2d(p[k]) if p[k].ndim == 1 else p[k].T for k in names]
    out = function.map(count)(*args)
    return [np.array(o).T.reshape(count, -1) for o in out]


def test_stage_rejects_bad_numbers() -> None:
    with pytest.raises(ValueError, match="gains"):
        SecondStage(0.0, 1.0, (1.0,), (0.5,), 1.0)
    with pytest.raises(ValueError, match="width_floor <= width_start"):
        SecondStage(1.0, 1.0, (0.4,), (0.5,), 1.0)
    with pytest.raises(ValueError, match="finite"):
        SecondStage(1.0, float("nan"), (1.0,), (0.5,), 1.0)


def test_velocity_tube_piece_matches_the_oracle() -> None:
    t = np.concatenate([np.linspace(0.0, 30.0, 301), [1e-9, 100.0]])
    f = cascade.velocity_tube(3)
    got = np.array([np.array(f(v, STAGE.width_start, STAGE.width_floor, STAGE.decay)).ravel()
                    for v in t])
    expected = cascade_reference.velocity_tube(STAGE, t)
    np.testing.assert_allclose(got, expected, rtol=TOLERANCE, atol=0)
    assert np.all(got >= np.array(STAGE.width_floor)) and np.allclose(got[0], STAGE.width_start)


def test_cascade_step_matches_the_oracle(tube) -> None:
    p = _points(tube, 3000, seed=4)
    got = _casadi(cascade.cascade_step(tube, STAGE), p)
    expected = cascade_reference.cascade_step(tube, STAGE, p["x"], p["x2"], p["t"], p["dt"],
                                              p["alpha"])
    assert got[3].min() == 1.0 and expected[3].min() == 1.0      # all inside the tube
    assert got[4].min() == 1.0 and expected[4].min() == 1.0
    for name, a, b in zip(cascade.CASCADE_OUTPUTS, got, expected):
        b = np.asarray(b, dtype=float).reshape(a.shape)
        scale = np.maximum(1.0, np.abs(b))
        assert np.max(np.abs(a - b) / scale) <= TOLERANCE, name


def test_outside_the_velocity_tube_is_reported_and_u_stays_finite(tube) -> None:
    p = _points(tube, 500, seed=5)
    rho2 = cascade_reference.velocity_tube(STAGE, p["t"])
    first = dataclasses.replace(tube, gain=STAGE.position_gain)
    r, _, _ = cascade_reference.reference.law_step(first, p["x"], p["t"], p["dt"], p["alpha"])
    p["x2"] = r + rho2 * np.where(np.arange(len(p["t"]))[:, None] % 2 == 0, 1.0, -3.0)
    u, _, _, inside_p, inside_v = _casadi(cascade.cascade_step(tube, STAGE), p)
    assert inside_p.min() == 1.0 and inside_v.max() == 0.0
    assert np.all(np.isfinite(u))
    e2 = (p["x2"] - r) / rho2
    # the clamped law pushes back, with the magnitude of |e2| = E_MAX
    assert np.all(np.sign(u) == -np.sign(e2))
    bound = STAGE.velocity_gain * 2.0 / (np.array(STAGE.width_floor) * (1 - E_MAX**2)) \
        * np.log((1 + E_MAX) / (1 - E_MAX))
    assert np.all(np.abs(u) <= bound * (1 + 1e-12))


def test_emitted_python_is_bit_identical_to_casadi(tube) -> None:
    function = cascade.cascade_step(tube, STAGE)
    printed = python_function(function)
    p = _points(tube, 40, seed=6)
    for k in range(40):
        inputs = [list(np.atleast_1d(p[name][k])) for name in ("x", "x2", "t", "dt", "alpha")]
        expected = casadi_dense(function, inputs)
        got = printed(*inputs)
        for e, g in zip(expected, got):
            assert all(same_double(a, b) for a, b in zip(e, g))


def _load(tmp_path, tube, precision: str):
    files = cascade_c_files(tube, STAGE, "cascade_test", precision)
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    lib = tmp_path / f"libcascade_{precision}.so"
    proc = subprocess.run([CC, *STRICT, "-fPIC", "-shared", str(tmp_path / "cascade_test.c"),
                           "-o", str(lib), "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    return ctypes.CDLL(str(lib)), files


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
def test_emitted_c_double_is_bit_identical_and_checks_inputs(tmp_path, tube) -> None:
    lib, files = _load(tmp_path, tube, "double")
    assert "malloc" not in files["cascade_test.c"]
    includes = [line for line in files["cascade_test.c"].splitlines()
                if line.startswith("#include")]
    assert includes == ["#include <math.h>", '#include "cascade_test.h"']
    function = cascade.cascade_step(tube, STAGE)
    real_p = ctypes.POINTER(ctypes.c_double)
    step = lib.cascade_test_step
    step.argtypes = [ctypes.c_double, ctypes.c_double] + [real_p] * 6
    p = _points(tube, 200, seed=7)
    for k in range(200):
        x1, x2, alpha = (np.ascontiguousarray(p[name][k], dtype=float)
                         for name in ("x", "x2", "alpha"))
        u, alpha_next, r = np.zeros(3), np.zeros(6), np.zeros(3)
        code = step(float(p["t"][k]), float(p["dt"][k]),
                    *(a.ctypes.data_as(real_p) for a in (x1, x2, alpha, u, alpha_next, r)))
        expected = casadi_dense(function, [x1, x2, [p["t"][k]], [p["dt"][k]], alpha])
        assert code == 0
        for got, exp in zip((u, alpha_next, r), expected):
            assert all(same_double(float(a), b) for a, b in zip(got, exp))
    # outside the domain: INVALID_INPUT, u = 0, alpha kept
    x1, x2, alpha = np.full(3, 1.0), np.zeros(3), np.full(6, 0.1)
    u = np.full(3, 7.0)
    alpha_next, r = np.zeros(6), np.zeros(3)
    for t, dt in ((-1.0, 1e-3), (float("nan"), 1e-3), (1.0, 0.0), (1.0, 2.0)):
        code = step(t, dt, *(a.ctypes.data_as(real_p) for a in (x1, x2, alpha, u, alpha_next, r)))
        assert code == 2 and np.all(u == 0.0) and np.all(alpha_next == alpha)


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
def test_emitted_c_single_compiles_without_warnings(tmp_path, tube) -> None:
    _, files = _load(tmp_path, tube, "single")
    assert "double" not in files["cascade_test.c"].split("*/", 1)[1]


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
def test_emitted_c_single_is_within_the_derived_bound(tmp_path, tube) -> None:
    """The single C against the numpy oracle on 1000 points (times packed near window
    edges and ``t_c``, ``alpha > 0``, ``|e2| <= 0.99``, inputs rounded to float32): every
    ``u``, ``r`` and ``alpha_next`` within :func:`tolerance.cascade_bounds`."""
    from stt_codegen.codegen import tolerance
    lib, _ = _load(tmp_path, tube, "single")
    step = lib.cascade_test_step
    real_p = ctypes.POINTER(ctypes.c_float)
    step.argtypes = [ctypes.c_float, ctypes.c_float] + [real_p] * 6
    p = {k: np.asarray(v, dtype=np.float32).astype(float)
         for k, v in _points(tube, 1000, seed=8).items()}
    x1, x2, t, dt, alpha = (p[k] for k in ("x", "x2", "t", "dt", "alpha"))
    u_ref, a_ref, r_ref, _, _ = cascade_reference.cascade_step(tube, STAGE, x1, x2, t, dt, alpha)
    bounds = tolerance.cascade_bounds(tube, STAGE, x1, x2, t, alpha, r_ref, a_ref,
                                      tolerance.UNIT_SINGLE)
    for k in range(t.size):
        inputs = [np.ascontiguousarray(a[k], dtype=np.float32) for a in (x1, x2, alpha)]
        u, alpha_next, r = np.zeros(3, np.float32), np.zeros(6, np.float32), np.zeros(3, np.float32)
        step(t[k], dt[k], *(a.ctypes.data_as(real_p) for a in (*inputs, u, alpha_next, r)))
        for got, ref, bound in zip((u, r, alpha_next), (u_ref, r_ref, a_ref), bounds):
            assert np.all(np.abs(got - ref[k]) <= bound[k]), (k, got, ref[k], bound[k])


def test_generated_files_are_deterministic_and_say_what_they_are(tube) -> None:
    first = {**cascade_c_files(tube, STAGE, "cascade_test"),
             **cascade_python_file(tube, STAGE, "cascade_test")}
    again = {**cascade_c_files(tube, STAGE, "cascade_test"),
             **cascade_python_file(tube, STAGE, "cascade_test")}
    assert first == again
    for text in first.values():
        assert "GENERATED FILE" in text.splitlines()[0] and tube.name in text[:400]
        assert "/work" not in text and "/home" not in text


def test_generated_python_runs_and_matches_the_oracle(tube) -> None:
    namespace: dict = {}
    exec(compile(cascade_python_file(tube, STAGE, "cascade_test")["cascade_test.py"],
                 "cascade_test.py", "exec"), namespace)
    p = _points(tube, 30, seed=8)
    expected = cascade_reference.cascade_step(tube, STAGE, p["x"], p["x2"], p["t"], p["dt"],
                                              p["alpha"])
    for k in range(30):
        u, alpha_next, r, status = namespace["step"](p["t"][k], p["dt"][k], p["x"][k],
                                                     p["x2"][k], p["alpha"][k])
        assert status == namespace["OK"]
        np.testing.assert_allclose(u, expected[0][k], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(r, expected[2][k], rtol=1e-10, atol=1e-12)
    assert namespace["step"](-1.0, 1e-3, p["x"][0], p["x2"][0], p["alpha"][0])[3] == 2


def test_the_oracles_unclamped_transform_is_the_deployed_one_inside() -> None:
    rng = np.random.default_rng(9)
    r, rho2 = rng.uniform(-2, 2, (200, 3)), rng.uniform(0.1, 2, (200, 3))
    x2 = r + rho2 * rng.uniform(-0.99, 0.99, (200, 3))
    expected = cascade_reference.velocity_transform(x2, r, rho2)
    f = cascade.velocity_transform(3)
    for k in range(200):
        got = [np.array(v).ravel() for v in f(x2[k], r[k], rho2[k])]
        for a, b in zip(got, expected):
            np.testing.assert_allclose(a, b[k], rtol=1e-12, atol=1e-15)
    outside = cascade_reference.velocity_transform([[2.0]], [[0.0]], [[1.0]])
    assert np.isnan(outside[1][0, 0])                  # the oracle does not clamp
