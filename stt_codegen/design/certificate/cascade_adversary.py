"""Members of a second-order class that leave a tube: an adversary on the sampled cascade.

The cascade's sampled-data certificate (:mod:`.cascade_sampled`) proves a class of
second-order plants, :class:`~.cascade_sampled.CascadeClass`: every ``x1_dot = x2``,
``x2_dot = f + g u + w`` whose ``g`` is symmetric with eigenvalues in ``[g_min, g_max]``,
with ``|f_i| <= F0 + F1 |x2_i|`` and ``|w_i| <= W``. This module searches the class for a
member that leaves the position tube or the velocity tube under the sampled cascade,
as :mod:`.class_search` does for first-order plants; a certificate that accepts a class
in which the search finds such a member is wrong.

The adversary, exact in its arithmetic:

* ``g`` is piecewise constant along the path: on each sampling interval one diagonal
  matrix with entries ``g_min`` or ``g_max`` (the class's extreme members; with
  ``coupling > 0`` the rotated members are not tried);
* ``f + w`` is constant on each interval where ``F1 = 0``: ``d_i = s_i (F0 + W)`` with a
  sign ``s_i`` per axis (with ``F1 > 0``, ``f_i = s_i (F0 + F1 |x2_i(t)|)`` is integrated
  by Runge-Kutta over :data:`SUBSTEPS` steps);
* with ``u_k`` held, ``x2`` and ``x1`` move exactly (``x2 + a s``, ``x1 + x2 s + a s^2 /
  2`` for the constant acceleration ``a = g u_k + d``).

On each interval every combination of ``g`` and signs (``4^n``) is tried and the strategy
keeps the one that maximises the next sample's ``max_i |e1_i|`` (``position``), ``max_i
|e2_i|`` (``velocity``), or ``max(|e1|, |e2|)`` (``both``), with ``e1`` the normalized
position error in the tube (eq. (10)) and ``e2 = (x2 - r) / rho2``. Then for each of the
``2^n`` members ``g`` held for the whole run, the signs alone (``held``). A run is a
counterexample when the deployed step reports the state outside a tube at a sample (the
status of :func:`~stt_codegen.tube.cascade_reference.cascade_step`). The path is the
trajectory of a member of the class while it does not pass one point twice with two
different choices (then ``g(x)`` and ``f(x)`` are defined on it and extended off it
within the bounds, which are convex); the search is not exhaustive: finding none proves
nothing, finding one disproves a certificate of that class.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ...tube import cascade_reference, reference
from ...tube.parameters import TubeDesign
from ...tube.second_stage import SecondStage
from .cascade_sampled import CascadeClass

__all__ = ["CascadeExit", "STRATEGIES", "SUBSTEPS", "search_cascade"]

#: The greedy strategies (module docstring), then ``held``.
STRATEGIES = ("position", "velocity", "both", "held")
#: Runge-Kutta steps per interval when the drift depends on the velocity (``F1 > 0``).
SUBSTEPS = 8


@dataclass(frozen=True)
class CascadeExit:
    """A member of the class whose sampled cascade leaves a tube.

    Attributes
    ----------
    strategy : str
        One of :data:`STRATEGIES` (``held`` with the held member's diagonal).
    time : float
        The sample at which the step reports the state outside a tube, s.
    tube : {"position", "velocity"}
        Which tube was left (the position tube takes precedence, as in the status).
    depth : float
        ``max_i |e1_i|`` (position) or ``max_i |e2_i|`` (velocity) there, ``>= 1``.
    """

    strategy: str
    time: float
    tube: str
    depth: float

    def to_json(self) -> dict:
        """The exit as a JSON-ready dict."""
        return {"strategy": self.strategy, "time": self.time, "tube": self.tube,
                "depth": self.depth}


def _members(cls: CascadeClass, n: int) -> np.ndarray:
    """The diagonal extreme members, shape (2^n, n)."""
    return np.array(list(itertools.product((cls.g_min, cls.g_max), repeat=n)))


def _signs(n: int) -> np.ndarray:
    return np.array(list(itertools.product((-1.0, 1.0), repeat=n)))


def _advance(cls: CascadeClass, x1: np.ndarray, x2: np.ndarray, gu: np.ndarray,
             signs: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities after ``h`` for rows of ``g u`` and drift signs."""
    f0 = cls.drift_bounds(x2.shape[-1])
    if cls.drift_slope == 0.0:
        a = gu + signs * (f0 + cls.disturbance_bound)
        return x1 + x2 * h + 0.5 * a * h * h, x2 + a * h
    step = h / SUBSTEPS

    def rates(v):
        return gu + signs * (f0 + cls.drift_slope * np.abs(v)
                             + cls.disturbance_bound)
    for _ in range(SUBSTEPS):
        k1p, k1v = x2, rates(x2)
        k2p, k2v = x2 + 0.5 * step * k1v, rates(x2 + 0.5 * step * k1v)
        k3p, k3v = x2 + 0.5 * step * k2v, rates(x2 + 0.5 * step * k2v)
        k4p, k4v = x2 + step * k3v, rates(x2 + step * k3v)
        x1 = x1 + step / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p)
        x2 = x2 + step / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return x1, x2


