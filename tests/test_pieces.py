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
