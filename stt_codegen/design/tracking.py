"""How much of law (13)'s gain a tube needs to be followed at ``|e| <= 0.7`` (an estimate).

The certificate proves the tube; whether the sampled law keeps the state well inside it is
:func:`stt_codegen.verify.sampled.check_sampled`'s business (200-300 ms a design, too slow
for the search). This module estimates, cheaply, the gain a tube *asks for*: at ``|e| = E``
(:data:`TRACKING_ERROR`) law (13) drives state ``i`` at

    |u_i| = k (4 / gamma_d_i) Phi(E),   Phi(E) = ln((1 + E) / (1 - E)) / (1 - E^2),

(times ``g_min`` through the plant), and to keep a normalized error ``e`` the state must
move at ``((1 + e) gamma_U_dot + (1 - e) gamma_L_dot) / 2``; the least of that over
``|e| <= E`` plus the drift and disturbance bounds is the speed it needs. Their ratio,
over the dimensions and the instants of the certificate's partition (``alpha`` midway in
its proven bounds there), is the *tracking demand*: the gain needed over the gain given.
Above 1 the state rides near the tube's wall somewhere, whatever the certificate says: one
constant gain cannot both respect the narrowest point (the gain's limit, docs/decisions.md,
decision 15) and follow a wide, fast-moving part of the tube (a neck in one dimension while
another moves fast), or the tube moves faster than the gain follows (a circumvent let go).
``design_tube``'s ``auto`` then tries via points (:mod:`stt_codegen.design.search`).

Measured on ``bench arenas --count 100 --seed 0``: the demand orders the closed loops'
``max |e|`` almost exactly; the two satisfied arenas above 0.7 (0.93, 0.74) are the two with
demand above 1 (7.2, 1.4); the bundled cases have 0.68, 0.92, 0.14.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..spec.loader import Spec
from ..tube import reference
from ..tube.parameters import TubeDesign
from .certificate import Certificate

#: The normalized error the demand is computed for (issue 20's acceptance: ``max |e| <=
#: 0.7`` in closed loop).
TRACKING_ERROR = 0.7
#: Values of ``e`` in ``[-E, E]`` tried for the least speed the state needs.
_ERRORS = np.linspace(-TRACKING_ERROR, TRACKING_ERROR, 29)


@dataclass(frozen=True)
class TrackingDemand:
    """The gain a tube asks for, relative to the gain it has.

    Attributes
    ----------
    ratio : float
        Largest ``k_needed / k`` over the instants and dimensions (above 1: the state
        lags beyond ``|e| = TRACKING_ERROR`` somewhere, by this estimate).
    time : float
        Where it is largest, seconds.
    dimension : int
    """

    ratio: float
    time: float
    dimension: int


def tracking_demand(design: TubeDesign, certificate: Certificate, spec: Spec) -> TrackingDemand:
    """The tracking demand of ``design`` with its gain (see the module notes).

    Parameters
    ----------
    design : TubeDesign
        With its gain ``k`` (> 0) set.
    certificate : Certificate
        Of ``design``: its partition's instants and ``alpha`` bounds.
    spec : Spec
        ``[assumptions]``: ``g_min``, the drift and disturbance bounds.

    Returns
    -------
    TrackingDemand
    """
    state = certificate.state
    t = np.array(state.points, dtype=float) / design.rate_hz
    alpha = 0.5 * (np.array([e[0] for e in state.entries]) + np.array([e[1] for e in state.entries]))
    with reference.numpy_math():
        g_l, g_u, rate_l, rate_u = reference.adaptive_tube(design, t, alpha)
    speed = np.full(g_l.shape, np.inf)
    for e in _ERRORS:
        speed = np.minimum(speed, np.abs((1.0 + e) * rate_u + (1.0 - e) * rate_l) / 2.0)
    a = spec.assumptions
    need = speed + a.disturbance_bound
    e = TRACKING_ERROR
    phi = math.log((1.0 + e) / (1.0 - e)) / (1.0 - e * e)
    # at the gain's design point lambda* (the middle of [g_min, g_max]):
    # k lambda* (4 / gamma_d) Phi(E) = need  ->  k_needed = need gamma_d / (4 Phi(E) lambda*)
    design_point = 0.5 * (a.input_gain[0] + a.input_gain[1])
    ratio = need * (g_u - g_l) / (4.0 * phi * design_point * design.gain)
    k, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    return TrackingDemand(float(ratio[k, i]), float(t[k]), int(i))
