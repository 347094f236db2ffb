"""Test vectors: inputs and expected outputs from the numpy reference, with tolerances.

The inputs are float32 numbers (exact in both precisions), drawn with a fixed seed:
:data:`INSIDE` points with ``|e_i| <= 0.99`` in tubes at least 1e-2 wide (so that the
status is the same in single precision, see
:func:`~stt_codegen.codegen.tolerance.status_certain`), and :data:`OUTSIDE` points with
``1.1 <= |e_i| <= 2`` in one dimension (status OUTSIDE_TUBE, ``u`` clamped); times
cover ``[0, 1.2 t_c]``, so after ``t_c`` too. Expected values are the reference's
(:mod:`stt_codegen.tube.reference`) at those inputs; tolerances are
:mod:`~stt_codegen.codegen.tolerance`'s bounds for the chosen precision (double: with the
floor ``1e-12 max(1, |ref|)``).
"""

from __future__ import annotations

import numpy as np

from ..tube import reference as R
from ..tube.parameters import STATUS_OK, STATUS_OUTSIDE_TUBE
from ..tube.parameters import TubeDesign
from . import tolerance as T

INSIDE = 48
OUTSIDE = 8
SEED = 20240531


def _f32(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def sample_inputs(design: TubeDesign) -> dict[str, np.ndarray]:
    """The vectors' inputs: ``x`` (N, n), ``t`` (N,), ``dt`` (N,), ``alpha`` (N, 2n)."""
    rng = np.random.default_rng(SEED)
    n = design.dimension
    t_c = design.prescribed_time
    chosen = {k: [] for k in ("x", "t", "dt", "alpha")}
    want = {False: INSIDE, True: OUTSIDE}
    have = {False: 0, True: 0}
    while have[False] < INSIDE or have[True] < OUTSIDE:
        m = 64
        t = _f32(rng.uniform(0.0, 1.2 * t_c, m))
        psi = R.conflict_distance(design, t)
        alpha = _f32(np.maximum(0.0, -psi + 1e-2)
                     + rng.exponential(0.05, psi.shape) * (rng.random(psi.shape) < 0.7))
        dt = _f32(rng.choice([1e-4, 1e-3, 1e-2], m))
        outside = rng.random(m) < 0.3
        e = rng.uniform(-0.99, 0.99, (m, n))
        k = rng.integers(0, n, m)
        far = rng.uniform(1.1, 2.0, m) * rng.choice([-1.0, 1.0], m)
        e[outside, k[outside]] = far[outside]
        g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
        x = _f32(((g_u - g_l) * e + (g_u + g_l)) / 2)
        ok = (np.all(g_u - g_l >= 1e-2, axis=1) & np.all(psi + alpha > 0, axis=1)
              & T.status_certain(design, x, alpha, g_l, g_u, T.UNIT_SINGLE))
        _, _, inside = R.controller_step(design, x, t, dt, alpha)
        for i in np.flatnonzero(ok):
            kind = bool(inside[i] == 0.0)
            if kind != bool(outside[i]) or have[kind] >= want[kind]:
                continue
            have[kind] += 1
            for key, value in (("x", x), ("t", t), ("dt", dt), ("alpha", alpha)):
                chosen[key].append(value[i])
    return {k: np.array(v) for k, v in chosen.items()}


def test_vectors(design: TubeDesign, precision: str) -> dict:
    """Inputs, expected outputs and tolerances of every vector, as JSON-ready lists.

    Returns
    -------
    dict
        Keys ``x``, ``t``, ``dt``, ``alpha`` (inputs); ``u``, ``alpha_next``, ``status``,
        ``gamma_L``, ``gamma_U`` (reference); ``tol_u``, ``tol_alpha_next``,
        ``tol_gamma`` (absolute tolerances, same shapes); ``unit_roundoff``.
    """
    p = sample_inputs(design)
    x, t, dt, alpha = p["x"], p["t"], p["dt"], p["alpha"]
    u, alpha_next, inside = R.controller_step(design, x, t, dt, alpha)
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    unit = T.unit_roundoff(precision)
    tol_u = T.u_bound(design, x, alpha, g_l, g_u, u, unit)
    tol_a = T.alpha_bound(design, alpha, alpha_next, unit)
    tol_g = np.broadcast_to(T.gamma_bound(design, alpha, unit), g_l.shape)
    if precision == "double":
        tol_u = T.with_double_floor(tol_u, u)
        tol_a = T.with_double_floor(tol_a, alpha_next)
        tol_g = T.with_double_floor(tol_g, np.maximum(np.abs(g_l), np.abs(g_u)))
    status = np.where(inside == 1.0, STATUS_OK, STATUS_OUTSIDE_TUBE)

    def rows(a):
        return [[float(v) for v in row] for row in np.asarray(a)]

    return {
        "x": rows(x), "t": [float(v) for v in t], "dt": [float(v) for v in dt],
        "alpha": rows(alpha), "u": rows(u), "alpha_next": rows(alpha_next),
        "status": [int(s) for s in status], "gamma_L": rows(g_l), "gamma_U": rows(g_u),
        "tol_u": rows(tol_u), "tol_alpha_next": rows(tol_a), "tol_gamma": rows(tol_g),
        "unit_roundoff": unit,
    }


test_vectors.__test__ = False  # not a pytest test
