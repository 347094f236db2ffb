"""How much of law (13)'s gain a tube needs to be followed at ``|e| <= 0.7`` (an estimate).

The certificate proves the tube; whether the sampled law keeps the state well inside it is
:func:`stt_codegen.design.certificate.sampled.check_sampled`'s business (200-300 ms a design, too slow
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
from functools import lru_cache

import numpy as np

from ..spec.loader import Spec
from ..tube import reference
from ..tube.parameters import TubeDesign
from .certificate import Certificate
from .certificate.actuator import prove_input_bound

__all__ = ["SMOOTHER_RATIO", "TRACKING_ERROR", "centre_speed", "proved_error", "tracking_demand",
           "unfollowable"]

#: The normalized error the demand is computed for: the closed loop is to keep ``max |e| <=
#: 0.7``.
TRACKING_ERROR = 0.7
#: Values of ``e`` in ``[-E, E]`` tried for the least speed the state needs.
_ERRORS = np.linspace(-TRACKING_ERROR, TRACKING_ERROR, 29)
#: ``auto`` prefers the via-point tube to the paper's tube with circumvents when the via
#: tube's centre moves at most this fraction of the paper tube's peak centre speed
#: (:func:`centre_speed`; docs/design.md, "Smoother tubes").
SMOOTHER_RATIO = 0.8


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
    t, g_l, g_u, rate_l, rate_u = _partition(design, certificate)
    # every e of _ERRORS at once (axis 0), the least over them
    errors = _ERRORS[:, None, None]
    speed = (np.abs((1.0 + errors) * rate_u + (1.0 - errors) * rate_l) / 2.0).min(axis=0)
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


#: The last few results of :func:`_partition`, with the (design, certificate) objects they
#: are of: ``auto`` asks for the demand and the centre speed of the same tube in turn.
_RECENT: list[tuple[TubeDesign, Certificate, tuple[np.ndarray, ...]]] = []


def _partition(design: TubeDesign, certificate: Certificate) -> tuple[np.ndarray, ...]:
    """The tube and its rates at the certificate's partition (``alpha`` midway in its
    proven bounds): ``t`` (K,), ``gamma_L``, ``gamma_U``, their rates (K, n)."""
    for known, of, result in list(_RECENT):
        if known is design and of is certificate:
            return result
    result = _evaluate_partition(design, certificate)
    _RECENT[:] = [(design, certificate, result)] + _RECENT[:1]
    return result


def _evaluate_partition(design: TubeDesign, certificate: Certificate) -> tuple[np.ndarray, ...]:
    state = certificate.state
    t = np.array(state.points, dtype=float) / design.rate_hz
    alpha = 0.5 * (np.array([e[0] for e in state.entries]) + np.array([e[1] for e in state.entries]))
    with reference.numpy_math():
        return (t, *reference.adaptive_tube(design, t, alpha))


def centre_speed(design: TubeDesign, certificate: Certificate) -> float:
    """The peak speed of the tube's centre, ``max |gamma_L_dot + gamma_U_dot| / 2`` over
    the dimensions and the instants of the certificate's partition (an estimate).

    With the gains of the bench's arenas the state rides near the centre (median ``max
    |e|`` below 0.01), so law (13) asks about this speed of the plant: the estimate
    :func:`~stt_codegen.design.search.design_tube`'s ``auto`` compares between the paper's
    tube and via points (docs/design.md, "Smoother tubes").

    Parameters
    ----------
    design : TubeDesign
    certificate : Certificate
        Of ``design``: its partition's instants and ``alpha`` bounds.

    Returns
    -------
    float
        State units per second.
    """
    _, _, _, rate_l, rate_u = _partition(design, certificate)
    return float(np.max(np.abs(rate_l + rate_u)) / 2.0)


@lru_cache(maxsize=32)
def proved_error(design: TubeDesign, spec: Spec) -> float:
    """The sampled-data proof's bound of ``max |e_i(t_k)|`` over the samples of ``design``
    for the plants of ``spec`` (``InputProof.max_abs_e`` of
    :func:`~.certificate.actuator.prove_input_bound`), ``-inf``
    when the proof fails (it cannot tell). Cached per ``(design, spec)``: the same bundled
    design is asked for again and again in one process, and the proof takes 0.2-1 s.

    Parameters
    ----------
    design : TubeDesign
        The tube with its gain.
    spec : Spec
        The spec (its ``[assumptions]``, the plants the proof covers).

    Returns
    -------
    float
        The bound, in ``[0, 1)`` when proved, else ``-inf``.
    """
    proof = prove_input_bound(design, spec)
    return proof.max_abs_e if proof.proved else -math.inf


def _followable_per_axis(design: TubeDesign, spec: Spec) -> bool:
    """Whether the per-axis argument alone proves ``|e| <= TRACKING_ERROR``: it bounds
    ``|e|`` no tighter than the whole check (the Lyapunov balls only cut its enclosures),
    so a yes here is the whole check's yes, at a quarter of its cost; it is also the check
    ``verify`` runs, which then finds it computed."""
    proof = prove_input_bound(design, spec, per_axis_first=True)
    return proof.proved and proof.max_abs_e <= TRACKING_ERROR


def unfollowable(design: TubeDesign, certificate: Certificate, spec: Spec) -> str:
    """Why law (13) with ``design``'s gain cannot follow the tube at ``|e| <= E``, or ``""``.

    The tube is refused when the sampled-data proof
    (:func:`~stt_codegen.design.certificate.actuator.prove_input_bound`: the bound of
    ``|e_i(t_k)|`` at every sample, for every plant of the spec's class) bounds ``|e|``
    above :data:`TRACKING_ERROR` somewhere. A tube whose proof fails is not refused here
    (the proof cannot tell; ``verify`` reports it).

    Parameters
    ----------
    design : TubeDesign
        With its gain set.
    certificate : Certificate
        Of ``design``.
    spec : Spec
        Without ``[actuator]`` or with it (the bound plays no part).

    Returns
    -------
    str
        The reason, in numbers; empty when the tube is kept.
    """
    # every candidate is proved: the demand, an estimate, is no screen (arena 18 of seed 0:
    # demand 0.24, proved and simulated |e| 0.75)
    if _followable_per_axis(design, spec):
        return ""
    proved = proved_error(design, spec)
    if proved <= TRACKING_ERROR:
        return ""
    demand = tracking_demand(design, certificate, spec)
    return (f"law (13) with gain {design.gain:.3g} is proved only to |e| <= "
            f"{proved:.3f} on this tube (above {TRACKING_ERROR}; tracking demand "
            f"{demand.ratio:.3g} at t = {demand.time:.3f} s, dimension {demand.dimension})")
