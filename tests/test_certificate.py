"""The continuous-time tube certificate: sound enclosures, and catches what samples miss."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np
import pytest
from conftest import arena_toml, designed

from stt_codegen.rounding import round_down
from stt_codegen.tube import reference as R
from stt_codegen.design.certificate import certify_tube
from stt_codegen.design.search import base_design
from stt_codegen.spec.loader import parse_spec
from stt_codegen.design.samples import sample_tube


def test_bundled_tubes_are_certified(case):
    spec, design, _ = designed(case)
    cert = certify_tube(design, spec)
    assert cert.passed, cert.first_failure()
    names = [m.name for m in cert.margins]
    assert names[:3] == ["non-empty", "initial state inside", "inside state space"]
    assert names[-2:] == ["inside target after t_c", "sampling rate"]
    assert sum(n.startswith("avoids obstacle") for n in names) == 4
    # every t >= 0, on far fewer intervals than the 9000 samples up to t_c
    assert cert.horizon == np.inf and cert.intervals < 2000
    assert cert.enclosure.t_end[-1] == np.inf


@pytest.mark.parametrize("resumed", [False, True])
def test_enclosures_contain_the_deployed_tube(case, resumed):
    """Soundness: the deployed alpha (the controller's own steps) and gamma(t, alpha(t)) at
    random times, alpha interpolated between samples, lie in the certificate's enclosure:
    a fresh one, and the design search's (resumed from its candidates' certificates)."""
    spec, design, check = designed(case)
    enc = check.certificate.enclosure if resumed else certify_tube(design, spec).enclosure
    samples = sample_tube(design, 1.5 * design.prescribed_time)
    rng = np.random.default_rng(0)
    t = rng.uniform(0.0, samples.t[-1], 20_000)
    k = np.minimum(np.searchsorted(samples.t, t, side="right") - 1, samples.t.size - 2)
    frac = (t - samples.t[k]) / (samples.t[k + 1] - samples.t[k])
    alpha = (1 - frac)[:, None] * samples.alpha[k] + frac[:, None] * samples.alpha[k + 1]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    j = np.searchsorted(enc.t_start, t, side="right") - 1
    assert np.all(enc.t_start[j] <= t) and np.all(t <= enc.t_end[j])
    slack = 1e-9
    assert np.all(enc.alpha_min[j] - slack <= alpha) and np.all(alpha <= enc.alpha_max[j] + slack)
    assert np.all(enc.lower_min[j] - slack <= g_l) and np.all(g_l <= enc.lower_max[j] + slack)
    assert np.all(enc.upper_min[j] - slack <= g_u) and np.all(g_u <= enc.upper_max[j] + slack)
    assert np.all(enc.width_min[j] - slack <= g_u - g_l)
    assert np.all(enc.width_min >= enc.upper_min - enc.lower_max)
    # and the enclosures are not vacuous: their median width is a small part of the tube
    assert np.median(enc.lower_max - enc.lower_min) < 0.1


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
    cert = certify_tube(design, obstacle_spec)
    failure = cert.first_failure()                              # the certificate catches it
    assert failure is not None and failure.name == "avoids obstacle 0"
    assert "may meet obstacle 0" in failure.detail


def _fixed_point_cases():
    rng = np.random.default_rng(7)
    n = 400
    psi = np.concatenate([rng.uniform(-3, 5, n), rng.uniform(-1e-3, 1e-3, n),
                          10 ** rng.uniform(-14, 1, n), -10 ** rng.uniform(-14, 1, n)])
    theta = np.concatenate([0.02 / (1 + np.exp(2 * (psi[:2 * n] - 1))),
                            10 ** rng.uniform(-30, -1, 2 * n)])
    return psi, theta


@pytest.mark.parametrize("newton_steps", [None, 0])
def test_alpha_fixed_point_bracket_is_rigorous_and_tight(newton_steps, monkeypatch):
    """The Newton bracket of a* (kappa a = theta / (psi + a)^2) holds in 50-digit
    arithmetic: f >= 0 at lo (or lo on the pole), f <= 0 right of the pole at hi. With no
    plain Newton steps (0), every element takes the bracketed search."""
    mpmath = pytest.importorskip("mpmath")
    from stt_codegen.design.certificate import alpha_fixed_point, implicit_step
    if newton_steps is not None:
        monkeypatch.setattr(implicit_step, "FIXED_POINT_NEWTON_STEPS", newton_steps)
    mpmath.mp.dps = 50
    psi, theta = _fixed_point_cases()
    kappa = 5.0
    lo, hi = alpha_fixed_point(psi, theta, kappa)
    assert np.all(lo <= hi) and np.all(lo >= 0.0)
    assert np.all(hi - lo <= 1e-10 * hi + 1e-15)

    def f(a, p, t):
        return t / (p + a) ** 2 - kappa * a
    for p, t, a, b in zip(psi, theta, lo, hi):
        p, t, a, b = (mpmath.mpf(float(v)) for v in (p, t, a, b))
        assert p + a <= 0 or f(a, p, t) >= 0
        assert p + b > 0 and f(b, p, t) <= 0


def test_alpha_fixed_point_bracket_is_each_element_own():
    """On the range of psi and theta the tubes meet (the trigger's theta, psi from -3 to 5
    state units), an element's bracket of a* is the same to the bit alone as in any batch:
    the plain Newton steps act on each element by itself (no iteration count shared by the
    batch), so a partition's coefficients do not depend on which intervals are computed
    together."""
    from stt_codegen.design.certificate import alpha_fixed_point
    rng = np.random.default_rng(11)
    psi = rng.uniform(-3.0, 5.0, 400)
    theta = 0.02 / (1 + np.exp(2 * (psi - 1)))
    lo, hi = alpha_fixed_point(psi, theta, 5.0)
    for k in range(0, psi.size, 7):
        one_lo, one_hi = alpha_fixed_point(psi[k:k + 1], theta[k:k + 1], 5.0)
        assert one_lo[0].tobytes() == lo[k].tobytes() and one_hi[0].tobytes() == hi[k].tobytes()
    # beside elements of every other kind (_fixed_point_cases: psi near the pole, theta
    # down to 1e-30), which may take the bracketed search
    other_psi, other_theta = _fixed_point_cases()
    mixed_lo, mixed_hi = alpha_fixed_point(np.concatenate([psi, other_psi]),
                                           np.concatenate([theta, other_theta]), 5.0)
    assert mixed_lo[:psi.size].tobytes() == lo.tobytes()
    assert mixed_hi[:psi.size].tobytes() == hi.tobytes()


def test_step_root_bracket_is_rigorous():
    """step_root's bracket of the implicit step's root, checked in 50-digit arithmetic."""
    mpmath = pytest.importorskip("mpmath")
    from stt_codegen.design.certificate import step_root
    mpmath.mp.dps = 50
    rng = np.random.default_rng(3)
    for _ in range(2000):
        a = float(10 ** rng.uniform(-12, 0)) * float(rng.integers(0, 2))
        psi = float(rng.uniform(-2, 5))
        theta = float(0.02 / (1 + np.exp(2 * (psi - 1))))
        dt = float(10 ** rng.uniform(-5, 0))
        c = 1.0 + 5.0 * dt
        lo, hi = step_root(a, psi, theta, dt, c)
        assert lo <= hi

        def g(x):
            x = mpmath.mpf(x)
            return c * x - a - dt * theta / (psi + x) ** 2
        assert psi + lo <= 0 or g(lo) <= 0
        assert psi + hi > 0 and g(hi) >= 0


def _step_root_transcribed(a, psi, theta, dt, c):
    """step_root's Newton loop and bracket written plainly (the bracket in its own
    function), as a second reading of the hot loop's arithmetic."""
    from stt_codegen.design.certificate.implicit_step import STEP_ROOT_TOLERANCE

    def bracket(x, g, terms):
        slack = 1e-15 * (c * abs(x) + terms) / c
        lo, hi = (x - g / c, x) if g > 0.0 else (x, x - g / c)
        return lo - slack, hi + slack
    big_a = dt * theta
    if not big_a > 0.0:
        return a / c, a / c
    x = a
    for _ in range(6):
        z = psi + x
        if not z > 0.0:
            break
        g = c * x - a - big_a / (z * z)
        if abs(g) <= STEP_ROOT_TOLERANCE * c * x:
            return bracket(x, g, a + big_a / (z * z))
        x_next = x - g / (c + 2.0 * big_a / (z * z * z))
        if x_next == x:
            break
        x = x_next
    if not psi + x > 0.0:
        q = max(-c * psi - a, 1e-300)
        x = max(a / c, -psi + min((big_a / (2.0 * c)) ** (1.0 / 3.0),
                                  math.sqrt(big_a / (2.0 * q))))
        for _ in range(60):
            z = psi + x
            x_next = x - (c * x - a - big_a / (z * z)) / (c + 2.0 * big_a / (z * z * z))
            if not x_next > x:
                break
            x = x_next
    z = psi + x
    return bracket(x, c * x - a - big_a / (z * z), a + big_a / (z * z))


