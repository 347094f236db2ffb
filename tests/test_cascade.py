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
from stt_codegen.tube.parameters import E_MAX, Status, step_status
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
    p["state"] = np.hstack([p["x"], p["x2"]])
    return p


def _casadi(function, p, names=("state", "t", "dt", "alpha")):
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
    expected = cascade_reference.cascade_step(tube, STAGE, p["state"], p["t"], p["dt"],
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
    p["state"] = np.hstack([p["x"], p["x2"]])
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
        inputs = [list(np.atleast_1d(p[name][k])) for name in ("state", "t", "dt", "alpha")]
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


def _c_step(lib, precision: str = "double"):
    """``step(x, t, dt, alpha) -> (code, u, alpha_next, r)`` of the loaded C: ``P_step``
    for the code, ``u`` and ``alpha_next``, ``P_virtual_velocity`` for ``r`` (its code
    agrees with a valid step's on the position tube; r = 0 when it is INVALID_INPUT)."""
    real = ctypes.c_double if precision == "double" else ctypes.c_float
    dtype = np.float64 if precision == "double" else np.float32
    pointer = ctypes.POINTER(real)
    entry = lib.cascade_test_step
    entry.argtypes = [pointer, real, real, pointer, pointer, pointer]
    entry.restype = ctypes.c_int
    virtual = lib.cascade_test_virtual_velocity
    virtual.argtypes = [pointer, real, pointer, pointer]
    virtual.restype = ctypes.c_int

    def step(x, t, dt, alpha):
        x, alpha = (np.ascontiguousarray(v, dtype=dtype) for v in (x, alpha))
        n = x.size // 2
        u, alpha_next, r = np.full(n, 7.0, dtype), np.zeros(2 * n, dtype), np.full(n, 7.0, dtype)
        code = entry(x.ctypes.data_as(pointer), t, dt, alpha.ctypes.data_as(pointer),
                     *(a.ctypes.data_as(pointer) for a in (u, alpha_next)))
        r_code = virtual(x.ctypes.data_as(pointer), t, alpha.ctypes.data_as(pointer),
                         r.ctypes.data_as(pointer))
        if code != Status.INVALID_INPUT:
            assert r_code == (Status.OUTSIDE_TUBE if code == Status.OUTSIDE_TUBE
                              else Status.OK), (code, r_code)
        assert np.all(np.isfinite(r))
        if r_code == Status.INVALID_INPUT:
            assert np.all(r == 0.0)
        return code, u, alpha_next, r
    return step


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
def test_emitted_c_double_is_bit_identical_and_checks_inputs(tmp_path, tube) -> None:
    lib, files = _load(tmp_path, tube, "double")
    assert "malloc" not in files["cascade_test.c"]
    includes = [line for line in files["cascade_test.c"].splitlines()
                if line.startswith("#include")]
    assert includes == ["#include <math.h>", "#include <stddef.h>", '#include "cascade_test.h"']
    function = cascade.cascade_step(tube, STAGE)
    step = _c_step(lib)
    p = _points(tube, 200, seed=7)
    for k in range(200):
        x, alpha = p["state"][k], p["alpha"][k]
        code, *got = step(x, float(p["t"][k]), float(p["dt"][k]), alpha)
        expected = casadi_dense(function, [x, [p["t"][k]], [p["dt"][k]], alpha])
        assert code == step_status(Status.OK, p["dt"][k], tube.rate_hz)    # OFF_PERIOD off it
        for out, exp in zip(got, expected):
            assert all(same_double(float(a), b) for a, b in zip(out, exp))
    # outside the domain: INVALID_INPUT, u = 0, r = 0, alpha kept (non-finite entries 0)
    x, alpha = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]), np.full(6, 0.1)
    nan = float("nan")
    for t, dt, xs, a in ((-1.0, 1e-3, x, alpha), (nan, 1e-3, x, alpha), (1.0, 0.0, x, alpha),
                         (1.0, 100.0, x, alpha), (1.0, 1e-3, np.r_[x[:5], nan], alpha),
                         (1.0, 1e-3, np.r_[x[:3], np.inf, x[4:]], alpha),
                         (1.0, 1e-3, x, np.r_[alpha[:5], -1.0]),
                         (1.0, 1e-3, x, np.r_[alpha[:5], nan])):
        code, u, alpha_next, r = step(xs, t, dt, a)
        assert code == Status.INVALID_INPUT
        assert np.all(u == 0.0)
        # the virtual velocity takes no dt: r = 0 where x, t or alpha is outside the domain
        assert np.all(r == 0.0) or (np.isfinite(t) and t >= 0 and np.all(np.isfinite(xs))
                                    and np.all((a >= 0) & np.isfinite(a)))
        assert np.array_equal(alpha_next, np.where(np.isfinite(a), a, 0.0))


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
    step = _c_step(lib, "single")
    p = {k: np.asarray(v, dtype=np.float32).astype(float)
         for k, v in _points(tube, 1000, seed=8).items()}
    x1, x2, x, t, dt, alpha = (p[k] for k in ("x", "x2", "state", "t", "dt", "alpha"))
    u_ref, a_ref, r_ref, *_ = cascade_reference.cascade_step(tube, STAGE, x, t, dt, alpha)
    bounds = tolerance.cascade_bounds(tube, STAGE, x1, x2, t, alpha, r_ref, a_ref,
                                      tolerance.UNIT_SINGLE)
    for k in range(t.size):
        _, u, alpha_next, r = step(x[k], t[k], dt[k], alpha[k])
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
    expected = cascade_reference.cascade_step(tube, STAGE, p["state"], p["t"], p["dt"],
                                              p["alpha"])
    for k in range(30):
        u, alpha_next, status = namespace["step"](p["state"][k], p["t"][k], p["dt"][k],
                                                  p["alpha"][k])
        r, r_status = namespace["virtual_velocity"](p["state"][k], p["t"][k], p["alpha"][k])
        assert r_status == namespace["STATUS_OK"] == Status.OK
        assert status == step_status(Status.OK, p["dt"][k], tube.rate_hz)
        np.testing.assert_allclose(u, expected[0][k], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(r, expected[2][k], rtol=1e-10, atol=1e-12)
    invalid = namespace["step"](p["state"][0], -1.0, 1e-3, p["alpha"][0])
    assert invalid[2] == namespace["STATUS_INVALID_INPUT"] == Status.INVALID_INPUT
    assert invalid[0] == [0.0] * 3
    assert invalid[1] == list(p["alpha"][0])
    assert namespace["virtual_velocity"](p["state"][0], -1.0, p["alpha"][0]) == (
        [0.0] * 3, Status.INVALID_INPUT)
    nan_x = [*p["state"][0][:5], float("nan")]
    nan_alpha = [*p["alpha"][0][:5], float("inf")]
    for args in ((nan_x, 1.0, 1e-3, p["alpha"][0]), (p["state"][0], 1.0, 1e-3, nan_alpha),
                 (p["state"][0][:5], 1.0, 1e-3, p["alpha"][0])):
        u, alpha_next, status = namespace["step"](*args)
        assert status == Status.INVALID_INPUT and u == [0.0] * 3
        assert alpha_next == [v if np.isfinite(v) else 0.0 for v in args[3]]
        assert namespace["virtual_velocity"](args[0], args[1], args[3]) == (
            [0.0] * 3, Status.INVALID_INPUT)


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


@pytest.fixture(scope="module")
def bounded(tube):
    """The tube with an actuator bound near the median ``|u|`` of :func:`_points`: about
    half of the steps clamp some input."""
    p = _points(tube, 400, seed=10)
    u = cascade_reference.cascade_step(tube, STAGE, p["state"], p["t"], p["dt"], p["alpha"])[0]
    return dataclasses.replace(tube, input_bound=tuple(float(b) for b in
                                                       np.median(np.abs(u), axis=0)))


def test_the_actuator_bound_clamps_u_like_the_oracle(tube, bounded) -> None:
    p = _points(tube, 2000, seed=11)
    function = cascade.cascade_step(bounded, STAGE)
    assert function.name_out()[-1] == "within_bound"
    got = _casadi(function, p)
    expected = cascade_reference.cascade_step(bounded, STAGE, p["state"], p["t"], p["dt"],
                                              p["alpha"])
    free = cascade_reference.cascade_step(tube, STAGE, p["state"], p["t"], p["dt"], p["alpha"])
    bound = np.array(bounded.input_bound)
    moved = np.any(np.abs(free[0]) > bound, axis=1)
    assert 0.2 < moved.mean() < 0.95                    # clamped and unclamped steps
    assert np.array_equal(got[5].ravel(), (~moved).astype(float))
    assert np.array_equal(expected[5], (~moved).astype(float))
    assert np.all(np.abs(got[0]) <= bound)
    for a, b in zip(got, expected):
        b = np.asarray(b, dtype=float).reshape(a.shape)
        assert np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))) <= TOLERANCE
    # where nothing is clamped, u is the unbounded law's
    np.testing.assert_array_equal(expected[0][~moved], free[0][~moved])


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
def test_emitted_c_with_a_bound_is_bit_identical_and_reports_input_clamped(tmp_path, tube,
                                                                           bounded) -> None:
    lib, files = _load(tmp_path, bounded, "double")
    assert "CASCADE_TEST_STATUS_INPUT_CLAMPED 3" in files["cascade_test.h"]
    step = _c_step(lib)
    function = cascade.cascade_step(bounded, STAGE)
    p = _points(tube, 300, seed=12)
    # every third point outside the velocity tube: OUTSIDE_VELOCITY_TUBE takes precedence
    rho2 = cascade_reference.velocity_tube(STAGE, p["t"])
    p["state"][::3, 3:] += 3.0 * rho2[::3]
    codes = []
    for k in range(300):
        x, alpha = p["state"][k], p["alpha"][k]
        code, *got = step(x, float(p["t"][k]), float(p["dt"][k]), alpha)
        expected = casadi_dense(function, [x, [p["t"][k]], [p["dt"][k]], alpha])
        for out, exp in zip(got, expected):
            assert all(same_double(float(a), b) for a, b in zip(out, exp))
        inside_p, inside_v, within = (e[0] for e in expected[3:])
        assert inside_p == 1.0
        assert code == step_status(Status.OUTSIDE_VELOCITY_TUBE if inside_v == 0.0 else
                                   Status.INPUT_CLAMPED if within == 0.0 else Status.OK,
                                   p["dt"][k], bounded.rate_hz)
        code = (Status.OUTSIDE_VELOCITY_TUBE if inside_v == 0.0 else     # the law's status
                step(x, float(p["t"][k]), 1.0 / bounded.rate_hz, alpha)[0])
        assert np.all(np.abs(got[0]) <= np.array(bounded.input_bound))
        codes.append(code)
    assert {Status.OK, Status.INPUT_CLAMPED, Status.OUTSIDE_VELOCITY_TUBE} <= set(codes)


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_every_output_is_finite_whatever_the_inputs(tmp_path, tube, bounded,
                                                    precision) -> None:
    """Extreme finite inputs (states and times up to 1e30, ``alpha`` up to ``ALPHA_MAX``)
    and non-finite ones: every output finite, ``|u| <= input_bound``."""
    from stt_codegen.codegen.generate import input_limits
    lib, _ = _load(tmp_path, bounded, precision)
    step = _c_step(lib, precision)
    limits = input_limits(bounded)
    rng = np.random.default_rng(13)
    big = 1e30
    specials = [0.0, -0.0, 1e-30, -1e-30, big, -big, float("nan"), float("inf")]
    seen = set()
    for k in range(400):
        x = rng.choice(specials, 6) if k % 2 else rng.uniform(-1, 1, 6) * 10.0 ** rng.integers(-3, 30, 6)
        t = float(rng.choice([0.0, 1e-6, 5.0, 1e6, big, float("nan")]))
        dt = float(rng.choice([limits["dt_min"], 1e-3, limits["dt_max"], 0.0]))
        alpha = rng.choice([0.0, 1e-3, 10.0, limits["alpha_max"]], 6)
        code, u, alpha_next, r = step(x, t, dt, alpha)
        seen.add(code)
        assert all(np.all(np.isfinite(v)) for v in (u, alpha_next, r)), (x, t, dt, alpha)
        assert np.all(np.abs(u) <= np.array(bounded.input_bound, dtype=u.dtype))
    assert Status.INVALID_INPUT in seen and Status.OUTSIDE_TUBE in seen


