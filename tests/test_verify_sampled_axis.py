"""The per-axis bound of the coupling: the other inputs' push on one axis,
correlated with that axis's own gain, against random matrices of the class."""

from __future__ import annotations

import numpy as np

from stt_codegen.design.certificate.sampled_axis import coupling_push


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
