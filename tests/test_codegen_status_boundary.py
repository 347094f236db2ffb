"""Status OK means strictly inside the tube, C (double, single) and Python, every variant.

The old test ``|2 x - (gamma_U + gamma_L)| < gamma_U - gamma_L`` is rounded: on
omnirobot-s1 it reported OK for points exactly on a bound and for points one ulp outside.
Now ``gamma_L < p < gamma_U`` for the tube point ``p``, compared without rounding. Here
every point is built from the bounds the code itself computes in its own precision
(``P_tube``): on ``gamma_L`` / ``gamma_U`` exactly, one ulp inside and one ulp outside
(``numpy.nextafter`` in that precision), the other coordinates at the computed centre;
the state is the one whose tube point the code computes as exactly that point
(:meth:`hard_helpers.HardCase.exact_state`: the point itself; the cascade's positions,
with the velocity at the virtual velocity so that the velocity error is 0; the base
whose look-ahead point it is, heading 0). Only the points one ulp inside may report OK,
and they must (OK, or INPUT_CLAMPED under an actuator bound: inside, ``u`` clamped), at
``dt = PERIOD``; every API function taking ``x`` reports that status. At the points' own
``dt`` the step reports the same status, ``OFF_PERIOD`` in place of ``OK`` and
``INPUT_CLAMPED`` where ``dt`` is not the period, with the same ``u``. In double the
status and ``u`` also equal the variant's CasADi step (``inside*`` and ``within_bound``
outputs) bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from codegen_helpers import COMPILERS
from hard_helpers import c_api, hard_case, variant_params
from sampling import random_points
from test_model_equivalence import casadi_outputs

from stt_codegen.tube.parameters import step_status

#: (kind, expected status names): where the point lies relative to the bound. Strictly
#: inside is OK, or INPUT_CLAMPED where the header has an actuator bound (inside, u clamped).
KINDS = (("on", ("OUTSIDE_TUBE",)), ("inside", ("OK", "INPUT_CLAMPED")),
         ("outside", ("OUTSIDE_TUBE",)))


def _codes(case, names) -> list[int]:
    """The header's codes of the status names it defines."""
    return [case.statuses[name] for name in names if name in case.statuses]

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc, clang)")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("status-boundary"))


def boundary_points(n, g_l, g_u, dtype):
    """Points on, one ulp inside and one ulp outside each bound, in ``dtype``.

    ``g_l``, ``g_u``: (N, n) bounds computed in that precision. Returns ``(index, p,
    kind)``: the row of the bounds each point belongs to, the tube points (M, n) and the
    index into :data:`KINDS` (M,).
    """
    g_l, g_u = g_l.astype(dtype), g_u.astype(dtype)
    centre = g_l + (g_u - g_l) / dtype(2)
    rows, ps, kinds = [], [], []
    for r in range(len(g_l)):
        if not np.all((g_l[r] < centre[r]) & (centre[r] < g_u[r])):
            continue
        for i in range(n):
            for bound, towards_inside in ((g_l[r, i], g_u[r, i]), (g_u[r, i], g_l[r, i])):
                away = dtype(np.inf) if towards_inside < bound else dtype(-np.inf)
                for j, (kind, _) in enumerate(KINDS):
                    value = {"on": bound, "inside": np.nextafter(bound, towards_inside),
                             "outside": np.nextafter(bound, away)}[kind]
                    p = centre[r].copy()
                    p[i] = value
                    rows.append(r)
                    ps.append(p)
                    kinds.append(j)
    return np.array(rows), np.array(ps, dtype=dtype), np.array(kinds)


def _c_bounds(lib, case, p):
    count, n = len(p["t"]), case.n
    g_l = np.zeros((count, n), lib.dtype)
    g_u = np.zeros((count, n), lib.dtype)
    for k in range(count):
        gl, gu = lib.arr(None, n), lib.arr(None, n)
        assert lib.call("tube", t=lib.dtype(p["t"][k]), alpha=lib.arr(p["alpha"][k]),
                        gamma_L=gl, gamma_U=gu, gamma_L_dot=None, gamma_U_dot=None) \
            == case.statuses["OK"]
        g_l[k], g_u[k] = gl, gu
    return g_l, g_u


