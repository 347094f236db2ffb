"""The status a sampled check reads: below the width floor, ``inside`` uses the true width.

The deployed law floors ``gamma_d`` at ``GAMMA_D_MIN`` (1e-6) to keep ``u`` finite. The
floored ``e`` is smaller than the true one, so judging ``|e| < 1`` with it would report a
state outside a tube narrower than the floor as inside.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from conftest import designed

from stt_codegen.tube import reference
from stt_codegen.tube.model import controller_law
from stt_codegen.tube.parameters import GAMMA_D_MIN

WIDTH = 0.4 * GAMMA_D_MIN
# 0.6e-6 is above gamma_U = 0.4e-6: e = 2 with the true width, 0.8 with the floored one
OUTSIDE = np.array([[0.6e-6, 0.2e-6, 0.2e-6]])
INSIDE = np.array([[0.3e-6, 0.2e-6, 0.2e-6]])


def _tiny_tube(monkeypatch):
    lower, upper = np.zeros((1, 3)), np.full((1, 3), WIDTH)
    monkeypatch.setattr(reference, "adaptive_tube",
                        lambda design, t, alpha: (lower, upper, 0 * lower, 0 * upper))
    return lower, upper


def test_reference_reports_a_state_outside_a_tube_below_the_floor_as_outside(monkeypatch):
    _, design, _ = designed("omnirobot-s2")
    lower, upper = _tiny_tube(monkeypatch)
    floored_e = (2 * OUTSIDE[0, 0] - WIDTH) / GAMMA_D_MIN
    assert abs(floored_e) < 1.0          # the old test would have said "inside"
    alpha = np.zeros((1, 6))
    _, _, out = reference.controller_step(design, OUTSIDE, 1.0, 1e-3, alpha)
    _, _, inn = reference.controller_step(design, INSIDE, 1.0, 1e-3, alpha)
    assert out[0] == 0.0 and inn[0] == 1.0


def test_model_judges_inside_with_the_true_width():
    _, design, _ = designed("omnirobot-s2")
    lower, upper = ca.DM(np.zeros(3)), ca.DM(np.full(3, WIDTH))
    for x, expected in ((OUTSIDE[0], 0.0), (INSIDE[0], 1.0)):
        u, inside = controller_law(design, ca.DM(x), lower, upper)
        assert float(inside) == expected
        assert np.all(np.isfinite(np.array(u)))   # u stays finite through the floor
