"""Exact derivatives of the CasADi model against central finite differences of the reference."""

from __future__ import annotations

import numpy as np
from conftest import designed, model_of
from sampling import random_points

from stt_codegen.tube import reference as R


def central(f, x, h):
    """Central difference over the steps actually representable around ``x``."""
    up, down = x + h, x - h
    return (f(up) - f(down)) / (up - down)


def test_alpha_dot_jacobian_is_diagonal_and_matches_differences(case):
    _, design, _ = designed(case)
    model = model_of(case)
    import casadi as ca
    t = ca.SX.sym("t")
    a = ca.SX.sym("a", 2 * design.dimension)
    full = ca.jacobian(model["adaptive_law"](t, a)[0], a)
    assert full.sparsity().is_diag()
    p = random_points(design, 300, seed=3)
    for k in range(len(p["t"])):
        t_k, a_k = p["t"][k], p["alpha"][k]
        exact = np.array(model["adaptive_law"](t_k, a_k)[1]).ravel()
        z = R.conflict_distance(design, t_k)[0] + a_k
        h = 1e-6 * np.maximum(z, 1e-3)
        for i in range(a_k.size):
            def f(v, i=i):
                b = a_k.copy()
                b[i] = v
                return R.adaptive_law(design, t_k, b)[0][0, i]
            approx = central(f, a_k[i], h[i])
            assert abs(exact[i] - approx) <= 1e-5 * max(1.0, abs(approx)), (k, i)


def test_epsilon_jacobian_equals_diagonal_xi_and_differences(case):
    _, design, _ = designed(case)
    model = model_of(case)
    n = design.dimension
    p = random_points(design, 300, seed=4)
    for k in range(len(p["t"])):
        x, t, a = p["x"][k], p["t"][k], p["alpha"][k]
        e, _, xi, jac = (np.array(v).ravel() for v in model["error_transform"](x, t, a))
        jac = jac.reshape(n, n, order="F")
        # same quantity through two expression graphs: equal to rounding (the 1e-12)
        np.testing.assert_allclose(jac, np.diag(xi), rtol=1e-12, atol=0)
        g_l, g_u, _, _ = R.adaptive_tube(design, t, a)
        width = (g_u - g_l)[0]
        for i in range(n):
            h = 1e-5 * width[i] * (1 - abs(e[i]))  # ~cbrt(machine eps) of the local scale
            def f(v, i=i):
                y = x.copy()
                y[i] = v
                return R.error_transform(design, y, t, a)[1][0]
            col = central(f, x[i], h)
            np.testing.assert_allclose(col, jac[:, i], rtol=1e-5, atol=1e-6 * np.abs(jac).max())


def test_time_derivatives_match_differences(case):
    _, design, _ = designed(case)
    model = model_of(case)
    p = random_points(design, 300, seed=5)
    h = 1e-6
    for k in range(len(p["t"])):
        t, a = p["t"][k], p["alpha"][k]
        if abs(t - design.prescribed_time) < 10 * h or t < 10 * h:
            continue
        if any(abs(t - edge) < 10 * h for c in design.circumvents for edge in (c.start, c.end)):
            continue
        rho = [np.array(v).ravel() for v in model["reach_tube"](t)]
        beta = [np.array(v).ravel() for v in model["circumvent"](t)]
        fd_rho = central(lambda s: np.concatenate(R.reach_tube(design, s)[:2], axis=1)[0], t, h)
        fd_beta = central(lambda s: np.concatenate(R.circumvent(design, s)[:2], axis=1)[0], t, h)
        for exact, fd in ((np.concatenate(rho[2:]), fd_rho), (np.concatenate(beta[2:]), fd_beta)):
            np.testing.assert_allclose(exact, fd, rtol=1e-5, atol=1e-5 * max(1, np.abs(fd).max()))
        # gamma_dot is the total derivative along (11): difference gamma(t, alpha(t)) with
        # alpha advanced by its own rate (first order in h is enough at this tolerance).
        gam = [np.array(v).ravel() for v in model["tube"](t, a)]
        a_dot = R.adaptive_law(design, t, a)[0][0]
        def along(s):
            return np.concatenate(R.adaptive_tube(design, s, a + (s - t) * a_dot)[:2], axis=1)[0]
        fd = central(along, t, h)
        scale = max(1.0, np.abs(fd).max())
        # the second-order term alpha_ddot h^2 / 2 / (2h) is O(h) and bounded by the check
        np.testing.assert_allclose(np.concatenate(gam[2:]), fd, rtol=1e-4, atol=1e-4 * scale)
