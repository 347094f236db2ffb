"""Continuous-time safety certificate of a designed tube (for all t, not just at samples).

The controller keeps ``x(t)`` strictly inside the box ``[gamma_L(t), gamma_U(t)]``
(Theorem 4.1), so if that box is non-empty, misses every obstacle, stays in the state
space and, from ``t_c`` on, lies in the target, then Definition 2.1 holds whatever the
dynamics (design notes, item 11). This module proves those four properties on
``[0, t_end]`` for the tube the deployed controller enforces: ``alpha`` is the sequence
``alpha_k`` of the controller's own implicit steps, linearly interpolated between the
sampling instants.

The proof is by enclosure on every sampling interval ``[t_k, t_{k+1}]``:

* ``rho_L``, ``rho_U`` (eq. (4)) are monotone in ``t``: their range is spanned by the
  end-point values;
* each bump of eqs. (7)-(8) increases up to its centre ``m`` and decreases after: its
  range is spanned by the end-point values, and by 1 where ``m`` lies inside;
* the smooth max/min of eqs. (9)-(10) are non-decreasing in every argument, and
  ``gamma_L`` is non-increasing in ``alpha_L`` and ``gamma_U`` non-decreasing in
  ``alpha_U``; the interpolated ``alpha`` lies between ``alpha_k`` and ``alpha_{k+1}``.

Evaluating (9)-(10) at the ends of those ranges encloses ``gamma_L(t)`` and
``gamma_U(t)`` for every ``t`` in the interval. Each property is then checked on the
enclosures with a margin of at least :data:`ROUNDING_MARGIN` (for floating-point rounding).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tube import reference
from .samples import TubeSamples, sample_tube
from ..spec.loader import Spec
from ..tube.parameters import TubeDesign

#: Margins below this (state units) count as failures: rounding in the enclosures.
ROUNDING_MARGIN = 1e-9


@dataclass(frozen=True)
class Margin:
    """One certified property: its smallest margin over time and where it occurs.

    Attributes
    ----------
    name : str
    passed : bool
        ``margin > ROUNDING_MARGIN``.
    margin : float
        State units; positive means the property holds with that much room.
    time : float
        Start of the sampling interval where the margin is smallest, seconds.
    detail : str
        Evidence in words.
    """

    name: str
    passed: bool
    margin: float
    time: float
    detail: str


@dataclass(frozen=True)
class Certificate:
    """The tube certificate: every property with its margin."""

    horizon: float
    intervals: int
    margins: tuple[Margin, ...]

    @property
    def passed(self) -> bool:
        return all(m.passed for m in self.margins)

    def first_failure(self) -> Margin | None:
        return next((m for m in self.margins if not m.passed), None)


@dataclass(frozen=True)
class Enclosure:
    """Bounds of the tube over each sampling interval: arrays of shape (K, n)."""

    t_start: np.ndarray
    t_end: np.ndarray
    lower_min: np.ndarray
    lower_max: np.ndarray
    upper_min: np.ndarray
    upper_max: np.ndarray


def _bump_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray, center: float,
                radius: float) -> tuple[np.ndarray, np.ndarray]:
    k = design.circumvent_sharpness
    b0, _ = reference.bump(t0, center, radius, k)
    b1, _ = reference.bump(t1, center, radius, k)
    low = np.minimum(b0, b1)
    high = np.where((t0 <= center) & (center <= t1), 1.0, np.maximum(b0, b1))
    return low, high


def circumvent_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray):
    """Ranges of ``beta_L`` and ``beta_U`` (eq. (9)) over each interval, shape (K, n) each.

    ``beta_L`` is non-decreasing and ``beta_U`` non-increasing in every bump value, so
    eq. (9) at the ends of the bumps' ranges gives the ends of theirs.
    """
    ranges = [_bump_range(design, t0, t1, c.center, c.radius) for c in design.circumvents]
    lower_min, upper_max, _ = reference.circumvent_from_bumps(design, [r[0] for r in ranges],
                                                              t0.size)
    lower_max, upper_min, _ = reference.circumvent_from_bumps(design, [r[1] for r in ranges],
                                                              t0.size)
    return (lower_min, lower_max), (upper_min, upper_max)


def enclose_tube(design: TubeDesign, samples: TubeSamples) -> Enclosure:
    """Enclosures of ``gamma_L`` and ``gamma_U`` on every sampling interval of ``samples``."""
    n = design.dimension
    t0, t1 = samples.t[:-1], samples.t[1:]
    rho_l0, rho_u0, _, _ = reference.reach_tube(design, t0)
    rho_l1, rho_u1, _, _ = reference.reach_tube(design, t1)
    (bl_lo, bl_hi), (bu_lo, bu_hi) = circumvent_range(design, t0, t1)
    a0, a1 = samples.alpha[:-1], samples.alpha[1:]
    al_lo, al_hi = np.minimum(a0[:, :n], a1[:, :n]), np.maximum(a0[:, :n], a1[:, :n])
    au_lo, au_hi = np.minimum(a0[:, n:], a1[:, n:]), np.maximum(a0[:, n:], a1[:, n:])
    nu = design.smoothness

    def smax(a, b):
        return reference.smooth_max(np.stack([a, b], -1), nu)[0]

    def smin(a, b):
        return -smax(-a, -b)

    lower_min = smax(np.minimum(rho_l0, rho_l1) - al_hi, bl_lo)
    lower_max = smax(np.maximum(rho_l0, rho_l1) - al_lo, bl_hi)
    upper_min = smin(np.minimum(rho_u0, rho_u1) + au_lo, bu_lo)
    upper_max = smin(np.maximum(rho_u0, rho_u1) + au_hi, bu_hi)
    return Enclosure(t0, t1, lower_min, lower_max, upper_min, upper_max)


def _worst(values: np.ndarray, t: np.ndarray) -> tuple[float, float, int]:
    flat = values.min(axis=1) if values.ndim == 2 else values
    k = int(np.argmin(flat))
    return float(flat[k]), float(t[k]), k


def certify_tube(design: TubeDesign, spec: Spec, horizon: float | None = None,
                 obstacles: list[int] | None = None,
                 samples: TubeSamples | None = None) -> Certificate:
    """Prove the tube's safety properties for every ``t`` in ``[0, horizon]``.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
        For the state space, obstacles and target set.
    horizon : float, optional
        ``t_end``, seconds; default that of :func:`sample_tube` (``1.1 t_c``).
    obstacles : list of int, optional
        Obstacles to certify against; default all.
    samples : TubeSamples, optional
        Precomputed :func:`sample_tube` output (then ``horizon`` is ignored).

    Returns
    -------
    Certificate
        Properties ``non-empty``, ``initial state inside``, ``inside state space``,
        ``avoids obstacle j`` (one per obstacle) and ``inside target after t_c``.
    """
    s = samples if samples is not None else sample_tube(design, horizon)
    enc = enclose_tube(design, s)
    t0 = enc.t_start
    margins = []

    width = enc.upper_min - enc.lower_max
    m, t, k = _worst(width, t0)
    margins.append(Margin("non-empty", m > ROUNDING_MARGIN, m, t,
                          f"min width gamma_U - gamma_L >= {m:.6g} (interval at t = {t:.4f} s)"))

    x0 = np.array(design.initial_state)
    g_l0, g_u0 = s.gamma_lower[0], s.gamma_upper[0]
    m0 = float(np.min(np.minimum(x0 - g_l0, g_u0 - x0)))
    margins.append(Margin("initial state inside", m0 > ROUNDING_MARGIN, m0, 0.0,
                          f"x(0) is {m0:.6g} inside the tube at t = 0"))

    lo, hi = np.array(design.state_lower), np.array(design.state_upper)
    room = np.minimum(enc.lower_min - lo, hi - enc.upper_max)
    m, t, _ = _worst(room, t0)
    # the smooth max/min keep gamma inside [beta_L, beta_U] within [X, X-bar] exactly
    margins.append(Margin("inside state space", m >= 0.0, m, t,
                          f"min distance to the state-space boundary {m:.6g} at t = {t:.4f} s"))

    boxes = spec.obstacle_boxes()
    selected = range(len(boxes)) if obstacles is None else obstacles
    by_source: dict[int, list[int]] = {}
    for b in selected:
        by_source.setdefault(spec.obstacles[b].source, []).append(b)
    for j, members in sorted(by_source.items()):
        # the separation from the union of a shape's covering boxes bounds the separation
        # from the shape itself (the union contains it)
        seps, gaps_all = [], []
        for b in members:
            box = boxes[b]
            gaps = np.maximum(np.array(box.lower) - enc.upper_max,
                              enc.lower_min - np.array(box.upper))
            seps.append(gaps.max(axis=1))
            gaps_all.append(gaps)
        sep = np.min(seps, axis=0)
        m, t, k = _worst(sep, t0)
        worst_box = int(np.argmin([v[k] for v in seps]))
        dim = int(np.argmax(gaps_all[worst_box][k]))
        what = f"obstacle {j}" + (f" (box {members[worst_box]} of its covering)"
                                  if len(members) > 1 else "")
        margins.append(Margin(f"avoids obstacle {j}", m > ROUNDING_MARGIN, m, t,
                              f"separation from {what} >= {m:.6g} along dimension {dim} "
                              f"(interval at t = {t:.4f} s)" if m > ROUNDING_MARGIN else
                              f"the tube may meet {what} on [{t:.4f}, "
                              f"{float(enc.t_end[k]):.4f}] s (separation {m:.3g})"))

    late = enc.t_end > design.prescribed_time
    t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
    if late.any():
        inside = np.minimum(enc.lower_min[late] - t_lo, t_hi - enc.upper_max[late])
        m, t, _ = _worst(inside, t0[late])
        margins.append(Margin("inside target after t_c", m > ROUNDING_MARGIN, m, t,
                              f"min distance inside the target {m:.6g} at t = {t:.4f} s"))
    else:
        margins.append(Margin("inside target after t_c", False, -math.inf, s.t[-1],
                              "the horizon ends before t_c"))
    return Certificate(float(s.t[-1]), int(t0.size), tuple(margins))
