"""The Lyapunov level of the coupled sampled check, one sampling interval at a
time: every bound of ``design/certificate/lyapunov.py`` is compared with the exact step of plants of
the class, at many points of the ball (seeded: the same cases every run)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen.design.certificate.lyapunov import level_after, next_level, others_max, psi
from stt_codegen.design.certificate.sampled_axis import phi, phi_slope

CASES = 120


def _ball_points(rng, level: float, limits: np.ndarray, count: int) -> np.ndarray:
    """Points ``a`` with ``|a| <= level`` and ``|a_i| <= limits_i``: random ones, and the
    corners of the box and the ball's points on each axis (where bounds are tight)."""
    m = len(limits)
    pts = rng.uniform(-1, 1, size=(count, m)) * limits
    norms = np.linalg.norm(pts, axis=1)
    scale = np.where(norms > level, level / np.maximum(norms, 1e-300), 1.0)
    pts = pts * scale[:, None] * rng.uniform(0.9, 1.0, size=(count, 1)) ** 0
    special = []
    for i in range(m):
        for sign in (-1.0, 1.0):
            p = np.zeros(m)
            p[i] = sign * min(level, limits[i])
            special.append(p)
    direction = np.minimum(limits, level / math.sqrt(m))
    special.append(direction)
    special.append(-direction)
    return np.vstack([pts, np.array(special)])


def _plants(rng, m: int, g_min: float, g_max: float, skew: float, count: int):
    """Constant input matrices of the class: ``g_min I + P + K``, with ``P`` symmetric in
    ``[0, g_max - g_min]`` and ``|K|_2 <= skew``, extremes included."""
    out = []
    for j in range(count):
        q, _ = np.linalg.qr(rng.normal(size=(m, m)))
        p = rng.uniform(0, g_max - g_min, m)
        if j % 3 == 0:
            p = rng.choice([0.0, g_max - g_min], m)
        k = rng.normal(size=(m, m))
        k = k - k.T
        norm = np.linalg.norm(k, 2)
        k = k / norm * skew * (1.0 if j % 2 else rng.uniform()) if norm > 0 else k
        out.append(g_min * np.eye(m) + q @ np.diag(p) @ q.T + k)
    return out


def test_level_after_bounds_the_exact_step_of_every_plant_of_the_class():
    rng = np.random.default_rng(2020)
    checked = tight = 0
    for case in range(CASES):
        m = int(rng.integers(2, 4))
        halves = rng.uniform(0.02, 0.5, m)
        g_min = float(rng.uniform(0.05, 1.0))
        g_max = g_min * float(rng.uniform(1.0, 6.0))
        skew = float(rng.uniform(0.0, 1.0))
        push = float(rng.uniform(0.0, 6.0)) * (case % 4 != 0)
        dt = 1e-3
        # a gain around the derived one at the narrowest half-width (factor 0.2 to 1.5)
        gain = float(rng.uniform(0.2, 1.5)) * (2 * halves.min()) ** 2 / (8 * dt * (g_min + g_max))
        level = float(rng.uniform(0.0, 1.4))
        limits = np.minimum(rng.uniform(0.2, 1.3, m) * level, level) if level > 0 else np.zeros(m)
        a = _ball_points(rng, level, limits, 300)
        e = np.tanh(a)
        z = phi(e) / halves                                     # (P, m): grad W
        taus = np.array([0.25, 0.5, 1.0]) * dt
        ends = []
        for g in _plants(rng, m, g_min, g_max, skew, 12):
            for kind in range(3):
                if kind == 0:     # pushing outward along the gradient, at full strength
                    d = z / np.maximum(np.linalg.norm(z, axis=1, keepdims=True), 1e-300) * push
                elif kind == 1:
                    d = rng.normal(size=z.shape)
                    d = d / np.linalg.norm(d, axis=1, keepdims=True) * push
                else:
                    d = np.zeros_like(z)
                vel = -2 * gain * z @ g.T + d                   # x_dot with u = -2 k z held
                for tau in taus:
                    ends.append((tau, e + tau * vel / halves))
        reach = np.max([np.abs(x).max(axis=0) for _, x in ends] + [np.abs(e).max(axis=0)],
                       axis=0)
        if reach.max() >= 0.999:
            continue                       # the step leaves the tube: no curvature bound
        curvature = phi_slope(reach) / halves ** 2
        bound = level_after(level, limits.tolist(), halves.tolist(), curvature.tolist(), gain,
                            dt, g_min, g_max, skew, push)
        if not math.isfinite(bound):
            continue
        checked += 1
        for tau, x in ends:
            w = (np.arctanh(x) ** 2).sum(axis=1)
            limit = max(level ** 2, bound) if tau < dt else bound
            assert w.max() <= limit * (1 + 1e-9) + 1e-15, (case, tau, w.max(), limit)
            tight += tau == dt and w.max() > 0.5 * bound
    assert checked >= CASES // 2 and tight >= checked // 4   # not vacuous, not loose


def test_next_level_contains_the_ball_in_the_next_coordinates():
    rng = np.random.default_rng(7)
    for _ in range(300):
        m = int(rng.integers(1, 4))
        alpha = rng.uniform(0.8, 1.25, m)
        beta = rng.uniform(-0.05, 0.05, m)
        level = float(rng.uniform(0, 2.0))
        a = _ball_points(rng, level, np.full(m, level), 400)
        with np.errstate(divide="ignore"):
            image = np.arctanh(np.clip(alpha * np.tanh(a) + beta, -1, 1))
        bound = next_level(level, alpha.tolist(), beta.tolist())
        assert np.linalg.norm(image, axis=1).max() <= bound * (1 + 1e-12) + 1e-15


def test_next_level_with_box_limits_contains_the_image_of_the_ball_and_box():
    rng = np.random.default_rng(8)
    for _ in range(300):
        m = int(rng.integers(1, 4))
        alpha = rng.uniform(0.8, 1.25, m)
        beta = rng.uniform(-0.05, 0.05, m)
        level = float(rng.uniform(0, 2.0))
        limits = rng.uniform(0, 1.5, m) * level
        a = _ball_points(rng, level, limits, 400)
        with np.errstate(divide="ignore"):
            image = np.arctanh(np.clip(alpha * np.tanh(a) + beta, -1, 1))
        bound = next_level(level, alpha.tolist(), beta.tolist(), limits.tolist())
        assert bound <= next_level(level, alpha.tolist(), beta.tolist()) * (1 + 1e-12)
        assert np.linalg.norm(image, axis=1).max() <= bound * (1 + 1e-12) + 1e-15


def test_next_level_is_exact_for_a_tube_that_does_not_move():
    assert next_level(0.7, [1.0, 1.0], [0.0, 0.0]) == pytest.approx(0.7)


def test_others_max_is_the_maximum_over_the_ball_and_the_box():
    rng = np.random.default_rng(11)
    for _ in range(200):
        m = int(rng.integers(1, 4))
        level = float(rng.uniform(0.05, 1.5))
        limits = rng.uniform(0.0, 1.5, m)
        halves = rng.uniform(0.02, 0.5, m)
        bound = others_max(limits.tolist(), level, halves.tolist())
        a = _ball_points(rng, level, limits, 3000)
        values = ((2 * a * np.cosh(a) ** 2 / halves) ** 2).sum(axis=1)
        assert values.max() <= bound * (1 + 1e-12)
        assert values.max() >= 0.8 * bound          # the vertex maximum is reached nearby


def test_psi_is_phi_of_tanh():
    a = np.linspace(-2, 2, 41)
    assert np.allclose([psi(v) for v in a], phi(np.tanh(a)))
