"""Random plants within declared ``[assumptions]``, for the tests and the study.

A plant ``x_dot = f(x) + g(x) u + w(t)`` is drawn so that every bound of
:class:`~stt_codegen.spec.loader.Assumptions` holds uniformly over the state space:

* ``g(x) = diag(d(x)) + P + tanh(v . x) Q``: ``P`` symmetric with zero diagonal, ``Q``
  skew-symmetric; every ``d_i(x)`` lies in ``[g_min + |P|_2, g_max - |P|_2]``, so the
  eigenvalues of the symmetric part ``diag(d) + P`` lie in ``[g_min, g_max]``; the skew
  part ``tanh(.) Q`` has norm at most ``|Q|_2 <= input_gain_skew``; each row of ``P`` and
  of ``Q`` off the diagonal has norm at most half of ``input_gain_coupling``;
* ``f(x) = f_amp sin(W x + phi) + L (x - centre)`` with
  ``sqrt(n) f_amp + |L|_2 |half-widths| <= drift_bound``;
* ``w_i(t) = w_amp sin(omega_i t + p_i)`` with ``sqrt(n) w_amp <= disturbance_bound``.
"""

from __future__ import annotations

import numpy as np


def _scaled_rows(m: np.ndarray, bound: float) -> np.ndarray:
    rows = np.linalg.norm(m, axis=1).max()
    return m * (bound / rows) if rows > 0 else m


def plant_within(rng: np.random.Generator, assumptions, space) -> dict:
    """Parameters of a random plant satisfying ``assumptions`` on the box ``space``."""
    n = len(space.lower)
    g_min, g_max = assumptions.input_gain
    coupling, skew = assumptions.input_gain_coupling, assumptions.input_gain_skew
    p = rng.normal(size=(n, n))
    p = p + p.T
    np.fill_diagonal(p, 0.0)
    p = _scaled_rows(p, 0.5 * coupling * rng.uniform(0.5, 1.0))
    p_norm = float(np.linalg.norm(p, 2))
    if 2 * p_norm > g_max - g_min:                      # no room for P: drop it
        p, p_norm = 0 * p, 0.0
    q = rng.normal(size=(n, n))
    q = q - q.T
    q = _scaled_rows(q, 0.5 * coupling * rng.uniform(0.5, 1.0))
    q_norm = float(np.linalg.norm(q, 2))
    if q_norm > skew:
        q = q * (skew / q_norm) if q_norm > 0 else q
    lo_d, hi_d = g_min + p_norm, g_max - p_norm
    d_lo = rng.uniform(lo_d, hi_d, n)
    d_hi = rng.uniform(d_lo, hi_d)
    d_lo[0], d_hi[-1] = lo_d, hi_d                      # the extremes are reached
    lower, upper = np.array(space.lower), np.array(space.upper)
    half = (upper - lower) / 2
    share = rng.uniform(0.0, 1.0)
    drift = assumptions.drift_bound
    lin = rng.normal(size=(n, n))
    lin = lin / np.linalg.norm(lin, 2)
    return {"d_mid": (d_lo + d_hi) / 2, "d_amp": (d_hi - d_lo) / 2,
            "d_w": rng.normal(size=(n, n)), "d_phase": rng.uniform(0, 2 * np.pi, n),
            "P": p, "Q": q, "v": rng.normal(size=n),
            "f_amp": share * drift / np.sqrt(n), "W": rng.normal(size=(n, n)),
            "phi": rng.uniform(0, 2 * np.pi, n),
            "L": (1 - share) * drift / np.linalg.norm(half) * lin,
            "centre": (lower + upper) / 2,
            "w_amp": assumptions.disturbance_bound / np.sqrt(n),
            "omega": rng.uniform(0.2, 5.0, n), "w_phase": rng.uniform(0, 2 * np.pi, n)}


def input_matrix(p: dict, x) -> np.ndarray:
    """``g(x)``, shape (n, n)."""
    d = p["d_mid"] + p["d_amp"] * np.sin(p["d_w"] @ x + p["d_phase"])
    return np.diag(d) + p["P"] + np.tanh(p["v"] @ x) * p["Q"]


def plant_system(p: dict):
    """The plant as a python-control ``NonlinearIOSystem`` (n states, inputs, outputs)."""
    import control as ct
    n = len(p["centre"])

    def rhs(t, x, u, params):
        f = p["f_amp"] * np.sin(p["W"] @ x + p["phi"]) + p["L"] @ (x - p["centre"])
        w = p["w_amp"] * np.sin(p["omega"] * t + p["w_phase"])
        return f + input_matrix(p, x) @ np.asarray(u, float) + w

    return ct.nlsys(rhs, None, inputs=n, states=n, outputs=n)
