"""The certificate's result types and its report: every property with its margin.

:class:`Certificate` (one :class:`Margin` per property of :data:`PROPERTIES`),
:class:`Enclosure` (the tube's bounds per interval) and :class:`CertificateState` (what a
related certificate resumes from); :func:`certificate_report` reads the margins off a
final enclosure (:mod:`.refine` computes it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...rounding import distinct, round_down
from ...spec.loader import Spec
from ...tube import reference
from ...tube.parameters import TubeDesign

__all__ = ["Certificate", "CertificateState", "Enclosure", "MAX_MOVE_PER_SAMPLE", "Margin",
           "PROPERTIES", "ROUNDING_MARGIN", "certificate_report", "obstacle_separation",
           "point_tube"]

#: Margins below this (state units) count as failures: rounding in the enclosures.
ROUNDING_MARGIN = 1e-9
#: Largest distance a tube bound may move in one sampling period, as a fraction of the
#: tube's width there: a sampled controller cannot follow a faster tube.
MAX_MOVE_PER_SAMPLE = 0.25

#: Certified property names, in report order (``avoids obstacle j`` repeats per obstacle).
PROPERTIES = ("non-empty", "initial state inside", "inside state space", "avoids obstacle",
              "inside target after t_c", "sampling rate")


@dataclass(frozen=True)
class Margin:
    """One certified property: its smallest margin over time and where it occurs.

    Attributes
    ----------
    name : str
    passed : bool
        ``margin > ROUNDING_MARGIN`` (``>= 0`` for ``inside state space``, which the
        smooth max/min guarantee exactly).
    margin : float
        State units (tube widths for ``sampling rate``: the limit minus the largest
        move per period); positive means the property holds with that much room.
    time : float
        Start of the interval where the margin is smallest, seconds.
    detail : str
        Evidence in words.
    """

    name: str
    passed: bool
    margin: float
    time: float
    detail: str


@dataclass(frozen=True, eq=False)
class Enclosure:
    """Bounds of the tube over each certified interval.

    Attributes
    ----------
    t_start, t_end : ndarray, shape (K,)
        Seconds; the last interval ends at ``inf``.
    lower_min, lower_max, upper_min, upper_max : ndarray, shape (K, n)
        ``gamma_L`` and ``gamma_U`` lie in these ranges on the interval.
    alpha_min, alpha_max : ndarray, shape (K, 2n)
        The deployed ``alpha`` lies in this range on the interval.
    move_ratio : ndarray, shape (K,)
        Upper bound of ``max_i |gamma_dot_i| dt / gamma_d_i`` on the interval (0 where the
        enclosure's width is not positive: ``non-empty`` fails there).
    psi_min, psi_max : ndarray, shape (K, 2n)
        Range of ``psi`` (eq. (11)) on the interval.
    width_min : ndarray, shape (K, n)
        Lower bound of ``gamma_U - gamma_L`` on the interval: at least
        ``upper_min - lower_max``, and tighter where the box moves
        (:func:`~.enclosures.width_lower_bound`).
    """

    t_start: np.ndarray
    t_end: np.ndarray
    lower_min: np.ndarray
    lower_max: np.ndarray
    upper_min: np.ndarray
    upper_max: np.ndarray
    alpha_min: np.ndarray
    alpha_max: np.ndarray
    move_ratio: np.ndarray
    psi_min: np.ndarray
    psi_max: np.ndarray
    width_min: np.ndarray


@dataclass(frozen=True)
class CertificateState:
    """Where a certificate's refinement ended: enough to resume a related certificate.

    Attributes
    ----------
    points : tuple of int
        Sample indices starting the intervals of the final partition, increasing; the
        last starts the tail ``[T, inf)``.
    alpha_lo, alpha_hi : tuple of list of float, (K, 2n)
        Range of the deployed ``alpha`` on each interval.
    entries : tuple of (list, list)
        Lower and upper bounds of ``alpha`` at each interval's start.
    """

    points: tuple[int, ...] = ()
    alpha_lo: tuple[list[float], ...] = ()
    alpha_hi: tuple[list[float], ...] = ()
    entries: tuple[tuple[list[float], list[float]], ...] = ()


@dataclass(frozen=True)
class Certificate:
    """The tube certificate: every property with its margin.

    Attributes
    ----------
    horizon : float
        ``inf``: the certificate covers every ``t >= 0``.
    intervals : int
        Intervals of the final partition (the work done).
    margins : tuple of Margin
        In the order of :data:`PROPERTIES`.
    max_move_ratio : float
        Certified bound of ``|gamma_dot| dt / gamma_d`` over all ``t``.
    min_width : float
        Certified lower bound of ``min_t min_i gamma_d_i(t)``, state units, rounded down to
        :data:`~stt_codegen.rounding.DIGITS` significant digits (the same on every CPU).
    initial_error : float
        ``max_i |e_i|`` of ``x(0)`` in the tube at ``t = 0``.
    enclosure : Enclosure
    state : CertificateState
        The final partition and ``alpha`` bounds (to resume a related certificate from).
    decisive : str
        A property the tube fails for certain at some instant (refinement stopped there);
        ``""`` if none.
    work : int
        Intervals whose ``alpha`` bounds this certificate computed over all refinement
        rounds, those resumed from another certificate excluded (a deterministic measure of
        its cost).
    """

    horizon: float
    intervals: int
    margins: tuple[Margin, ...]
    max_move_ratio: float
    min_width: float
    initial_error: float
    enclosure: Enclosure = field(compare=False, repr=False)
    #: The final partition and alpha bounds (to resume a related certificate from).
    state: CertificateState = field(default_factory=lambda: CertificateState(),
                                    compare=False, repr=False)
    #: A property the tube fails for certain at some instant (refinement stopped there).
    decisive: str = ""
    #: Intervals whose ``alpha`` bounds this certificate computed, over all refinement
    #: rounds, those resumed from another certificate excluded (a deterministic measure
    #: of its cost).
    work: int = 0

    def first_failure(self) -> Margin | None:
        """The decisive failure if there is one, else the first property not proven."""
        if self.decisive:
            return next(m for m in self.margins if m.name == self.decisive)
        return next((m for m in self.margins if not m.passed), None)

    @property
    def passed(self) -> bool:
        return all(m.passed for m in self.margins)

    def margin(self, name: str) -> Margin:
        """The margin called ``name``."""
        return next(m for m in self.margins if m.name == name)


# --------------------------------------------------------------------------- report


def obstacle_separation(spec: Spec, enc: Enclosure, selected):
    """Separation of the enclosure from each spec obstacle of the boxes ``selected``.

    Parameters
    ----------
    spec : Spec
        The spec (its obstacles and their covering boxes).
    enc : Enclosure
        Bounds of ``gamma`` on ``K`` intervals.
    selected : list of int
        Indices of ``spec.obstacle_boxes()`` to measure against.

    Returns
    -------
    list of (int, ndarray (K,), list of int, ndarray (B, K), list of ndarray (K, n))
        Per spec obstacle ``j`` (indices of ``spec.obstacle_boxes()`` in ``selected``):
        ``j``, its separation per interval, its member boxes, their separations and
        their per-dimension gaps.
    """
    boxes = spec.obstacle_boxes()
    by_source: dict[int, list[int]] = {}
    for b in selected:
        by_source.setdefault(spec.obstacles[b].source, []).append(b)
    out = []
    for j, members in sorted(by_source.items()):
        # the separation from the union of a shape's covering boxes bounds the separation
        # from the shape itself (the union contains it)
        gaps = [np.maximum(np.array(boxes[b].lower) - enc.upper_max,
                           enc.lower_min - np.array(boxes[b].upper)) for b in members]
        seps = np.array([g.max(axis=1) for g in gaps])
        out.append((j, seps.min(axis=0), members, seps, gaps))
    return out


def _worst(values: np.ndarray, t: np.ndarray) -> tuple[float, float, int]:
    flat = values.min(axis=1) if values.ndim == 2 else values
    k = int(np.argmin(flat))
    return float(flat[k]), float(t[k]), k


def _below_rounding(margin: float) -> str:
    """What a failing margin adds to its text: one in ``(0, ROUNDING_MARGIN]`` prints as
    positive and fails because it is not above the enclosures' rounding."""
    return "" if margin > ROUNDING_MARGIN else (
        f" (a margin must exceed {ROUNDING_MARGIN:g}, the enclosures' rounding)")


def point_tube(design: TubeDesign, t: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """``gamma_L``, ``gamma_U`` of eq. (10) at ``t`` for ``alpha``, without their rates.

    The numbers of :func:`stt_codegen.tube.reference.adaptive_tube` (the same operations),
    at half its cost: the rates need ``psi`` and the adaptive law on top.

    Parameters
    ----------
    design : TubeDesign
    t : ndarray, shape (K,)
        Seconds.
    alpha : ndarray, shape (K, 2n)
        ``[alpha_L, alpha_U]``, state units.

    Returns
    -------
    gamma_L, gamma_U : ndarray, shape (K, n)
        State units.
    """
    n = design.dimension
    rho_l, rho_u, _, _ = reference.reach_tube(design, t, rates=False)
    beta_l, beta_u, _, _ = reference.circumvent(design, t, rates=False)
    nu = design.smoothness
    gamma_l = reference.smooth_max_pair(rho_l - alpha[:, :n], beta_l, nu)
    return gamma_l, -reference.smooth_max_pair(-(rho_u + alpha[:, n:]), -beta_u, nu)


def certificate_report(design: TubeDesign, spec: Spec, enc: Enclosure, selected, final: bool,
            budget_hit: bool, tail_start: float, max_intervals: int,
            narrowest: tuple[float, float] | None = None) -> Certificate:
    """The margins of the tube's properties from its enclosure over a partition.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    spec : Spec
        For the state space, obstacles and target set.
    enc : Enclosure
        Bounds of ``gamma`` on the final partition's ``K`` intervals.
    selected : list of int
        Indices of ``spec.obstacle_boxes()`` certified against.
    final : bool
        Also report ``inside target after t_c``.
    budget_hit : bool
        The refinement budget ran out: the messages of failed margins say so.
    tail_start : float
        Start of the tail interval ``[tail_start, inf)``, s.
    max_intervals : int
        The refinement budget (for the message).
    narrowest : (float, float), optional
        ``(width, time)`` of a sharper lower bound of the least width ``gamma_U -
        gamma_L`` (state units, s) than the enclosure's, if one was computed.

    Returns
    -------
    Certificate
        Margins in the order of :data:`PROPERTIES`, one ``avoids obstacle j`` per spec
        obstacle; ``state``, ``decisive`` and ``work`` at their defaults (the caller sets
        them).
    """
    t0 = enc.t_start
    margins = []
    note = (" (the certificate's refinement budget of "
            f"{max_intervals} intervals was exhausted)") if budget_hit else ""

    min_width, t = _worst(enc.width_min, t0)[:2] if narrowest is None else narrowest
    margins.append(Margin("non-empty", min_width > ROUNDING_MARGIN, min_width, t,
                          f"min width gamma_U - gamma_L >= {min_width:.6g} (interval at "
                          f"t = {t:.4f} s)" + _below_rounding(min_width) + note))

    x0 = np.array(design.initial_state)
    g_l0, g_u0 = point_tube(design, np.zeros(1), np.zeros((1, 2 * design.dimension)))
    g_l0, g_u0 = g_l0[0], g_u0[0]
    m0 = float(np.min(np.minimum(x0 - g_l0, g_u0 - x0)))
    margins.append(Margin("initial state inside", m0 > ROUNDING_MARGIN, m0, 0.0,
                          f"x(0) is {m0:.6g} inside the tube at t = 0" + _below_rounding(m0)))
    width0 = g_u0 - g_l0
    initial_error = (float(np.max(np.abs((2 * x0 - (g_u0 + g_l0)) / width0)))
                     if np.all(width0 > 0) else math.inf)

    lo, hi = np.array(design.state_lower), np.array(design.state_upper)
    room = np.minimum(enc.lower_min - lo, hi - enc.upper_max)
    m, t, _ = _worst(room, t0)
    # the smooth max/min keep gamma inside [beta_L, beta_U] within [X, X-bar] exactly
    margins.append(Margin("inside state space", m >= 0.0, m, t,
                          f"min distance to the state-space boundary {m:.6g} at t = {t:.4f} s"))

    for j, sep, members, seps, gaps in obstacle_separation(spec, enc, selected):
        m, t, k = _worst(sep, t0)
        worst_box = int(np.argmin(seps[:, k]))
        dim = int(np.argmax(gaps[worst_box][k]))
        what = f"obstacle {j}" + (f" (box {members[worst_box]} of its covering)"
                                  if len(members) > 1 else "")
        margins.append(Margin(f"avoids obstacle {j}", m > ROUNDING_MARGIN, m, t,
                              f"separation from {what} >= {m:.6g} along dimension {dim} "
                              f"(interval at t = {t:.4f} s)" if m > ROUNDING_MARGIN else
                              f"the tube may meet {what} on [{t:.4f}, "
                              f"{float(enc.t_end[k]):.4f}] s (separation {m:.3g})" + note))

    if final:
        late = enc.t_end > design.prescribed_time
        t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
        inside = np.minimum(enc.lower_min[late] - t_lo, t_hi - enc.upper_max[late])
        m, t, _ = _worst(inside, t0[late])
        margins.append(Margin("inside target after t_c", m > ROUNDING_MARGIN, m, t,
                              f"min distance inside the target {m:.6g} for t >= {t:.4f} s "
                              f"(every t >= {tail_start:.4f} s enclosed at once)"
                              + _below_rounding(m) + note))

    k = int(np.argmax(enc.move_ratio))
    ratio = float(enc.move_ratio[k])
    margins.append(Margin("sampling rate", ratio <= MAX_MOVE_PER_SAMPLE,
                          MAX_MOVE_PER_SAMPLE - ratio, float(t0[k]),
                          f"a tube bound moves at most {distinct(ratio, MAX_MOVE_PER_SAMPLE)}"
                          " tube widths in one sampling "
                          f"period at {design.rate_hz:g} Hz (limit {MAX_MOVE_PER_SAMPLE}; "
                          f"worst on the interval at t = {float(t0[k]):.3f} s)" + note))
    # The width the gains derive from, rounded down (still a certified lower bound) so that
    # it is the same whatever SIMD kernels computed the enclosures (docs/codegen.md).
    return Certificate(math.inf, int(t0.size), tuple(margins), ratio, round_down(min_width),
                       initial_error, enc)
