"""Helpers of the issue-7 hostile-input tests (tests/test_hard_*.py): a small TOML writer."""

from __future__ import annotations

import json
import math
import tomllib
from importlib import resources


def toml_value(value) -> str:
    """One TOML value (inline tables and arrays; NaN and infinities as TOML spells them)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(type(value))


def dumps(doc: dict) -> str:
    """A TOML document of top-level ``key = value`` lines."""
    return "".join(f"{json.dumps(str(k))} = {toml_value(v)}\n" for k, v in doc.items())


def bundled_doc(name: str) -> dict:
    data = resources.files("stt_codegen.cases").joinpath(name + ".toml").read_bytes()
    return tomllib.loads(data.decode())


def shape_docs() -> list[dict]:
    """The bundled specs, plus variants with a ball and a polytope obstacle (with tolerance)."""
    docs = [bundled_doc(f"omnirobot-s{k}") for k in (1, 2, 3)]
    ball = bundled_doc("omnirobot-s1")
    ball["obstacles"].append({"center": [3.5, 3.8], "radius": 0.3, "tolerance": 0.1})
    poly = bundled_doc("omnirobot-s2")
    poly["obstacles"].append({"vertices": [[3.2, 3.8], [3.9, 3.8], [3.5, 4.3]],
                              "tolerance": 0.08})
    poly3 = bundled_doc("omnirobot-s3")
    poly3["obstacles"].append({"vertices": [[2.8, 3.8, -0.5], [3.4, 3.8, -0.5],
                                            [3.0, 4.2, -0.5], [3.0, 4.0, 0.5]],
                               "dims": [0, 1, 2], "tolerance": 0.2})
    return docs + [ball, poly, poly3]


# --------------------------------------------------------------------------- unknown plants


def _skew(v):
    """A unit skew-symmetric matrix: the rotation generator in 2-D, ``v x`` in 3-D."""
    import numpy as np
    if len(v) == 2:
        return np.array([[0.0, -1.0], [1.0, 0.0]])
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def random_plant_parameters(rng, f_amp: float, f_lin: float, g_min: float, g_max: float,
                            skew: float, w_amp: float, n: int = 3) -> dict:
    """Parameters of ``x_dot = f(x) + g(x) u + w(t)`` (see :func:`unknown_plant`), seeded.

    ``f(x) = f_amp sin(W x + phi) + f_lin L (x - c) / |L|``: a bounded smooth term and a
    linear term about the state space's middle ``c`` (``|f_lin L/|L||`` is the spectral norm).
    ``g(x) = D + S + K(x)``: ``D + S`` symmetric with eigenvalues in ``[g_min, g_max]``,
    ``K(x) = skew * tanh(v . x) * skew-matrix``, skew-symmetric (so the symmetric part of g
    has ``lambda_min >= g_min``, uniformly in x). ``w_i(t) = w_amp sin(omega_i t + p_i)``.
    """
    import numpy as np
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    eig = rng.uniform(g_min, g_max, n)
    eig[0], eig[-1] = g_min, g_max                      # the extremes are attained
    sym = q @ np.diag(eig) @ q.T
    lin = rng.normal(size=(n, n))
    lin = lin / np.linalg.norm(lin, 2)
    axis = rng.normal(size=n)
    return {"W": rng.normal(size=(n, n)), "phi": rng.uniform(0, 2 * np.pi, n), "f_amp": f_amp,
            "L": f_lin * lin, "sym": sym, "skew_axis": axis / np.linalg.norm(axis),
            "skew": skew, "v": rng.normal(size=n), "w_amp": w_amp,
            "omega": rng.uniform(0.2, 5.0, n), "w_phase": rng.uniform(0, 2 * np.pi, n)}


def unknown_plant(p: dict, centre):
    """A python-control ``NonlinearIOSystem`` (n states, inputs and outputs) from parameters."""
    import control as ct
    import numpy as np
    centre = np.asarray(centre, float)
    k_mat = _skew(p["skew_axis"])

    def rhs(t, x, u, params):
        f = p["f_amp"] * np.sin(p["W"] @ x + p["phi"]) + p["L"] @ (x - centre)
        g = p["sym"] + p["skew"] * np.tanh(p["v"] @ x) * k_mat
        w = p["w_amp"] * np.sin(p["omega"] * t + p["w_phase"])
        return f + g @ u + w

    n = len(centre)
    return ct.nlsys(rhs, None, inputs=n, states=n, outputs=n)


def plant_bounds(p: dict, spec) -> dict:
    """Bounds of the drawn plant over the state space: ``|f|_inf``, ``lambda_min`` and
    ``lambda_max`` of the symmetric part of g, and ``|g|_2`` (upper bound)."""
    import numpy as np
    lo, hi = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    centre = (lo + hi) / 2
    f_bound = p["f_amp"] + np.max(np.abs(p["L"]) @ ((hi - lo) / 2))
    eig = np.linalg.eigvalsh(p["sym"])
    return {"f_inf": float(f_bound), "g_sym_min": float(eig[0]), "g_sym_max": float(eig[-1]),
            "g_norm": float(eig[-1] + p["skew"]), "w_inf": p["w_amp"], "centre": centre}
