"""Random evaluation points strictly inside the tube, shared by equivalence tests."""

from __future__ import annotations

import numpy as np

from stt_codegen.tube import reference
from stt_codegen.tube.parameters import TubeDesign

#: Largest |e_i| of a sampled point (the acceptance criterion's "strictly inside").
E_LIMIT = 0.999


def random_points(design: TubeDesign, count: int, seed: int = 0) -> dict[str, np.ndarray]:
    """``count`` points ``(t, alpha, x, dt)`` with ``alpha`` valid and ``|e_i| <= E_LIMIT``.

    ``t`` mixes uniform times on ``[0, 1.2 t_c]`` with times packed near every window
    edge and near ``t_c``; ``alpha >= 0`` with ``psi + alpha > 0``, from 0 up to a few
    times the conflict size; points where the tube is narrower than 1e-3 are redrawn.
    """
    rng = np.random.default_rng(seed)
    n = design.dimension
    t_c = design.prescribed_time
    edges = [t_c] + [e for c in design.circumvents for e in (c.start, c.end)]
    out = {k: [] for k in ("t", "alpha", "x", "dt")}
    have = 0
    while have < count:
        m = 2 * count
        t = rng.uniform(0.0, 1.2 * t_c, m)
        near = rng.random(m) < 0.3
        t[near] = np.clip(rng.choice(edges, near.sum()) + rng.normal(0, 0.05, near.sum()),
                          0.0, None)
        psi = reference.conflict_distance(design, t)
        floor = np.maximum(0.0, -psi + 1e-3)
        alpha = floor + rng.exponential(0.05, psi.shape) * (rng.random(psi.shape) < 0.7)
        g_l, g_u, _, _ = reference.adaptive_tube(design, t, alpha)
        ok = np.all(g_u - g_l > 1e-3, axis=1)
        e = rng.uniform(-E_LIMIT, E_LIMIT, (m, n))
        x = ((g_u - g_l) * e + (g_u + g_l)) / 2
        dt = rng.choice([1e-4, 1e-3, 1e-2], m)
        for key, value in (("t", t), ("alpha", alpha), ("x", x), ("dt", dt)):
            out[key].append(value[ok])
        have += int(ok.sum())
    return {k: np.concatenate(v)[:count] for k, v in out.items()}
