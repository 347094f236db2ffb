"""Status OK means strictly inside the tube, C (double, single) and Python.

The old test ``|2 x - (gamma_U + gamma_L)| < gamma_U - gamma_L`` is rounded: on
omnirobot-s1 it reported OK for points exactly on a bound and for points one ulp outside.
Now ``gamma_L < x < gamma_U``, compared without rounding. Here every point is built from
the bounds the code itself computes in its own precision (``P_tube``): on ``gamma_L`` /
``gamma_U`` exactly, one ulp inside and one ulp outside (``numpy.nextafter`` in that
precision), the other coordinates at the computed centre. Only the points one ulp inside
may report OK, and they must. In double the status and ``u`` also equal the CasADi model's
``inside`` and ``u`` bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import designed, model_of
from sampling import random_points
from codegen_helpers import COMPILERS, built, files_of
from test_model_equivalence import casadi_outputs

from stt_codegen.runtime.compiled import load_python_module

CASE = "omnirobot-s1"
OK, OUTSIDE = 0, 1
#: (kind, expected status): where the point lies relative to the bound.
KINDS = (("on", OUTSIDE), ("inside", OK), ("outside", OUTSIDE))

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc, clang)")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("status-boundary"))


def boundary_points(design, g_l, g_u, dtype):
    """Points on, one ulp inside and one ulp outside each bound, in ``dtype``.

    ``g_l``, ``g_u``: (N, n) bounds computed in that precision. Returns ``(index, x,
    expected)``: the row of the bounds each point belongs to, the states (M, n) and the
    expected status (M,).
    """
    g_l, g_u = g_l.astype(dtype), g_u.astype(dtype)
    centre = g_l + (g_u - g_l) / dtype(2)
    rows, xs, expected = [], [], []
    for r in range(len(g_l)):
        if not np.all((g_l[r] < centre[r]) & (centre[r] < g_u[r])):
            continue
        for i in range(design.dimension):
            for bound, towards_inside in ((g_l[r, i], g_u[r, i]), (g_u[r, i], g_l[r, i])):
                away = dtype(np.inf) if towards_inside < bound else dtype(-np.inf)
                for kind, status in KINDS:
                    value = {"on": bound, "inside": np.nextafter(bound, towards_inside),
                             "outside": np.nextafter(bound, away)}[kind]
                    x = centre[r].copy()
                    x[i] = value
                    rows.append(r)
                    xs.append(x)
                    expected.append(status)
    return np.array(rows), np.array(xs, dtype=dtype), np.array(expected)


def _tube_and_points(lib, design, count, seed):
    p = random_points(design, count, seed=seed)
    n = design.dimension
    g_l = np.zeros((count, n), lib.dtype)
    g_u = np.zeros((count, n), lib.dtype)
    for k in range(count):
        a = lib.arr(p["alpha"][k])
        gl, gu = lib.arr(None, n), lib.arr(None, n)
        assert lib.f["tube"](float(lib.dtype(p["t"][k])), lib.ptr(a), lib.ptr(gl), lib.ptr(gu),
                             None, None) == OK
        g_l[k], g_u[k] = gl, gu
    rows, x, expected = boundary_points(design, g_l, g_u, lib.dtype)
    assert len(rows) > 0.9 * 6 * n * count  # nearly every row usable
    return p, rows, x, expected


@pytest.mark.parametrize("precision", ["double", "single"])
def test_c_reports_ok_only_strictly_inside(precision, root):
    _, design, _ = designed(CASE)
    lib = built(CASE, precision, COMPILERS[0], root)
    p, rows, x, expected = _tube_and_points(lib, design, 150, seed=23)
    n = design.dimension
    status = np.zeros(len(rows), int)
    control_status = np.zeros(len(rows), int)
    u_all = np.zeros((len(rows), n))
    for k, r in enumerate(rows):
        t, dt = float(lib.dtype(p["t"][r])), float(lib.dtype(p["dt"][r]))
        xa, a = lib.arr(x[k]), lib.arr(p["alpha"][r])
        u, nxt = lib.arr(None, n), lib.arr(None, 2 * n)
        status[k] = lib.f["step"](lib.ptr(xa), t, dt, lib.ptr(a), lib.ptr(u), lib.ptr(nxt))
        u_all[k] = u
        u2 = lib.arr(None, n)
        control_status[k] = lib.f["control"](lib.ptr(xa), t, lib.ptr(a), lib.ptr(u2))
        assert np.array_equal(u, u2)
    for kind, want in KINDS:
        sel = np.array([KINDS[k % 3][0] == kind for k in range(len(rows))])
        assert np.all(expected[sel] == want)
        wrong = int(np.sum(status[sel] != want))
        assert wrong == 0, f"{wrong} of {int(sel.sum())} points {kind} a bound: other status"
    assert np.array_equal(control_status, status)
    if precision == "double":
        step = model_of(CASE)["controller_step"]
        got = casadi_outputs(step, {"x": x, "t": p["t"][rows], "dt": p["dt"][rows],
                                    "alpha": p["alpha"][rows]})
        assert np.array_equal(got[0], u_all)
        assert np.array_equal(np.where(got[2][:, 0] == 1.0, OK, OUTSIDE), status)


def test_python_reports_ok_only_strictly_inside():
    spec, design, _ = designed(CASE)
    module = load_python_module(files_of(CASE, "double")[f"{spec.c_name}.py"], spec.c_name)
    p = random_points(design, 20, seed=29)
    bounds = [module.tube(float(p["t"][r]), list(p["alpha"][r])) for r in range(20)]
    assert all(b[4] == OK for b in bounds)
    g_l = np.array([b[0] for b in bounds])
    g_u = np.array([b[1] for b in bounds])
    rows, x, expected = boundary_points(design, g_l, g_u, np.float64)
    assert len(rows) == 6 * design.dimension * 20
    for k, r in enumerate(rows):
        _, _, status = module.step(list(x[k]), float(p["t"][r]), float(p["dt"][r]),
                                   list(p["alpha"][r]))
        assert status == expected[k], (KINDS[k % 3][0], k)
