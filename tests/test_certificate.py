"""The continuous-time tube certificate: sound enclosures, and catches what samples miss."""

from __future__ import annotations

import numpy as np
from conftest import arena_toml, designed

from stt_codegen.tube import reference as R
from stt_codegen.design.certificate import certify_tube, enclose_tube
from stt_codegen.design.search import base_design
from stt_codegen.spec.loader import parse_spec
from stt_codegen.design.samples import sample_tube


def test_bundled_tubes_are_certified(case):
    spec, design, _ = designed(case)
    cert = certify_tube(design, spec)
    assert cert.passed, cert.first_failure()
    names = [m.name for m in cert.margins]
    assert names[:3] == ["non-empty", "initial state inside", "inside state space"]
    assert names[-1] == "inside target after t_c"
    assert sum(n.startswith("avoids obstacle") for n in names) == 4
    assert cert.horizon >= spec.prescribed_time and cert.intervals >= 9000


def test_enclosures_contain_the_tube_between_samples(case):
    """Soundness: gamma(t, alpha(t)) at random times inside each interval lies in its enclosure."""
    _, design, _ = designed(case)
    samples = sample_tube(design)
    enc = enclose_tube(design, samples)
    rng = np.random.default_rng(0)
    k = rng.integers(0, enc.t_start.size, 20_000)
    frac = rng.random(k.size)
    t = enc.t_start[k] + frac * (enc.t_end[k] - enc.t_start[k])
    alpha = (1 - frac)[:, None] * samples.alpha[k] + frac[:, None] * samples.alpha[k + 1]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    slack = 1e-12
    assert np.all(enc.lower_min[k] - slack <= g_l) and np.all(g_l <= enc.lower_max[k] + slack)
    assert np.all(enc.upper_min[k] - slack <= g_u) and np.all(g_u <= enc.upper_max[k] + slack)
    # and they are tight: the enclosure width is of the order of one step's motion
    assert np.median(enc.lower_max - enc.lower_min) < 1e-2


CORNER = arena_toml("corner", 4.0, "[controller]\nrate_hz = 50.0\n")


def test_an_obstacle_clipped_between_samples_is_caught():
    """A 0.1 mm obstacle that the tube's corner clips for less than one 20 ms period."""
    from stt_codegen.spec.loader import Box
    spec = parse_spec(CORNER)
    design = base_design(spec)
    samples = sample_tube(design)
    g_l, g_u = samples.gamma_lower, samples.gamma_upper
    # dense evaluation of the tube (1e-5 s) with alpha interpolated as certified
    t = np.arange(0.0, samples.t[-1], 1e-5)
    alpha = np.column_stack([np.interp(t, samples.t, a) for a in samples.alpha.T])
    d_l, d_u, _, _ = R.adaptive_tube(design, t, alpha)
    # the corner (gamma_U_1, gamma_L_2) at a time midway between two samples
    k = int(np.searchsorted(t, samples.t[60] + 0.01))
    corner = (float(d_u[k, 0]) - 2e-4, float(d_l[k, 1]) - 1e-4)
    box = Box(corner, (corner[0] + 1e-4, corner[1] + 1e-4))
    hit_dense = np.all((d_l <= box.upper) & (d_u >= box.lower), axis=1)
    hit_samples = np.all((g_l <= box.upper) & (g_u >= box.lower), axis=1)
    assert hit_dense.any() and hit_dense.sum() * 1e-5 < 0.02   # met, for less than a period
    assert not hit_samples.any()                                # every sample misses it
    obstacle_spec = parse_spec(CORNER + f"""
[[obstacles]]
lower = [{box.lower[0]!r}, {box.lower[1]!r}]
upper = [{box.upper[0]!r}, {box.upper[1]!r}]
""")
    cert = certify_tube(design, obstacle_spec, samples=samples)
    failure = cert.first_failure()                              # the certificate catches it
    assert failure is not None and failure.name == "avoids obstacle 0"
    assert "may meet obstacle 0" in failure.detail
