"""Pieces of the deployed controller: the skipped smooth-max correction is exactly zero."""

from __future__ import annotations

import numpy as np

from stt_codegen.tube import pieces as P


def test_skipped_smooth_max_correction_cannot_change_the_result():
    test, smooth_max, min_test, smooth_min = P.smooth_pieces()[:4]
    rng = np.random.default_rng(7)
    count = 20_000
    nu = 10.0 ** rng.uniform(-1, 3, count)
    a = rng.choice([-1, 1], count) * 10.0 ** rng.uniform(-4, 3, count)
    b = a + rng.choice([-1, 1], count) * 10.0 ** rng.uniform(-2, 3, count)
    top, needed = (np.array(v).ravel() for v in test.map(count)(a, b, nu))
    full = np.array(smooth_max.map(count)(a, b, nu)).ravel()
    skipped = needed == 0
    assert 0.2 < skipped.mean() < 0.9  # both branches are exercised
    assert np.array_equal(full[skipped], top[skipped])  # double: bit for bit
    # float32: the same formula evaluated in float32
    a32, b32, nu32 = (v.astype(np.float32) for v in (a, b, nu))
    top32 = np.maximum(a32, b32)
    corr32 = np.log1p(np.exp(np.maximum(-nu32 * np.abs(a32 - b32), np.float32(-80)))) / nu32
    assert np.array_equal((top32 + corr32)[skipped], top32[skipped])
    # the minimum likewise
    low, needed = (np.array(v).ravel() for v in min_test.map(count)(a, b, nu))
    full = np.array(smooth_min.map(count)(a, b, nu)).ravel()
    assert np.array_equal(full[needed == 0], low[needed == 0])


def test_near_skip_rule_is_exact_at_its_boundary():
    """The second skip rule (``nu |a - b| >= 34``, ``nu |max| (nu |a - b| - 33) >= 30.91``)
    at its boundary near ``nu |a - b| = 34`` (where its bound ``e^-d <= e^-34 / (d - 33)`` is
    tight), with maxima just below powers of two (the smallest half-ulp relative to the
    value): skipped corrections leave the max unchanged, in float64 (the Functions) and
    float32 (the same formula)."""
    test, smooth_max = P.smooth_pieces()[:2]
    rng = np.random.default_rng(11)
    count = 20_000
    top = rng.choice([-1, 1], count) * 2.0 ** rng.integers(-12, 12, count) * (2.0 - 2.0 ** -40)
    boundary = rng.uniform(34.0, 34.5, count)  # d where the rule starts to skip
    nu = P._SKIP_SCALE / ((boundary - 33.0) * np.abs(top))
    d = boundary * rng.uniform(0.995, 1.005, count)
    a, b = top, top - d / nu
    got_top, needed = (np.array(v).ravel() for v in test.map(count)(a, b, nu))
    full = np.array(smooth_max.map(count)(a, b, nu)).ravel()
    skipped = needed == 0
    assert np.array_equal(full[skipped], got_top[skipped])
    a32, b32, nu32 = (v.astype(np.float32) for v in (a, b, nu))
    top32 = np.maximum(a32, b32)
    corr32 = np.log1p(np.exp(np.maximum(-nu32 * np.abs(a32 - b32), np.float32(-80)))) / nu32
    assert np.array_equal((top32 + corr32)[skipped], top32[skipped])
    assert 0.2 < skipped.mean() < 0.8  # both sides of the boundary


def test_near_skip_rule_uses_the_clamped_exponent():
    """Where ``nu |a - b|`` is far beyond the exponent clamp (80) the correction is
    ``log1p(e^-80) / nu`` whatever ``|a - b|``: a tiny max next to a huge ``|a - b|`` must
    keep it (``max~`` differs from the max there)."""
    test, smooth_max = P.smooth_pieces()[:2]
    a, b, nu = 1e-30, -1e27, 1000.0
    top, needed = (float(v) for v in test(a, b, nu))
    assert float(smooth_max(a, b, nu)) != top
    assert needed == 1