def test_step_root_is_its_transcription_to_the_last_bit():
    """The hot loop of step_root (bracket written out) gives the transcription's numbers
    exactly, on the Newton path and on the left start (psi + a <= 0)."""
    from stt_codegen.design.certificate import step_root
    rng = np.random.default_rng(5)
    left = 0
    for _ in range(5000):
        a = float(10 ** rng.uniform(-12, 0)) * float(rng.integers(0, 2))
        psi = float(rng.uniform(-2, 5))
        theta = float(0.02 / (1 + np.exp(2 * (psi - 1))))
        dt = float(10 ** rng.uniform(-5, 1))
        c = 1.0 + 5.0 * dt
        left += psi + a <= 0.0
        assert step_root(a, psi, theta, dt, c) == _step_root_transcribed(a, psi, theta, dt, c)
    assert left > 100        # the left start is exercised too


def test_point_tube_is_the_reference_tube(case):
    """The certificate's tube at points without rates (point_tube: the early failure test
    and the initial-state margin) is reference.adaptive_tube's gamma_L, gamma_U exactly."""
    from stt_codegen.design.certificate.report import point_tube
    spec, design, _ = designed(case)
    rng = np.random.default_rng(1)
    t = np.concatenate([[0.0], rng.uniform(0.0, 1.2 * design.prescribed_time, 500)])
    alpha = rng.uniform(0.0, 0.05, (t.size, 2 * design.dimension))
    for numpy_math in (False, True):
        with R.numpy_math() if numpy_math else contextlib.nullcontext():
            g_l, g_u = point_tube(design, t, alpha)
            ref_l, ref_u, _, _ = R.adaptive_tube(design, t, alpha)
        assert np.array_equal(g_l, ref_l) and np.array_equal(g_u, ref_u)