def test_generated_python_with_a_bound_reports_input_clamped(tube, bounded) -> None:
    namespace: dict = {}
    exec(compile(cascade_python_file(bounded, STAGE, "cascade_test")["cascade_test.py"],
                 "cascade_test.py", "exec"), namespace)
    assert namespace["STATUS_INPUT_CLAMPED"] == Status.INPUT_CLAMPED
    p = _points(tube, 60, seed=14)
    expected = cascade_reference.cascade_step(bounded, STAGE, p["state"], p["t"], p["dt"],
                                              p["alpha"])
    statuses = []
    for k in range(60):
        u, _, status = namespace["step"](p["state"][k], p["t"][k], p["dt"][k],
                                         p["alpha"][k])
        assert status == step_status(Status.OK if expected[5][k] else Status.INPUT_CLAMPED,
                                     p["dt"][k], bounded.rate_hz)
        status = namespace["step"](p["state"][k], p["t"][k], namespace["PERIOD"],
                                   p["alpha"][k])[2]                  # the law's status
        np.testing.assert_allclose(u, expected[0][k], rtol=1e-10, atol=1e-12)
        statuses.append(status)
    assert len(set(statuses)) == 2


@pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_vectors_with_a_bound_cover_clamped_steps_and_the_c_meets_them(tmp_path, bounded,
                                                                       precision) -> None:
    """The oracle's vectors of a design with an actuator bound have clamped and unclamped
    steps; the C of either precision returns their statuses, and ``u``, ``r``,
    ``alpha_next`` within their tolerances."""
    from stt_codegen.codegen.cascade_source import cascade_vectors
    data = cascade_vectors(bounded, STAGE, precision=precision)
    statuses = [v["status"] for v in data["vectors"]]
    assert Status.INPUT_CLAMPED in statuses and Status.OK in statuses
    lib, _ = _load(tmp_path, bounded, precision)
    step = _c_step(lib, precision)
    for v in data["vectors"]:
        code, u, alpha_next, r = step(v["x"], v["t"], v["dt"], v["alpha"])
        assert code == v["status"]
        assert np.all(np.abs(u) <= np.array(bounded.input_bound, dtype=u.dtype))
        for got, name in ((u, "u"), (r, "r"), (alpha_next, "alpha_next")):
            assert np.all(np.abs(got - np.array(v[name])) <= np.array(v["tol_" + name])), name
