"""The glide profile of a reach segment (``tube.parameters.GLIDE``): jerk-limited ramps
around a cruise; the model, the oracle, the proof of its shape and its use by the via
timing for a force."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen.tube import reference as R
from stt_codegen.tube.parameters import (GLIDE, GLIDE_RAMP, GLIDE_TURN, SCURVE, SMOOTHSTEP,
                                         peak_acceleration_factor, peak_rate_factor)


def test_glide_model_and_oracle_agree_with_its_documented_peaks():
    """CasADi's piece and the numpy oracle give the same ``p`` and ``p_dot`` (to rounding;
    two independent writings); ``p`` is monotone from 0 to 1; the rate holds 5/3 of the mean
    over the cruise; the acceleration (differenced from the model's rate) peaks at
    ``peak_acceleration_factor`` and is continuous (no jump: the jerk stays within the
    quintic smooth step's 60)."""
    from stt_codegen.tube.pieces import progress
    start, end = 2.0, 7.0
    t = np.linspace(start - 0.5, end + 0.5, 220001)
    p, p_dot = (np.array(v).ravel() for v in progress(GLIDE).map(t.size)(t[None, :], start, end))
    p_ref, p_dot_ref = R._progress(GLIDE, t, start, end)
    assert np.max(np.abs(p - p_ref)) < 1e-15 and np.max(np.abs(p_dot - p_dot_ref)) < 1e-14
    mean = 1.0 / (end - start)
    assert np.all(np.diff(p) >= 0.0) and p[0] == 0.0 and p[-1] == 1.0
    tau = (t - start) / (end - start)
    cruise = (tau > GLIDE_RAMP + 1e-6) & (tau < 1.0 - GLIDE_RAMP - 1e-6)
    assert np.all(np.abs(p_dot[cruise] / mean - 5.0 / 3.0) < 1e-12)
    assert abs(p_dot.max() / mean - peak_rate_factor(GLIDE)) < 1e-12
    p_ddot = np.diff(p_dot) / np.diff(t)
    peak = peak_acceleration_factor(GLIDE) * mean**2
    assert abs(np.max(np.abs(p_ddot)) - peak) < 1e-6 * peak
    jerk = np.max(np.abs(np.diff(p_ddot) / np.diff(t)[1:])) / mean**3
    assert jerk < 60.0
    # the glide is below the quintic smooth step in both peaks, above the S-curve in
    # acceleration and below it in rate: the order of ACCELERATION_PROFILES
    assert peak_rate_factor(GLIDE) < peak_rate_factor(SMOOTHSTEP) < peak_rate_factor(SCURVE)
    assert (peak_acceleration_factor(SCURVE) < peak_acceleration_factor(GLIDE)
            < peak_acceleration_factor(SMOOTHSTEP))
    from stt_codegen.design.via import ACCELERATION_PROFILES
    assert ACCELERATION_PROFILES.index(GLIDE) == ACCELERATION_PROFILES.index(SCURVE) + 1


@pytest.mark.slow
def test_glide_is_proved_c2_with_its_peaks_and_is_deployed_as_documented():
    """SymPy, with the ramp share ``r`` and the turn share ``q`` symbolic (``0 < 2 q < r <
    1/2``): the documented glide has ``p``, ``p_dot``, ``p_ddot`` continuous at every joint,
    ``p = 0, 1`` and ``p_dot = p_ddot = 0`` at the ends, ``p(1/2) = 1/2``; on the first half
    its acceleration lies in ``[0, A]`` (``A = V / (r - q)``) and its rate in ``[0, V]`` (``V =
    1 / (1 - r)``), so ``p`` is monotone and the rate unimodal with its plateau at ``1/2``, as
    the enclosures take it. The deployed CasADi piece, reduced on each of its eight branches,
    is that profile at ``GLIDE_RAMP``, ``GLIDE_TURN`` and its ``p_dot`` output is ``dp/dt``
    (1e-13 on every coefficient)."""
    import sympy as sp
    from test_tube_segments import (assert_c2_at_joints, assert_deployed_as,
                                    assert_first_half_within)

    from stt_codegen.tube import pieces

    r, q = sp.symbols("r q", positive=True)
    tau, x = sp.symbols("tau x", real=True)
    top = 1 / (1 - r)
    peak = top / (r - q)
    half = sp.Rational(1, 2)

    def first(u):                          # the first half's four pieces at u
        w = r - u
        return (peak * u**3 / (6 * q), peak * (u**2 / 2 - q * u / 2 + q**2 / 6),
                top * r / 2 - top * w + peak * w**3 / (6 * q), top * (u - r / 2))

    branches = first(tau) + tuple(1 - b for b in reversed(first(1 - tau)))
    assert_c2_at_joints(branches, (q, r - q, r, half, 1 - r, 1 - r + q, 1 - q), tau)
    assert sp.simplify(branches[3].subs(tau, half) - half) == 0
    # each piece of the first half: the acceleration in [0, A], the rate in [0, V]
    values = {r: sp.Rational(2, 5), q: sp.Rational(9, 100)}
    assert_first_half_within(branches[:4], ((0, q), (q, r - q), (r - q, r), (r, half)),
                             values, peak, top, tau, x)
    assert (GLIDE_RAMP, GLIDE_TURN) == (0.4, 0.09)
    assert math.isclose(peak_rate_factor(GLIDE), float(top.subs(values)), rel_tol=1e-15)
    assert math.isclose(peak_acceleration_factor(GLIDE), float(peak.subs(values)),
                        rel_tol=1e-15)

    # the branches' ends as the piece compares them: the doubles of q, r - q, r, 1/2 and
    # their mirrors
    r_, q_ = GLIDE_RAMP, GLIDE_TURN
    assert_deployed_as(GLIDE, (q_, r_ - q_, r_, 0.5, 1.0 - r_, 1.0 - (r_ - q_), 1.0 - q_),
                       [b.subs(values) for b in branches], tau)
    assert pieces.PROFILE_NAMES.index(GLIDE) == 4


def test_timed_moves_give_a_glide_where_the_s_curve_passes_the_velocity_bound():
    """Timed for the force from the S-curve on, under ``|v_i| <= 1``, the long move whose
    S-curve would pass the bound takes a glide (peak rate 5/3 of the mean, the smooth
    step's 15/8): within the bound, where its S-curve is not; no move takes the smooth
    step. From the smooth step on (the other candidate), no move takes a glide."""
    from test_design_via import MOVES, _force_spec

    from stt_codegen.design.via import timed_moves
    spec = _force_spec([1.0, 1.0])
    durations, profiles = timed_moves(spec, MOVES, 24.0, SCURVE)
    assert profiles[1] == GLIDE and SMOOTHSTEP not in profiles
    assert peak_rate_factor(GLIDE) * 9.0 / durations[1] <= 1.0 + 1e-9
    assert peak_rate_factor(SCURVE) * 9.0 / durations[1] > 1.0
    _, smooth = timed_moves(spec, MOVES, 24.0, SMOOTHSTEP)
    assert GLIDE not in smooth and SCURVE not in smooth
