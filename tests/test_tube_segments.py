"""Piecewise reach tube and the eq. (9) combination over open circumvents."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen.tube import reference as R
from stt_codegen.tube.model import build_model
from stt_codegen.tube.parameters import (CRUISE, CRUISE_RAMP, GLIDE, LOWER, SCURVE, SCURVE_TURN,
                                         SMOOTHSTEP, TANH, UPPER, Circumvent, ReachSegment,
                                         TubeDesign, peak_rate_factor)

TOLERANCE = 1e-12


def piecewise_design(profile: str = SMOOTHSTEP) -> TubeDesign:
    boxes = [((0.1, 0.1), (0.5, 0.5)), ((0.1, 2.0), (0.5, 2.4)), ((2.0, 2.0), (2.4, 2.4)),
             ((4.5, 4.5), (4.9, 4.9))]
    times = [0.0, 2.0, 5.0, 8.0]
    segments = tuple(ReachSegment(times[k], times[k + 1], boxes[k][0], boxes[k][1],
                                  boxes[k + 1][0], boxes[k + 1][1], profile)
                     for k in range(3))
    circumvents = (Circumvent(0, 0, LOWER, 1.0, 3.0, 0.8, 0.0, 0.1),
                   Circumvent(1, 0, LOWER, 2.5, 4.0, 1.1, 0.0, 0.3),
                   Circumvent(2, 1, UPPER, 6.0, 9.0, 0.4, 5.0, 0.05))
    return TubeDesign(name="piecewise", prescribed_time=9.0, state_lower=(0.0, 0.0),
                      state_upper=(5.0, 5.0), segments=segments, initial_state=(0.3, 0.3),
                      circumvents=circumvents, smoothness=50.0, theta0=0.01, kappa=5.0,
                      mu=1.0, gain=0.2, rate_hz=1000.0)


def times() -> np.ndarray:
    rng = np.random.default_rng(3)
    edges = np.array([0.0, 2.0, 5.0, 8.0, 1.0, 3.0, 2.5, 4.0, 6.0, 9.0])
    near = np.concatenate([edges + d for d in (-1e-9, 0.0, 1e-9)])
    return np.sort(np.concatenate([rng.uniform(-1.0, 12.0, 2000), near]))


@pytest.mark.parametrize("profile", [SMOOTHSTEP, TANH, CRUISE, SCURVE])
def test_model_matches_reference_on_segments_and_open_circumvents(profile):
    design = piecewise_design(profile)
    model = build_model(design)
    t = times()
    for name, expected in (("reach_tube", R.reach_tube(design, t)),
                           ("circumvent", R.circumvent(design, t))):
        got = model[name].map(t.size)(t[None, :])
        for a, b in zip(got, expected):
            a = np.array(a).T
            assert np.all(np.abs(a - b) <= TOLERANCE * np.maximum(1.0, np.abs(b))), name


@pytest.mark.parametrize("profile", [SMOOTHSTEP, CRUISE, SCURVE])
def test_reach_tube_and_its_rate_are_continuous_at_every_via_point(profile):
    design = piecewise_design(profile)
    for seg in design.segments:
        for when in (seg.start, seg.end):
            before = R.reach_tube(design, [when - 1e-9])
            after = R.reach_tube(design, [when + 1e-9])
            for a, b in zip(before, after):
                assert np.max(np.abs(a - b)) < 1e-6, when
    # far from the ends the rate is not zero: the test above can fail
    assert np.max(np.abs(R.reach_tube(design, [1.0])[2])) > 0.1


@pytest.mark.parametrize("profile", [SMOOTHSTEP, CRUISE, SCURVE, GLIDE])
def test_smooth_profile_peak_rate_and_its_second_derivative(profile):
    """The CasADi model's p_dot peaks at peak_rate_factor times the mean (1.875 for the
    smooth step, 1 / (1 - ramp) = 1.25 for the cruise, held over the whole cruise, 2 for
    the S-curve); p_ddot (from the model's p_dot) is continuous, 0 at both ends, and p is
    monotone; the S-curve's p_ddot peaks at 4 / (1 - 2 q) / duration^2, below the quintic's
    10 / sqrt(3)."""
    from stt_codegen.tube.pieces import progress
    start, end = 1.0, 5.0
    t = np.linspace(start - 0.5, end + 0.5, 200001)
    p, p_dot = (np.array(v).ravel() for v in progress(profile).map(t.size)(t[None, :], start, end))
    mean = 1.0 / (end - start)
    assert abs(p_dot.max() / mean - peak_rate_factor(profile)) < 1e-9
    assert np.all(np.diff(p) >= 0.0) and p[0] == 0.0 and p[-1] == 1.0
    p_ddot = np.diff(p_dot) / np.diff(t)
    assert np.max(np.abs(np.diff(p_ddot))) < 1e-3 * np.max(np.abs(p_ddot))   # no jump
    assert np.max(np.abs(p_ddot[np.abs(t[1:] - start) < 1e-3])) < 1e-2
    assert np.max(np.abs(p_ddot[np.abs(t[1:] - end) < 1e-3])) < 1e-2
    if profile == CRUISE:
        tau = (t - start) / (end - start)
        cruise = (tau > CRUISE_RAMP + 1e-6) & (tau < 1.0 - CRUISE_RAMP - 1e-6)
        assert np.all(np.abs(p_dot[cruise] / mean - 1.25) < 1e-12)
        assert peak_rate_factor(CRUISE) == 1.25 and CRUISE_RAMP == 0.2
        # a ramp covers half its length at the cruise rate: p(ramp) = 1.25 * 0.2 / 2
        (at_ramp,) = np.array(progress(CRUISE, False)(start + CRUISE_RAMP * (end - start),
                                                       start, end)).ravel()
        assert abs(at_ramp - 0.125) < 1e-15
    if profile == SCURVE:
        peak = 4.0 / (1.0 - 2.0 * SCURVE_TURN) * mean**2
        assert abs(np.max(np.abs(p_ddot)) - peak) < 1e-6 * peak
        assert peak < 10.0 / math.sqrt(3.0) * mean**2 * 0.83


def test_reach_tube_holds_its_boxes_outside_the_segments():
    design = piecewise_design(SMOOTHSTEP)
    rho_l, rho_u, rate_l, _ = R.reach_tube(design, [-3.0, 8.0, 100.0])
    assert rho_l[0].tolist() == [0.1, 0.1] and rho_u[0].tolist() == [0.5, 0.5]
    assert rho_l[1].tolist() == rho_l[2].tolist() == [4.5, 4.5]
    assert not rate_l.any()


@pytest.mark.parametrize("nu", [1.0, 50.0, 1e4])
def test_open_bump_sum_properties(nu):
    rng = np.random.default_rng(11)
    y = rng.uniform(0.0, 2.0, (500, 3)) * (rng.random((500, 3)) < 0.7)
    f, w = R.open_bump_sum(y, nu)
    top = y.max(axis=1)
    assert np.all(f >= top - 1e-15) and np.all(f <= top + math.log(3) / nu + 1e-12)
    assert np.all((w >= 0) & (w <= 1 + 1e-12))  # (0, 1] in exact arithmetic; may underflow
    # a closed window adds exactly nothing: the sum over the open ones is bit-identical
    for row in range(50):
        open_ = y[row][y[row] > 0]
        if open_.size:
            assert R.open_bump_sum(open_[None, :], nu)[0][0] == f[row] or open_.size == 1
    zero, _ = R.open_bump_sum(np.zeros((1, 4)), nu)
    assert zero[0] == 0.0
    one, _ = R.open_bump_sum(np.array([[0.7]]), nu)
    assert one[0] == 0.7
    # non-decreasing in every argument
    bumped = y.copy()
    bumped[:, 1] += 0.01
    assert np.all(R.open_bump_sum(bumped, nu)[0] >= f)


@pytest.mark.slow
def test_open_bump_sum_is_proved_in_verify():
    from stt_codegen.proofs.lemma import check_open_bump_sum, lemma_checks
    check = check_open_bump_sum()
    assert check.passed, check.detail
    assert "design.open_bump_sum" in [c.name for c in lemma_checks(orders=1)]


def test_cruise_profile_is_proved_c2_with_its_peak_rate_and_is_deployed_as_documented():
    """SymPy: the documented cruise profile (ramp share ``a`` in (0, 1/2), symbolic) has
    ``p``, ``p_dot``, ``p_ddot`` continuous at both joints, ``p = 0, 1`` and
    ``p_dot = p_ddot = 0`` at the ends, rate ``1 / (1 - a)`` in the cruise and between 0
    and that on the ramps; the deployed CasADi piece, printed and reduced on each branch,
    is that profile at ``a = CRUISE_RAMP`` and its ``p_dot`` output is ``dp/dt`` (both to
    the doubles' rounding of the constants, 1e-13 on every coefficient)."""
    import sympy as sp

    from stt_codegen.codegen.emit import sympy_expressions
    from stt_codegen.tube import pieces
    from stt_codegen.proofs.deployed import exact, on_domain

    a = sp.Symbol("a", positive=True)
    tau, x = sp.symbols("tau x", real=True)
    v = 1 / (1 - a)

    def covered(y):
        return v * a * (y**3 - y**4 / 2)

    branches = (covered(tau / a), v * (tau - a / 2), 1 - covered((1 - tau) / a))
    for k in range(3):
        d = [sp.diff(b, tau, k) for b in branches]
        assert sp.simplify((d[0] - d[1]).subs(tau, a)) == 0
        assert sp.simplify((d[1] - d[2]).subs(tau, 1 - a)) == 0
        assert sp.simplify(d[0].subs(tau, 0)) == 0
        assert sp.simplify(d[2].subs(tau, 1) - (0 if k else 1)) == 0
    assert sp.simplify(sp.diff(branches[1], tau) - v) == 0
    ramp_rate = sp.simplify(sp.diff(branches[0], tau).subs(tau, a * x))
    assert sp.simplify(ramp_rate - v * x**2 * (3 - 2 * x)) == 0
    # on x in [0, 1]: v x^2 (3 - 2x) >= 0 and v - it = v (1 - x)^2 (1 + 2x) >= 0
    assert sp.simplify(v - ramp_rate - v * (1 - x) ** 2 * (1 + 2 * x)) == 0
    assert peak_rate_factor(CRUISE) == float(v.subs(a, sp.Rational(1, 5)))

    t = sp.Symbol("t", real=True)
    d_ = sp.Symbol("d", positive=True)
    w = sp.Symbol("w", positive=True)
    (p,), (p_dot,) = sympy_expressions(pieces.progress(CRUISE), {"t": [t], "start": [0],
                                                                 "end": [d_]})
    lo, hi = exact(sp.Float(CRUISE_RAMP)), exact(sp.Float(1.0 - CRUISE_RAMP))
    domains = ({t: lo * d_ * w / (1 + w)}, {t: (lo + (hi - lo) * w / (1 + w)) * d_},
               {t: (hi + (1 - hi) * w / (1 + w)) * d_})
    documented = [sp.expand(b.subs(a, sp.Rational(1, 5))) for b in branches]

    def gap(got, expected) -> float:      # largest coefficient of got - expected in tau
        diff = sp.Poly(sp.expand(got - expected), tau)
        return max(abs(float(c)) for c in diff.all_coeffs())

    for domain, expected in zip(domains, documented):
        value, rate = on_domain(p, domain), on_domain(p_dot, domain)
        value, rate = value.subs(t, tau * d_), (rate * d_).subs(t, tau * d_)
        assert gap(value, expected) < 1e-13
        assert gap(rate, sp.diff(expected, tau)) < 1e-13
    assert pieces.PROFILE_NAMES.index(CRUISE) == 2


@pytest.mark.slow
def test_scurve_profile_is_proved_c2_with_its_peaks_and_is_deployed_as_documented():
    """SymPy: the documented S-curve (turn share ``q`` in (0, 1/4), symbolic) has ``p``,
    ``p_dot``, ``p_ddot`` continuous at every joint (``q``, ``1/2 - q``, the middle, where
    the second half is ``1 - p(1 - tau)``), ``p = 0, 1`` and ``p_dot = p_ddot = 0`` at the
    ends; its rate lies in ``[0, 2]`` (so ``p`` is monotone and ``peak_rate_factor`` is
    right) and its acceleration in ``[-A, A]``, ``A = 4 / (1 - 2 q)``; the deployed CasADi
    piece, reduced on each of its six branches, is that profile at ``q = SCURVE_TURN`` and
    its ``p_dot`` output is ``dp/dt`` (1e-13 on every coefficient)."""
    import sympy as sp

    from stt_codegen.tube import pieces

    q = sp.Symbol("q", positive=True)
    tau, x = sp.symbols("tau x", real=True)
    peak = 4 / (1 - 2 * q)
    half = sp.Rational(1, 2)

    def first(u):                          # the first half's three pieces at u
        w = half - u
        return (peak * u**3 / (6 * q), peak * (u**2 / 2 - q * u / 2 + q**2 / 6),
                half - 2 * w + peak * w**3 / (6 * q))

    branches = first(tau) + tuple(1 - b for b in reversed(first(1 - tau)))
    assert_c2_at_joints(branches, (q, half - q, half, half + q, 1 - q), tau)
    # the rate is non-decreasing up to the middle (and, mirrored, non-increasing after:
    # unimodal, as the enclosures take it), its range on a piece its ends' values
    assert_first_half_within(branches[:3], ((0, q), (q, half - q), (half - q, half)),
                             {q: sp.Rational(2, 25)}, peak, 2, tau, x)
    assert sp.simplify(sp.diff(branches[2], tau).subs(tau, half) - 2) == 0
    assert peak_rate_factor(SCURVE) == 2.0 and SCURVE_TURN == 0.08

    # the branches' ends as the piece compares them: the doubles of q, 1/2 - q, ...
    assert_deployed_as(SCURVE, (SCURVE_TURN, 0.5 - SCURVE_TURN, 0.5, 0.5 + SCURVE_TURN,
                                1.0 - SCURVE_TURN),
                       [b.subs(q, sp.Rational(2, 25)) for b in branches], tau)
    assert pieces.PROFILE_NAMES.index(SCURVE) == 3


def assert_c2_at_joints(branches, joints, tau) -> None:
    """A piecewise profile (SymPy, one expression in ``tau`` per branch, the branches
    meeting at ``joints``) has ``p``, ``p_dot``, ``p_ddot`` continuous at every joint, ``p =
    0`` and ``p = 1`` at the ends and ``p_dot = p_ddot = 0`` there."""
    import sympy as sp
    for k in range(3):
        d = [sp.diff(b, tau, k) for b in branches]
        for j, at in enumerate(joints):
            assert sp.simplify((d[j] - d[j + 1]).subs(tau, at)) == 0, (k, j)
        assert sp.simplify(d[0].subs(tau, 0)) == 0
        assert sp.simplify(d[-1].subs(tau, 1) - (0 if k else 1)) == 0


def assert_first_half_within(branches, ends, values, peak, top, tau, x) -> None:
    """On each of the first half's ``branches`` (``x`` in ``[0, 1]`` across its ``ends``,
    at the parameters ``values``) the acceleration is linear in ``x`` and in ``[0, peak]``
    at both ends, so across it; the rate is in ``[0, top]`` at both ends."""
    import sympy as sp
    for b, (lo, hi) in zip(branches, ends):
        at = {tau: lo + (hi - lo) * x}
        rate, acc = sp.diff(b, tau).subs(at), sp.diff(b, tau, 2).subs(at)
        assert sp.degree(sp.expand(acc.subs(values)), x) <= 1
        for end in (0, 1):
            a, v = acc.subs(x, end).subs(values), rate.subs(x, end).subs(values)
            assert 0 <= sp.simplify(a) <= sp.simplify(sp.sympify(peak).subs(values))
            assert 0 <= sp.simplify(v) <= sp.simplify(sp.sympify(top).subs(values))


def assert_deployed_as(profile: str, cuts, documented: list, tau) -> None:
    """The deployed CasADi piece of ``profile``, reduced on each branch between the
    doubles ``cuts`` (inner ends, in order), is the ``documented`` polynomial in ``tau`` of
    that branch, and its ``p_dot`` output is ``dp/dt`` (1e-13 on every coefficient)."""
    import sympy as sp

    from stt_codegen.codegen.emit import sympy_expressions
    from stt_codegen.proofs.deployed import exact, on_domain
    from stt_codegen.tube import pieces

    t = sp.Symbol("t", real=True)
    d_ = sp.Symbol("d", positive=True)
    w = sp.Symbol("w", positive=True)
    (p,), (p_dot,) = sympy_expressions(pieces.progress(profile), {"t": [t], "start": [0],
                                                                  "end": [d_]})
    ends = [sp.Integer(0)] + [exact(sp.Float(c)) for c in cuts] + [sp.Integer(1)]

    def gap(got, expected) -> float:      # largest coefficient of got - expected in tau
        diff = sp.Poly(sp.expand(got - expected), tau)
        return max(abs(float(c)) for c in diff.all_coeffs())

    assert len(documented) == len(ends) - 1
    for (lo, hi), expected in zip(zip(ends, ends[1:]), documented):
        expected = sp.expand(expected)
        domain = {t: (lo + (hi - lo) * w / (1 + w)) * d_}
        value, rate = on_domain(p, domain), on_domain(p_dot, domain)
        value, rate = value.subs(t, tau * d_), (rate * d_).subs(t, tau * d_)
        assert gap(value, expected) < 1e-13
        assert gap(rate, sp.diff(expected, tau)) < 1e-13
