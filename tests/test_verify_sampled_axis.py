"""The per-axis bound of the coupling: the other inputs' push on one axis,
correlated with that axis's own gain, against random matrices of the class; the peak
``s*`` of a box decided without bisecting where the box lies away from it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from stt_codegen.design.certificate.sampled_axis import coupling_push, peak_for_box, peak_scalar
from stt_codegen.tube.parameters import E_MAX


def test_coupling_push_bounds_every_matrix_of_the_class():
    rng = np.random.default_rng(20)
    worst = 0.0
    for _ in range(3000):
        n = int(rng.integers(2, 5))
        g_min = float(rng.uniform(0.05, 1.0))
        g_max = g_min * float(rng.uniform(1.0, 6.0))
        q, _ = np.linalg.qr(rng.normal(size=(n, n)))
        eig = rng.uniform(g_min, g_max, n)
        if rng.uniform() < 0.3:
            eig = rng.choice([g_min, g_max], n)
        sym = q @ np.diag(eig) @ q.T
        k = rng.normal(size=(n, n))
        k = k - k.T
        skew = float(rng.uniform(0, 1.0))
        k = k / np.linalg.norm(k, 2) * skew * rng.uniform(0, 1)
        g = sym + k
        coupling = float(np.linalg.norm(g[0, 1:]))          # the row's true coupling
        coupling *= float(rng.uniform(1.0, 1.5))           # or a looser declared one
        u = rng.normal(size=n - 1)
        others = float(rng.uniform(0, 2.0))
        u = u / np.linalg.norm(u) * others
        own = float(rng.uniform(0, 2.0)) if rng.uniform() < 0.8 else 0.0
        off = float(g[0, 1:] @ u)
        bound = coupling_push(others, coupling, g_max - g_min, skew, own)
        outward = off - (g[0, 0] - g_min) * own           # beyond what g_min leaves
        inward = -off - (g_max - g[0, 0]) * own            # beyond what g_max leaves
        assert max(outward, inward) <= bound * (1 + 1e-12) + 1e-15
        if bound > 0:
            worst = max(worst, max(outward, inward) / bound)
    assert worst > 0.7                                     # not a loose bound


def test_coupling_push_is_at_most_the_row_coupling_and_zero_without_others():
    assert coupling_push(0.0, 1.0, 2.0, 0.5, 1.0) == 0.0
    assert coupling_push(1.0, 0.3, 2.0, 0.5, 0.0) == 0.3
    assert abs(coupling_push(0.1, 5.0, 2.0, 0.0, 1.0) - 2.0 * 0.01 / 4.0) < 1e-15


def _clipped(s_peak: float, a: float, b: float) -> list[float]:
    """``s_peak`` clipped as :func:`axis_interval` clips it, to each non-empty range of
    ``|e_i|`` for ``e_i`` in ``[a, b]``."""
    out = []
    for s_a, s_b, empty in ((max(a, 0.0), b, b < max(a, 0.0)),
                            (max(-b, 0.0), -a, -a < max(-b, 0.0) or -a == 0.0)):
        if not empty:
            out.append(min(max(s_peak, s_a), s_b))
    return out


@settings(max_examples=3000, deadline=None)
@given(ratio=st.floats(0.5, 1e7), a=st.floats(-E_MAX, E_MAX), width=st.floats(0.0, 2.0),
       near=st.sampled_from([None, 0, 1]), shift=st.floats(-1e-6, 1e-6))
@pytest.mark.slow
def test_the_peak_for_a_box_is_clipped_as_the_bisected_peak(ratio, a, width, near, shift):
    """The shortcut of :func:`peak_for_box` gives the same doubles as the bisection wherever
    axis_interval reads them, also for ranges whose end lies at or next to ``s*``."""
    s_star = peak_scalar(ratio)
    if near is not None:                      # an end of the range at s* (either sign)
        end = min(max(s_star + shift, 0.0), E_MAX)
        a, width = (end, width) if near == 0 else (-end, width)
    b = min(a + width, E_MAX)
    assert _clipped(peak_for_box(ratio, a, b), a, b) == _clipped(s_star, a, b)


def test_the_peak_for_a_box_skips_the_bisection_away_from_the_peak(monkeypatch):
    """Ranges clearly below or above ``s*`` are decided without bisecting; a range that
    holds ``s*`` is bisected."""
    from stt_codegen.design.certificate import sampled_axis
    calls, bisect = [], sampled_axis._peak_float
    s_star = peak_scalar(40.0)
    monkeypatch.setattr(sampled_axis, "_peak_float", lambda r: calls.append(r) or bisect(r))
    assert peak_for_box(40.0, -0.1, 0.2) == 0.2 and not calls          # below s*
    assert peak_for_box(40.0, s_star + 0.01, 0.99) == 0.0 and not calls  # above s*
    assert peak_for_box(40.0, -0.99, -(s_star + 0.01)) == 0.0 and not calls
    assert peak_for_box(40.0, s_star - 0.01, s_star + 0.01) == s_star and calls == [40.0]