def test_sharpened_narrowest_width_is_sound_and_sharper(case):
    """The narrowest width the gain comes from: a lower bound of the deployed tube's width
    (alpha interpolated between samples, at 40 000 random times and at every sample),
    and no looser than the partition's own enclosure."""
    spec, design, check = designed(case)
    cert = check.certificate
    enc = cert.enclosure
    samples = sample_tube(design, 1.2 * design.prescribed_time)
    rng = np.random.default_rng(1)
    t = np.concatenate([samples.t, rng.uniform(0.0, samples.t[-1], 40_000)])
    k = np.minimum(np.searchsorted(samples.t, t, side="right") - 1, samples.t.size - 2)
    frac = (t - samples.t[k]) / (samples.t[k + 1] - samples.t[k])
    alpha = (1 - frac)[:, None] * samples.alpha[k] + frac[:, None] * samples.alpha[k + 1]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    true_min = float((g_u - g_l).min())
    assert cert.min_width <= true_min + 1e-12
    assert cert.min_width >= float((enc.upper_min - enc.lower_max).min())
    # the gains' width is the non-empty margin rounded down, the same on every CPU
    assert cert.min_width == round_down(cert.margin("non-empty").margin)


def test_numpy_math_is_per_thread():
    """The certificate's switch to numpy's ufuncs (reference.numpy_math) holds in its own
    thread only: another thread evaluating the oracle meanwhile keeps libm."""
    import math
    import threading
    # the oracle's libm exp is inf from 709 on (its overflow guard), numpy's is finite
    # up to 709.78: the last entry tells which one ran
    x = np.append(np.random.default_rng(5).uniform(-30.0, 30.0, 20_000), 709.5)
    libm = np.array([math.exp(v) if v < 709.0 else math.inf for v in x])
    assert np.isinf(libm[-1]) and np.isfinite(np.exp(x[-1]))
    inside, seen = threading.Event(), {}

    def other():
        inside.wait()
        seen["other"] = R.exp(x)
    thread = threading.Thread(target=other)
    thread.start()
    with R.numpy_math():
        inside.set()
        thread.join()
        seen["here"] = R.exp(x)
    assert np.array_equal(seen["other"], libm)
    assert np.array_equal(seen["here"], np.exp(x))
    assert np.array_equal(R.exp(x), libm)


def test_resume_state_is_typed_and_resuming_from_it_changes_nothing(case):
    """The refinement's end state (what the design search resumes from) is a frozen
    CertificateState: one entry per interval, and a certificate resumed from its own
    state at ``t = inf`` reuses it (only the tail ``[T, inf)`` is enclosed again, from
    the last interval's entry: its margins agree to rounding)."""
    from stt_codegen.design.certificate import CertificateState
    spec, design, _ = designed(case)
    certificate = certify_tube(design, spec)
    state = certificate.state
    assert isinstance(state, CertificateState)
    with pytest.raises(dataclasses.FrozenInstanceError):
        state.points = ()
    assert len(state.points) == certificate.intervals
    assert len(state.alpha_lo) == len(state.alpha_hi) == len(state.entries) == len(state.points)
    assert list(state.points) == sorted(set(state.points))
    again = certify_tube(design, spec, resume=(certificate, math.inf))
    assert again.intervals == certificate.intervals and again.work <= 2 < certificate.work
    assert again.state.points == state.points
    for m, n in zip(again.margins, certificate.margins):
        assert (m.name, m.passed) == (n.name, n.passed)
        assert m.margin == pytest.approx(n.margin, rel=1e-12, abs=1e-15)
