"""Piecewise reach tube and the eq. (9) combination over open circumvents."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen.tube import reference as R
from stt_codegen.tube.model import build_model
from stt_codegen.tube.parameters import (CRUISE, CRUISE_RAMP, LOWER, SMOOTHSTEP, TANH, UPPER,
                                         Circumvent, ReachSegment, TubeDesign,
                                         peak_rate_factor)

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


@pytest.mark.parametrize("profile", [SMOOTHSTEP, TANH, CRUISE])
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


@pytest.mark.parametrize("profile", [SMOOTHSTEP, CRUISE])
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


@pytest.mark.parametrize("profile", [SMOOTHSTEP, CRUISE])
def test_smooth_profile_peak_rate_and_its_second_derivative(profile):
    """The CasADi model's p_dot peaks at peak_rate_factor times the mean (1.875 for the
    smooth step, 1 / (1 - ramp) = 1.25 for the cruise, held over the whole cruise);
    p_ddot (from the model's p_dot) is continuous, 0 at both ends, and p is monotone."""
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


def test_open_bump_sum_is_proved_in_verify():
    from stt_codegen.verify.lemma import check_open_bump_sum, lemma_checks
    check = check_open_bump_sum()
    assert check.passed, check.detail
    assert "design.open_bump_sum" in [c.name for c in lemma_checks(orders=1)]
