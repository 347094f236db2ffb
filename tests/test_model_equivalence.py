"""The CasADi model agrees with the numpy reference (issue: tube model, acceptance 2)."""

from __future__ import annotations

import numpy as np
from conftest import designed, model_of
from sampling import E_LIMIT, random_points

from stt_codegen.tube import reference as R
from stt_codegen.design.samples import sample_tube
from stt_codegen.tube.model import FUNCTION_NAMES

POINTS = 10_000
TOLERANCE = 1e-12


def reference_outputs(design, p):
    t, a, x, dt = p["t"], p["alpha"], p["x"], p["dt"]
    return {
        "reach_tube": R.reach_tube(design, t),
        "circumvent": R.circumvent(design, t),
        "tube": R.adaptive_tube(design, t, a),
        "adaptive_law": R.adaptive_law(design, t, a),
        "error_transform": R.error_transform(design, x, t, a),
        "control": (R.control(design, x, t, a),),
        "alpha_step": (R.alpha_step(design, t, dt, a),),
        "controller_step": R.controller_step(design, x, t, dt, a),
    }


def casadi_outputs(function, p):
    count = len(p["t"])
    inputs = [np.atleast_2d(p[name]) if p[name].ndim == 1 else p[name].T
              for name in function.name_in()]
    outputs = function.map(count)(*inputs)
    outputs = outputs if isinstance(outputs, (list, tuple)) else [outputs]
    return [np.array(o).T.reshape(count, -1) for o in outputs]


def test_points_are_strictly_inside_the_tube(case):
    _, design, _ = designed(case)
    p = random_points(design, 2000, seed=7)
    e, _, _, _ = R.error_transform(design, p["x"], p["t"], p["alpha"])
    assert np.abs(e).max() <= E_LIMIT + 1e-9
    psi = R.conflict_distance(design, p["t"])
    assert np.all(p["alpha"] >= 0) and np.all(psi + p["alpha"] > 0)


def test_every_function_matches_the_reference(case):
    _, design, _ = designed(case)
    model = model_of(case)
    assert tuple(model.functions) == FUNCTION_NAMES
    p = random_points(design, POINTS, seed=1)
    expected = reference_outputs(design, p)
    for name, function in model.functions.items():
        got = casadi_outputs(function, p)
        assert len(got) == len(expected[name]) == function.n_out()
        for k, (a, b) in enumerate(zip(got, expected[name])):
            b = np.asarray(b, dtype=float).reshape(len(p["t"]), -1)
            assert np.all(np.isfinite(a)), (name, function.name_out(k))
            bad = np.abs(a - b) > TOLERANCE * np.maximum(1.0, np.abs(b))
            assert not bad.any(), (
                f"{name}.{function.name_out(k)}: {bad.sum()} of {bad.size} entries differ, "
                f"worst {np.max(np.abs(a - b) / np.maximum(1, np.abs(b))):.3e}")


def test_controller_step_reports_outside_and_stays_finite(case):
    _, design, _ = designed(case)
    model = model_of(case)
    samples = sample_tube(design)
    k = int(np.searchsorted(samples.t, 2.0))
    t, alpha = samples.t[k], samples.alpha[k]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    for x in (g_u[0] + 1.0, g_l[0] - 1e-9, g_u[0], (g_l[0] + g_u[0]) / 2 + 1e6):
        u, alpha_next, inside = model["controller_step"](x, t, 1e-3, alpha)
        assert float(inside) == 0.0
        assert np.all(np.isfinite(np.array(u))) and np.all(np.isfinite(np.array(alpha_next)))
        u_ref, _, inside_ref = R.controller_step(design, x, t, 1e-3, alpha)
        assert inside_ref[0] == 0.0
        np.testing.assert_allclose(np.array(u).ravel(), u_ref[0], rtol=1e-12)
    u, _, inside = model["controller_step"]((g_l[0] + g_u[0]) / 2, t, 1e-3, alpha)
    assert float(inside) == 1.0