def _c_velocity(lib, t, a):
    """The C's virtual velocity at a state (the cascade's ``P_virtual_velocity``)."""
    def velocity(x):
        r = lib.nan("N")
        lib.call("virtual_velocity", x=lib.arr(x), t=t, alpha=a, r=r)
        return r
    return velocity


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", variant_params())
def test_c_reports_ok_only_strictly_inside(variant, precision, root):
    case = hard_case(variant)
    lib = c_api(case, precision, COMPILERS[0], root)
    st, n, count = case.statuses, case.n, 150
    p = random_points(case.tube, count, seed=23)
    rows, points, kinds = boundary_points(n, *_c_bounds(lib, case, p), lib.dtype)
    assert len(rows) > 0.9 * 6 * n * count  # nearly every row usable
    others = [name for name, args in case.functions.items()
              if name != "step" and any(a.name == "x" for a in args)]
    used, states, status, u_all = [], [], [], []
    for k, r in enumerate(rows):
        t, dt = lib.dtype(p["t"][r]), lib.dtype(p["dt"][r])
        a = lib.arr(p["alpha"][r])
        x = case.exact_state(points[k], lib.dtype, _c_velocity(lib, t, a))
        if x is None:
            continue
        u, nxt = lib.nan("N_INPUT"), lib.nan("N_ALPHA")
        s = lib.call("step", x=lib.arr(x), t=t, dt=lib.dtype(1.0 / case.tube.rate_hz),
                     alpha=a, u=u, alpha_next=nxt)
        u_dt = lib.nan("N_INPUT")
        s_dt = lib.call("step", x=lib.arr(x), t=t, dt=dt, alpha=a, u=u_dt, alpha_next=nxt)
        assert s_dt == step_status(s, dt, case.tube.rate_hz), (k, s, s_dt)
        assert np.array_equal(u_dt, u), k
        for name in others:                      # P_control, P_virtual_velocity
            outs = {b.name: lib.nan(b.size) for b in case.functions[name] if b.kind == "out"}
            assert lib.call(name, x=lib.arr(x), t=t, alpha=a, **outs) == s, (name, k)
            if "u" in outs:
                assert np.array_equal(outs["u"], u), (name, k)
        used.append(k)
        states.append(x)
        status.append(s)
        u_all.append(u)
    assert len(used) > 0.9 * len(rows), (len(used), len(rows))   # nearly every point placed
    used, status = np.array(used), np.array(status)
    for j, (kind, want) in enumerate(KINDS):
        sel = kinds[used] == j
        wrong = int(np.sum(~np.isin(status[sel], _codes(case, want))))
        assert sel.sum() > 0 and wrong == 0, \
            f"{wrong} of {int(sel.sum())} points {kind} a bound: other status"
    if precision == "double":
        step = case.casadi_step()
        got = casadi_outputs(step, {"x": np.array(states), "t": p["t"][rows[used]],
                                    "dt": p["dt"][rows[used]],
                                    "alpha": p["alpha"][rows[used]]})
        flag = {name: got[j][:, 0] == 1.0 for j, name in enumerate(step.name_out())}
        inside = np.all([v for name, v in flag.items() if name.startswith("inside")], axis=0)
        within = flag.get("within_bound", np.ones(len(used), bool))
        expected = np.where(~inside, st["OUTSIDE_TUBE"],
                            np.where(within, st["OK"], st.get("INPUT_CLAMPED", -1)))
        assert np.array_equal(got[0], np.array(u_all))
        assert np.array_equal(expected, status)


@pytest.mark.parametrize("variant", variant_params())
def test_python_reports_ok_only_strictly_inside(variant, root):
    """The Python module on the bounds it computes (its ``tube``; the double C's where it
    has none), the cascade's velocity its ``virtual_velocity`` (else the double C's)."""
    case = hard_case(variant)
    module = case.python()
    lib = c_api(case, "double", COMPILERS[0], root)
    p = random_points(case.tube, 20, seed=29)
    if hasattr(module, "tube"):
        bounds = [module.tube(float(p["t"][r]), list(p["alpha"][r])) for r in range(20)]
        assert all(b[-1] == case.statuses["OK"] for b in bounds)
        g_l, g_u = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    else:
        g_l, g_u = _c_bounds(lib, case, p)
    rows, points, kinds = boundary_points(case.n, g_l, g_u, np.float64)
    assert len(rows) == 6 * case.n * 20
    placed = 0
    for k, r in enumerate(rows):
        t, alpha = float(p["t"][r]), list(p["alpha"][r])
        if hasattr(module, "virtual_velocity"):
            def velocity(x):
                return np.array(module.virtual_velocity(list(x), t, alpha)[0])
        else:
            velocity = _c_velocity(lib, t, lib.arr(alpha))
        x = case.exact_state(points[k], np.float64, velocity)
        if x is None:
            continue
        u, _, status = module.step([float(v) for v in x], t, module.PERIOD, alpha)
        assert status in _codes(case, KINDS[kinds[k]][1]), (KINDS[kinds[k]][0], k, status)
        u_dt, _, status_dt = module.step([float(v) for v in x], t, float(p["dt"][r]), alpha)
        assert status_dt == step_status(status, p["dt"][r], case.tube.rate_hz), (k, status_dt)
        assert u_dt == u, k
        placed += 1
    assert placed > 0.9 * len(rows)
