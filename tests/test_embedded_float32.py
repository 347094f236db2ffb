"""Float32 safety of the single-precision C on the host (gcc -O2, fenv flags, UBSan).

Adversarial inputs (stt_codegen.embedded.fpsafety.adversarial_inputs): t at 0, tiny,
t_c -+ ulps, 100 t_c and at every circumvent window edge -+ ulps; alpha from 0 to 1e6 and
on the adaptive law's domain boundary; dt from 1e-6 to 1; states inside, on and outside
the tube.
"""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest

from conftest import CASES, designed
from stt_codegen.embedded.fpsafety import _ulps, adversarial_inputs, check_host


@pytest.fixture(scope="module", autouse=True)
def _gcc() -> None:
    if shutil.which("gcc") is None:
        pytest.skip("host C compiler missing: install the Debian package gcc")


# S1 (with the sanitizers) in the fast tier; S2 and S3 in the slow one
@pytest.mark.parametrize("case", [CASES[0]] + [pytest.param(c, marks=pytest.mark.slow)
                                                for c in CASES[1:]])
def test_no_overflow_or_invalid_on_adversarial_inputs(case, tmp_path) -> None:
    spec, design, _ = designed(case)
    r = check_host(spec, design, tmp_path, sanitize=(case == CASES[0]))
    assert r["count"] > 10000
    # In the domain of the adaptive law (psi + alpha > 0 at the float code's psi) nothing
    # raises; the only flags come from alpha = -psi + 1 ulp where the float psi differs
    # from the double one (psi + alpha = 0: the law's pole), in P_tube's derivatives.
    bad = [e for e in r["raised"] if "alpha=-psi+" not in e["what"]]
    assert bad == [], bad[:5]
    assert all(not e["step"] for e in r["raised"]), r["raised"][:5]
    assert r["sanitizer"] in ("clean", "not run"), r["sanitizer"]
    # the single-precision bound holds on every adversarial input inside the tube
    b = r["bounded"]
    assert b["count"] > 1000 and b["status_mismatches"] == 0
    assert all(v <= 1.0 for v in b["error_to_bound"].values()), b["error_to_bound"]


def _edge_inputs(design, c):
    n = design.dimension
    rows = {"x": [], "t": [], "dt": [], "alpha": [], "what": []}
    from stt_codegen.tube import reference as R
    for edge in (c.start, c.end):
        for k in range(-4, 5):
            t = _ulps(edge, k)
            alpha = np.zeros((1, 2 * n))
            g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t]), alpha)
            rows["x"].append(np.float32((g_l[0] + g_u[0]) / 2).astype(float))
            rows["t"].append(t)
            rows["dt"].append(float(np.float32(1e-3)))
            rows["alpha"].append(alpha[0])
            rows["what"].append(f"edge {edge:.6g} {k:+d}ulp")
    return {k: (np.array(v) if k != "what" else v) for k, v in rows.items()}


def test_bump_denominator_positive_inside_window(tmp_path) -> None:
    """Regression: with r^2 - (t-m)^2 the float32 denominator was exactly 0 at the window's
    edge ulp (FE_DIVBYZERO in the step, NaN gamma_dot); (r - |d|)(r + |d|) is not."""
    spec, design, _ = designed("omnirobot-s1")
    # a radius/centre (found by a float32 scan) where fl(r^2) == fl(d^2) with |d| < fl(r)
    r, m = 5.691208622368032, 3.0031455909313767
    c = dataclasses.replace(design.circumvents[0], start=m - r, end=m + r)
    crafted = dataclasses.replace(design, circumvents=(c,))
    rep = check_host(spec, crafted, tmp_path, sanitize=False,
                     inputs=_edge_inputs(crafted, c))
    assert rep["raised"] == [], rep["raised_summary"]


def test_adversarial_inputs_cover_the_edges() -> None:
    spec, design, _ = designed("omnirobot-s1")
    p = adversarial_inputs(design)
    t_c = np.float32(design.prescribed_time)
    assert np.float32(t_c) in p["t"] and np.nextafter(t_c, np.float32(0)) in p["t"]
    assert np.nextafter(t_c, np.float32(20)) in p["t"] and 0.0 in p["t"]
    for c in design.circumvents:
        for edge in (c.start, c.end):
            e = np.float32(edge)
            assert e in p["t"] and np.nextafter(e, np.float32(-1e9)) in p["t"]
    assert p["dt"].min() == np.float32(1e-6) and p["dt"].max() == 1.0
    assert p["alpha"].max() == 1e6 and p["alpha"].min() == 0.0