def _errors(tube: TubeDesign, stage: SecondStage, x1, x2, t: float, dt: float, alpha):
    """The deployed step at rows of states: ``(u, alpha_next, |e1| max, |e2| max, inside
    position, inside velocity)``."""
    rows = x1.shape[0]
    times = np.full(rows, t)
    u, alpha_next, r, inside_p, inside_v, _within = cascade_reference.cascade_step(
        tube, stage, np.hstack([x1, x2]), times, dt, alpha)
    g_l, g_u, _, _ = reference.adaptive_tube(tube, times, alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        e1 = np.abs(2.0 * x1 - (g_u + g_l)) / (g_u - g_l)
    e2 = np.abs(x2 - r) / cascade_reference.velocity_tube(stage, times)
    return u, alpha_next, e1.max(axis=1), e2.max(axis=1), inside_p, inside_v


def _run(tube: TubeDesign, stage: SecondStage, cls: CascadeClass, x1: np.ndarray,
         x2: np.ndarray, horizon: float, strategy: str, members: np.ndarray,
         signs: np.ndarray) -> CascadeExit | None:
    """One adversarial run from ``(x1, x2)`` at ``t = 0``, ``alpha = 0``."""
    n = tube.dimension
    dt = 1.0 / tube.rate_hz
    steps = int(np.ceil(horizon * tube.rate_hz - 1e-9))
    choices = [(g, s) for g in members for s in signs]
    gains = np.array([c[0] for c in choices])
    sign_rows = np.array([c[1] for c in choices])
    alpha = np.zeros((1, 2 * n))
    u, alpha_next, e1, e2, inside_p, inside_v = _errors(tube, stage, x1[None], x2[None],
                                                        0.0, dt, alpha)
    if not (inside_p[0] and inside_v[0]):
        return CascadeExit(strategy, 0.0, "position" if not inside_p[0] else "velocity",
                           float(e1[0] if not inside_p[0] else e2[0]))
    for k in range(steps):
        t_next = (k + 1) * dt
        nx1, nx2 = _advance(cls, np.broadcast_to(x1, (len(choices), n)),
                            np.broadcast_to(x2, (len(choices), n)), gains * u[0],
                            sign_rows, dt)
        alphas = np.broadcast_to(alpha_next[0], (len(choices), 2 * n))
        cu, c_alpha, c_e1, c_e2, c_in_p, c_in_v = _errors(tube, stage, nx1, nx2, t_next, dt,
                                                          alphas)
        outside = (c_in_p == 0.0) | (c_in_v == 0.0)
        if np.any(outside):
            j = int(np.argmax(outside))
            position = c_in_p[j] == 0.0
            return CascadeExit(strategy, float(t_next), "position" if position else "velocity",
                               float(c_e1[j] if position else c_e2[j]))
        score = (c_e1 if strategy == "position" else c_e2 if strategy == "velocity"
                 else np.maximum(c_e1, c_e2))
        j = int(np.argmax(score))
        x1, x2 = nx1[j].copy(), nx2[j].copy()
        u, alpha_next = cu[j:j + 1], c_alpha[j:j + 1]
    return None


def search_cascade(tube: TubeDesign, stage: SecondStage, plant_class: CascadeClass,
                   initial_velocity, horizon: float | None = None,
                   strategies: tuple[str, ...] = STRATEGIES) -> list[CascadeExit]:
    """Search the class for members whose sampled cascade leaves a tube.

    Parameters
    ----------
    tube : TubeDesign
        The position tube (its ``rate_hz`` is the sampling rate, its ``initial_state``
        the start ``x1(0)``).
    stage : SecondStage
        The cascade's second stage.
    plant_class : CascadeClass
        The class searched (:func:`~.cascade_sampled.cascade_class` of a spec).
    initial_velocity : array_like, shape (n,)
        ``x2(0)``, state units per second.
    horizon : float, optional
        Seconds searched, default the tube's ``prescribed_time``.
    strategies : tuple of str, optional
        Among :data:`STRATEGIES`, in order.

    Returns
    -------
    list of CascadeExit
        One per strategy (and per held member) that left a tube; empty when none did,
        which proves nothing.

    Raises
    ------
    ValueError
        An unknown strategy.
    """
    unknown = [s for s in strategies if s not in STRATEGIES]
    if unknown:
        raise ValueError(f"unknown strategies {unknown}; known: {', '.join(STRATEGIES)}")
    n = tube.dimension
    horizon = tube.prescribed_time if horizon is None else float(horizon)
    x1 = np.array(tube.initial_state, dtype=float)
    x2 = np.array(initial_velocity, dtype=float)
    cls = plant_class
    members, signs = _members(cls, n), _signs(n)
    found = []
    with reference.numpy_math():
        for strategy in strategies:
            held = [members[i:i + 1] for i in range(len(members))] if strategy == "held" \
                else [members]
            for member in held:
                name = (strategy if strategy != "held"
                        else f"held g = diag({', '.join(f'{v:g}' for v in member[0])})")
                exit_ = _run(tube, stage, cls, x1, x2, horizon,
                             "both" if strategy == "held" else strategy, member, signs)
                if exit_ is not None:
                    found.append(CascadeExit(name, exit_.time, exit_.tube, exit_.depth))
    return found
