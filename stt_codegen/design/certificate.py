"""Continuous-time safety certificate of a designed tube, for every ``t >= 0``.

The controller keeps ``x(t)`` strictly inside the box ``[gamma_L(t), gamma_U(t)]``
(Theorem 4.1), so if that box is non-empty, misses every obstacle, stays in the state
space and, from ``t_c`` on, lies in the target, then Definition 2.1 holds whatever the
dynamics (docs/decisions.md, decision 11). This module proves those properties for the tube the
deployed controller enforces: ``alpha`` follows the controller's own backward-Euler step
of (11) at its sampling rate (linearly interpolated between the instants), from
``alpha(0) = 0``. It also bounds how far a tube bound moves in one sampling period
(a sampled controller cannot follow a faster tube).

The proof works on long intervals ``[t_a, t_b]`` of sampling instants and splits an
interval in two only where a margin is too thin (adaptive bisection); nothing is
allocated per sample, and the last interval ``[T, inf)`` is closed analytically. On an
interval (proofs in ``docs/design.md``):

* ``rho`` is monotone on every reach segment, so its range is spanned by its values at
  the interval's ends and at the segment boundaries inside;
* each bump of eqs. (7)-(8) rises up to its centre and falls after it: its range is
  spanned by the end values, and by 1 where the centre lies inside; ``|b_dot|`` is
  unimodal on each half-window;
* eq. (9) (``X + F_nu``, ``X-bar - F_nu``) is monotone in every bump, and the smooth
  max/min of eq. (10) in every argument;
* ``alpha``: the implicit step's root ``a+`` of ``c a - a_k - dt theta / (psi + a)^2``,
  ``c = 1 + kappa dt``, increases with ``a_k`` and ``theta`` and decreases with ``psi``.
  With ``psi >= psi_lo`` and ``theta <= theta_hi`` on the interval the deployed sequence
  stays below the constant-coefficient one, which moves monotonically to its fixed point
  ``a*`` (``kappa a = theta / (psi + a)^2``) with ``a_N - a* <= (a_0 - a*) c^-N``;
  lower bounds alike. The deployed Newton iterate lies at or below the root, so every
  upper bound on ``alpha`` (what could widen the tube into an obstacle) holds for it
  exactly.
* after ``T`` (every window closed, the last segment ended, ``t >= t_c``) ``psi`` is
  constant, so ``alpha`` stays between its value at ``T`` and ``a*`` for ever.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..spec.loader import Spec
from ..tube import reference
from ..tube.parameters import LOWER, TANH, TubeDesign

#: Margins below this (state units) count as failures: rounding in the enclosures.
ROUNDING_MARGIN = 1e-9
#: Largest distance a tube bound may move in one sampling period, as a fraction of the
#: tube's width there: a sampled controller cannot follow a faster tube.
MAX_MOVE_PER_SAMPLE = 0.25
#: Most intervals the adaptive bisection may create before it gives up (the certificate
#: then fails with that reason); the work is linear in it.
MAX_INTERVALS = 200_000
#: A thin interval is cut into this many pieces (fewer rounds than bisection).
SPLIT = 4
#: Shortest interval the bisection creates, seconds (or one sampling period if longer):
#: at very high rates the enclosures need no finer time resolution than this.
MIN_INTERVAL = 1e-4
#: Intervals of at most this many steps follow the extreme implicit steps one by one.
EXACT_STEPS = 4
#: The narrowest width (the gain of law (13) comes from it) is sharpened on the intervals
#: whose width bound is within this fraction of the narrowest ...
WIDTH_BAND = 0.02
#: ... cut into this many pieces, this many times.
WIDTH_PIECES = 16
WIDTH_ROUNDS = 2
#: Relative width at which :func:`step_root` stops refining its (rigorous) bracket.
STEP_ROOT_TOLERANCE = 1e-13

#: Certified property names, in report order (``avoids obstacle j`` repeats per obstacle).
PROPERTIES = ("non-empty", "initial state inside", "inside state space", "avoids obstacle",
              "inside target after t_c", "sampling rate")


def _tanh_rate_peak() -> float:
    lo, hi = 0.5, 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if (1.0 + mid) * math.tanh(mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


#: ``w*``, the root of ``(1 + w) tanh w = 1``: the tanh profile's rate peaks at
#: ``tau = w* / (1 + w*)`` (see ``verify.lemma.reach_rate_bound``).
_W_STAR = _tanh_rate_peak()


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
        Certified lower bound of ``min_t min_i gamma_d_i(t)``, state units.
    initial_error : float
        ``max_i |e_i|`` of ``x(0)`` in the tube at ``t = 0``.
    enclosure : Enclosure
    """

    horizon: float
    intervals: int
    margins: tuple[Margin, ...]
    max_move_ratio: float
    min_width: float
    initial_error: float
    enclosure: Enclosure = field(compare=False, repr=False)
    #: The final partition and alpha bounds (to resume a related certificate from).
    state: tuple = field(default=((), [], [], []), compare=False, repr=False)
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


# --------------------------------------------------------------------------- ranges


def _bump_peaks(sharpness: float) -> float:
    """``z*`` where ``|b_dot|`` peaks, as a fraction of the half-window (``verify.lemma``)."""
    return math.sqrt(((1.0 - sharpness) + math.sqrt((1.0 - sharpness) ** 2 + 3.0)) / 3.0)


def bump_ranges(c, t0: np.ndarray, t1: np.ndarray) -> tuple[np.ndarray, ...]:
    """Range of one bump and of its rate ``b_dot`` on each interval, shape (K,) each.

    The bump rises up to its centre and falls after it; ``b_dot`` is 0 at the window's
    edges and centre and monotone between them and its peaks ``m -+ r z*``, so its
    extremes on an interval are at the ends or at those points inside.

    Returns
    -------
    low, high, rate_min, rate_max : ndarray, shape (K,)
    """
    z = _bump_peaks(c.sharpness)
    points = [t0, t1, np.clip(c.center, t0, t1)] + [
        np.clip(c.center + sign * c.radius * z, t0, t1) for sign in (-1, 1)]
    values, rates = reference.bump(np.concatenate(points), c.center, c.radius, c.sharpness)
    values = values.reshape(len(points), -1)
    rates = rates.reshape(len(points), -1)
    low = np.minimum(values[0], values[1])
    high = np.where((t0 <= c.center) & (c.center <= t1), 1.0, np.maximum(values[0], values[1]))
    return low, high, rates.min(axis=0), rates.max(axis=0)


def circumvent_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray):
    """Ranges of ``beta_L`` and ``beta_U`` (eq. (9)) over each interval, shape (K, n) each.

    ``beta_L`` is non-decreasing and ``beta_U`` non-increasing in every bump value, so
    eq. (9) at the ends of the bumps' ranges gives the ends of theirs.
    """
    t0, t1 = np.atleast_1d(t0), np.atleast_1d(t1)
    ranges = [bump_ranges(c, t0, t1) for c in design.circumvents]
    lower_min, upper_max, _ = reference.circumvent_from_bumps(design, [r[0] for r in ranges],
                                                              t0.size)
    lower_max, upper_min, _ = reference.circumvent_from_bumps(design, [r[1] for r in ranges],
                                                              t0.size)
    return (lower_min, lower_max), (upper_min, upper_max)


def _circumvent_rate(design: TubeDesign, t0: np.ndarray, t1: np.ndarray):
    """Ranges of ``beta_L_dot`` and ``beta_U_dot`` per interval, shape (K, n) each.

    ``beta_L_dot = sum_j w_j B^j b_dot_j`` with weights ``w_j`` in ``[0, 1]``
    (:func:`~stt_codegen.tube.reference.open_bump_sum`), ``beta_U_dot`` its negative.

    Returns
    -------
    (lower_min, lower_max), (upper_min, upper_max)
    """
    n = design.dimension
    lo_l, hi_l = np.zeros((t0.size, n)), np.zeros((t0.size, n))
    lo_u, hi_u = np.zeros((t0.size, n)), np.zeros((t0.size, n))
    for c in design.circumvents:
        _, _, r_min, r_max = bump_ranges(c, t0, t1)
        i = c.dimension
        if c.side == LOWER:
            lo_l[:, i] += c.height * np.minimum(r_min, 0.0)
            hi_l[:, i] += c.height * np.maximum(r_max, 0.0)
        else:
            lo_u[:, i] -= c.height * np.maximum(r_max, 0.0)
            hi_u[:, i] -= c.height * np.minimum(r_min, 0.0)
    return (lo_l, hi_l), (lo_u, hi_u)


def reach_range(design: TubeDesign, t0: np.ndarray, t1: np.ndarray):
    """Ranges of ``rho_L``, ``rho_U`` and of their rates per interval, shape (K, n) each.

    ``rho`` is monotone on each segment; its rate has one sign there and is unimodal
    (peak at ``tau = w*/(1+w*)`` for ``"tanh"``, ``1/2`` for ``"smoothstep"``) and 0 at a
    segment's end; evaluated at a boundary it is the right limit, so 0 joins the range
    of an interval with a segment end inside.

    Returns
    -------
    (lower_min, lower_max), (upper_min, upper_max), ((rate_lower_min, rate_lower_max),
    (rate_upper_min, rate_upper_max))
    """
    edges = sorted({s.start for s in design.segments} | {s.end for s in design.segments})
    peaks = [s.start + s.duration * (_W_STAR / (1.0 + _W_STAR) if s.profile == TANH else 0.5)
             for s in design.segments]
    points = [t0, t1] + [np.clip(e, t0, t1) for e in edges]
    value_points = len(points)
    points += [np.clip(p, t0, t1) for p in peaks]
    rho_l, rho_u, rate_l, rate_u = reference.reach_tube(design, np.concatenate(points))
    shape = (len(points), t0.size, design.dimension)
    rho_l, rho_u = rho_l.reshape(shape)[:value_points], rho_u.reshape(shape)[:value_points]
    rate_l, rate_u = rate_l.reshape(shape), rate_u.reshape(shape)
    ends = np.zeros(t0.shape, dtype=bool)
    for seg in design.segments:
        ends |= (t0 < seg.end) & (seg.end <= t1)
    zero = np.where(ends[:, None], 0.0, np.nan)

    def span(rate):
        return np.fmin(rate.min(0), zero), np.fmax(rate.max(0), zero)

    return ((rho_l.min(0), rho_l.max(0)), (rho_u.min(0), rho_u.max(0)),
            (span(rate_l), span(rate_u)))


def alpha_fixed_point(psi: np.ndarray, theta: np.ndarray, kappa: float) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    """Bracket ``[lo, hi]`` of ``a*``, the root of ``kappa a = theta / (psi + a)^2`` with ``psi + a > 0``.

    ``f(a) = theta / (psi + a)^2 - kappa a`` is decreasing and convex on ``a > -psi``, with
    slope ``<= -kappa``. Newton starts at ``theta / (kappa psi^2)`` (``psi > 0``; right of
    the root, so the first step lands left of it) or just right of the pole (``f >= 0``),
    and from the left rises monotonically to the root. Every iterate ``x`` bounds the root:
    from below where ``f(x) >= 0``, from above otherwise, and then its Newton point bounds
    it from below (convexity); a probe right of a left iterate (twice its Newton step and
    a few ulps) bounds it from above where ``f <= 0`` there. Where a Newton step would
    leave the bracket (or ``x`` rounds onto the pole) the next point is the bracket's
    middle. Iterates until the bracket is ``1e-11`` relative (or ``1e-16`` absolute)
    wide; both ends are widened by ``1e-13`` relative for rounding.

    Parameters
    ----------
    psi, theta : ndarray, same shape
        State units and ``1/s`` state units^3 (eq. (11)); ``theta >= 0``.
    kappa : float
        ``1/s``.

    Returns
    -------
    lo, hi : ndarray, the shape of ``psi``
        ``0`` where ``theta = 0``.
    """
    pole = np.maximum(0.0, -psi)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        # right of the pole, f >= 0 at pole + eps: theta/eps^2 >= kappa (eps + max(-psi, 0))
        eps = np.minimum(np.cbrt(theta / (2.0 * kappa)),
                         np.sqrt(theta / (2.0 * kappa * np.maximum(-psi, 1e-300))))
        lo, hi = pole, pole + np.cbrt(theta / kappa)
        # psi > 0: theta / (kappa psi^2), right of the root and close to it when a* << psi
        x = np.where(psi > 0.0, np.minimum(theta / (kappa * psi * psi), hi), pole + eps)
        for _ in range(100):
            z = psi + x
            f = theta / (z * z) - kappa * x
            newton = x - f / (-2.0 * theta / (z * z * z) - kappa)
            usable = (z > 0.0) & np.isfinite(newton)        # else: x rounds onto the pole
            left = f >= 0.0                                  # x left of the root
            # right of a left iterate by twice its Newton step and a few ulps: an upper
            # bound wherever f <= 0 there
            probe = x + 2.0 * (newton - x) + 4.0 * np.spacing(x)
            z_probe = psi + probe
            above = (z_probe > 0.0) & (theta / (z_probe * z_probe) - kappa * probe <= 0.0)
            lo = np.where(usable, np.maximum(lo, np.where(left, x, newton)), lo)
            hi = np.where(usable, np.minimum(hi, np.where(left, np.where(above, probe, hi), x)),
                          hi)
            if np.all(hi - lo <= 1e-11 * hi + 1e-16):
                break
            # Newton, or bisection where Newton is not usable or leaves the bracket
            inside = usable & (newton >= lo) & (newton <= hi)
            x = np.where(inside, newton, 0.5 * (lo + hi))
    done = theta > 0.0
    return (np.where(done, np.maximum(pole, lo * (1.0 - 1e-13)), 0.0),
            np.where(done, hi * (1.0 + 1e-13) + 1e-300, 0.0))


# --------------------------------------------------------------------------- intervals


@dataclass(frozen=True)
class _Pieces:
    """What an interval contributes, vectorized over the K intervals of a partition."""

    rho_l: tuple
    rho_u: tuple
    beta_l: tuple
    beta_u: tuple
    rho_rate: tuple
    beta_rate: tuple
    psi_lo: np.ndarray
    psi_hi: np.ndarray


def _pieces(design: TubeDesign, t0: np.ndarray, t1: np.ndarray) -> _Pieces:
    rho_l, rho_u, rho_rate = reach_range(design, t0, t1)
    beta_l, beta_u = circumvent_range(design, t0, t1)
    beta_rate = _circumvent_rate(design, t0, t1)
    psi_lo = np.concatenate([beta_u[0] - rho_l[1], rho_u[0] - beta_l[1]], axis=1)
    psi_hi = np.concatenate([beta_u[1] - rho_l[0], rho_u[1] - beta_l[0]], axis=1)
    return _Pieces(rho_l, rho_u, beta_l, beta_u, rho_rate, beta_rate, psi_lo, psi_hi)


def _alpha_ranges(design: TubeDesign, psi_lo: np.ndarray, psi_hi: np.ndarray,
                  steps: np.ndarray, start: tuple[list, list]):
    """Ranges of the deployed ``alpha`` on each interval, carried from bounds at the first.

    On an interval of ``N`` steps with ``psi`` in ``[psi_lo, psi_hi]``, the deployed
    sequence lies between the constant-coefficient sequences of (``psi_hi``,
    ``theta_lo``) and (``psi_lo``, ``theta_hi``) from the bounds ``A`` at its start; each
    moves monotonically to its fixed point ``a*``. With ``f(a) = theta/(psi+a)^2 - kappa a``
    (decreasing): a sequence moving towards ``a*`` is never behind one implicit step of
    length ``N dt`` from ``A``, nor behind ``a* -+ |A - a*| q^N`` with
    ``q = 1 / (c + 2 dt theta / z^3)`` (convexity of ``1/z^2``); one moving away from
    ``A`` is never ahead of ``A + N dt f(A)``, nor past ``a*``. ``alpha >= 0`` always.
    At most :data:`EXACT_STEPS` steps follow the extreme implicit steps one by one.

    Parameters
    ----------
    psi_lo, psi_hi : ndarray, shape (K, 2n)
    steps : ndarray, shape (K,)
        Steps per interval (``inf`` for the tail).
    start : (list, list)
        Lower and upper bounds of ``alpha`` at the first interval's start.

    Returns
    -------
    rows_lo, rows_hi : list of list of float, (K, 2n)
        Range of ``alpha`` on each interval.
    entries : list of (list, list)
        Bounds of ``alpha`` at each interval's start (to resume from).
    """
    kappa, dt = design.kappa, 1.0 / design.rate_hz
    c = 1.0 + kappa * dt
    theta_hi = reference.trigger(design, psi_lo)
    theta_lo = reference.trigger(design, psi_hi)
    star_hi = alpha_fixed_point(psi_lo, theta_hi, kappa)[1]
    star_lo = alpha_fixed_point(psi_hi, theta_lo, kappa)[0]
    with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
        q_lo = 1.0 / (c + 2.0 * dt * theta_lo / (psi_hi + star_lo) ** 3)
        decay_lo = np.where(np.isinf(steps)[:, None], 0.0,
                            np.power(q_lo, np.minimum(steps, 1e300)[:, None]))
    decay_lo = np.where(np.isnan(decay_lo), 1.0, decay_lo)   # no rate known: monotone only
    k_count, m = star_hi.shape
    a_lo, a_hi = list(start[0]), list(start[1])
    s_lo, s_hi = star_lo.tolist(), star_hi.tolist()
    d_lo, n_steps = decay_lo.tolist(), steps.tolist()
    out_lo, out_hi = [[0.0] * m for _ in range(k_count)], [[0.0] * m for _ in range(k_count)]
    p_lo, p_hi = psi_lo.tolist(), psi_hi.tolist()
    t_lo, t_hi = theta_lo.tolist(), theta_hi.tolist()
    two_dt = 2.0 * dt
    entries = []
    for k in range(k_count):
        entries.append((list(a_lo), list(a_hi)))
        sl, sh, row_lo, row_hi, steps_k = s_lo[k], s_hi[k], out_lo[k], out_hi[k], n_steps[k]
        if steps_k <= EXACT_STEPS:
            # few steps: follow the extreme backward-Euler sequences exactly
            for i in range(m):
                lo_i, hi_i = a_lo[i], a_hi[i]
                low, high = lo_i, hi_i
                for _ in range(int(steps_k)):
                    lo_i = max(step_root(lo_i, p_hi[k][i], t_lo[k][i], dt, c)[0], 0.0)
                    hi_i = step_root(hi_i, p_lo[k][i], t_hi[k][i], dt, c)[1]
                    low, high = min(low, lo_i), max(high, hi_i)
                row_lo[i], row_hi[i], a_lo[i], a_hi[i] = low, high, lo_i, hi_i
            continue
        if math.isinf(steps_k):
            # psi is constant from here on: alpha moves monotonically to a* for ever
            for i in range(m):
                row_lo[i] = min(a_lo[i], sl[i])
                row_hi[i] = max(a_hi[i], sh[i])
            continue
        span = steps_k * dt
        c_span = 1.0 + kappa * span
        for i in range(m):
            lo_i, hi_i = a_lo[i], a_hi[i]
            # lower sequence (psi_hi, theta_lo)
            if lo_i <= sl[i]:        # rising: one implicit step of N dt lags behind
                end = max(step_root(lo_i, p_hi[k][i], t_lo[k][i], span, c_span)[0],
                          sl[i] - (sl[i] - lo_i) * d_lo[k][i])
                row_lo[i] = lo_i
            else:                    # falling: no faster than its initial rate
                z = p_hi[k][i] + lo_i
                end = sl[i] if not z > 0.0 else max(
                    sl[i], lo_i + span * (t_lo[k][i] / (z * z) - kappa * lo_i))
                row_lo[i] = end
            a_lo[i] = end if end > 0.0 else 0.0
            # upper sequence (psi_lo, theta_hi)
            if hi_i >= sh[i]:        # falling: one implicit step of N dt lags behind
                q = 1.0 / (c + two_dt * t_hi[k][i] / (p_lo[k][i] + hi_i) ** 3)
                end = min(step_root(hi_i, p_lo[k][i], t_hi[k][i], span, c_span)[1],
                          sh[i] + (hi_i - sh[i]) * q ** steps_k)
                row_hi[i] = hi_i
            else:                    # rising: no faster than its initial rate
                z = p_lo[k][i] + hi_i
                end = sh[i] if not z > 0.0 else min(
                    sh[i], hi_i + span * (t_hi[k][i] / (z * z) - kappa * hi_i))
                row_hi[i] = end
            a_hi[i] = end
    return out_lo, out_hi, entries


def step_root(a: float, psi: float, theta: float, dt: float, c: float) -> tuple[float, float]:
    """Bracket of the backward-Euler root ``a+`` of ``g(x) = c x - a - dt theta / (psi + x)^2``.

    ``g`` has slope ``>= c`` on ``x > -psi``, so for any ``x`` there
    ``|a+ - x| <= |g(x)| / c``: the bracket is rigorous after any number of Newton
    iterations. They start at ``a`` (``alpha`` moves little per step) or, where
    ``psi + a <= 0``, at the left start of :func:`stt_codegen.tube.model.implicit_alpha_update`,
    and stop once the bracket is :data:`STEP_ROOT_TOLERANCE` relative wide.
    """
    big_a = dt * theta
    if not big_a > 0.0:
        return a / c, a / c
    x = a
    for _ in range(6):
        z = psi + x
        if not z > 0.0:
            break
        zz = z * z
        g = c * x - a - big_a / zz
        if abs(g) <= STEP_ROOT_TOLERANCE * c * x:
            return _root_bracket(x, g, c, a + big_a / zz)
        x_next = x - g / (c + 2.0 * big_a / (zz * z))
        if x_next == x:
            break
        x = x_next
    if not psi + x > 0.0:
        # left start (g <= 0 there): Newton then rises monotonically inside the domain
        q = max(-c * psi - a, 1e-300)
        x = max(a / c, -psi + min((big_a / (2.0 * c)) ** (1.0 / 3.0),
                                  math.sqrt(big_a / (2.0 * q))))
        for _ in range(60):
            z = psi + x
            x_next = x - (c * x - a - big_a / (z * z)) / (c + 2.0 * big_a / (z * z * z))
            if not x_next > x:
                break
            x = x_next
    z = psi + x
    g = c * x - a - big_a / (z * z)
    return _root_bracket(x, g, c, a + big_a / (z * z))


def _root_bracket(x: float, g: float, c: float, terms: float) -> tuple[float, float]:
    """``[x, x - g/c]`` or ``[x - g/c, x]`` (slope ``>= c``), widened by the rounding of
    ``g = c x - terms`` (a few ulps of its largest term)."""
    slack = 1e-15 * (c * abs(x) + terms) / c
    lo, hi = (x - g / c, x) if g > 0.0 else (x, x - g / c)
    return lo - slack, hi + slack


def _enclose(design: TubeDesign, pieces: _Pieces, alpha_min, alpha_max, t0, t1) -> Enclosure:
    n = design.dimension
    nu = design.smoothness

    def smax(a, b):
        return reference.smooth_max(np.stack([a, b], -1), nu)[0]

    def smin(a, b):
        return -smax(-a, -b)

    al_lo, al_hi = alpha_min[:, :n], alpha_max[:, :n]
    au_lo, au_hi = alpha_min[:, n:], alpha_max[:, n:]
    lower_min = smax(pieces.rho_l[0] - al_hi, pieces.beta_l[0])
    lower_max = smax(pieces.rho_l[1] - al_lo, pieces.beta_l[1])
    upper_min = smin(pieces.rho_u[0] + au_lo, pieces.beta_u[0])
    upper_max = smin(pieces.rho_u[1] + au_hi, pieces.beta_u[1])
    # alpha_dot = theta(psi) / (psi + alpha)^2 - kappa alpha decreases in alpha and psi
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        z_lo = pieces.psi_lo + alpha_min
        fast = np.where(z_lo > 0, reference.trigger(design, pieces.psi_lo) / (z_lo * z_lo), np.inf)
        slow = reference.trigger(design, pieces.psi_hi) / (pieces.psi_hi + alpha_max) ** 2
    adot_max = fast - design.kappa * alpha_min
    adot_min = slow - design.kappa * alpha_max
    # gamma_dot is a convex combination of (rho_dot -+ alpha_dot) and beta_dot (eq. (10))
    (rl_min, rl_max), (ru_min, ru_max) = pieces.rho_rate
    (bl_min, bl_max), (bu_min, bu_max) = pieces.beta_rate
    gl_min = np.minimum(rl_min - adot_max[:, :n], bl_min)
    gl_max = np.maximum(rl_max - adot_min[:, :n], bl_max)
    gu_min = np.minimum(ru_min + adot_min[:, n:], bu_min)
    gu_max = np.maximum(ru_max + adot_max[:, n:], bu_max)
    rate_l = np.maximum(np.abs(gl_min), np.abs(gl_max))
    rate_u = np.maximum(np.abs(gu_min), np.abs(gu_max))
    width = upper_min - lower_max
    # a bound moves in one period at most |gamma_dot| dt, and at most its whole range on
    # the interval (which is at least one period long)
    move = np.minimum(np.maximum(rate_l, rate_u) / design.rate_hz,
                      np.maximum(lower_max - lower_min, upper_max - upper_min))
    with np.errstate(divide="ignore", invalid="ignore"):
        # where the enclosure is empty the ratio means nothing: non-empty fails there
        ratio = np.where(width > 0, move / width, 0.0)
    ratio = np.where(np.isnan(ratio), np.inf, ratio)
    return Enclosure(t0, t1, lower_min, lower_max, upper_min, upper_max, alpha_min, alpha_max,
                     ratio.max(axis=1), pieces.psi_lo, pieces.psi_hi)


def enclose_tube(design: TubeDesign, samples) -> Enclosure:
    """Enclosures of ``gamma_L``, ``gamma_U`` on every sampling interval of ``samples``.

    ``alpha`` is the deployed sequence of ``samples`` (:func:`~.samples.sample_tube`),
    linearly interpolated, so on ``[t_k, t_{k+1}]`` it lies between ``alpha_k`` and
    ``alpha_{k+1}``; the other pieces are enclosed as in :func:`certify_tube`. Per sample:
    for checks that follow the sampled loop step by step (``verify``'s sampled check).

    Parameters
    ----------
    design : TubeDesign
    samples : TubeSamples
        ``t`` (N,) and ``alpha`` (N, 2n).

    Returns
    -------
    Enclosure
        ``N - 1`` intervals.
    """
    t0, t1 = samples.t[:-1], samples.t[1:]
    a0, a1 = samples.alpha[:-1], samples.alpha[1:]
    return _enclose(design, _pieces(design, t0, t1), np.minimum(a0, a1), np.maximum(a0, a1),
                    t0, t1)


def _breakpoints(design: TubeDesign) -> tuple[list[int], int]:
    """Initial partition (sample indices) and ``T``'s index, after which ``psi`` is constant."""
    rate = design.rate_hz
    times = [0.0, design.prescribed_time]
    for s in design.segments:
        times += [s.start, s.end]
    for c in design.circumvents:
        times += [c.start, c.center, c.end]
    last = max(times)
    end = int(math.ceil(last * rate)) + 1
    points = {0, end}
    for t in times:
        if 0.0 < t < last:
            k = int(math.floor(t * rate))
            points.update((k, k + 1))
    return sorted(p for p in points if 0 <= p <= end), end


# --------------------------------------------------------------------------- certificate


def _obstacle_separation(spec: Spec, enc: Enclosure, selected):
    """Per spec obstacle: (index, separation per interval (K,), members, per-box gaps)."""
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


def _failing(design: TubeDesign, spec: Spec, enc: Enclosure, selected, final: bool):
    """Boolean (K,) mask of intervals on which some property is not yet proven."""
    bad = (enc.upper_min - enc.lower_max).min(axis=1) <= ROUNDING_MARGIN
    lo, hi = np.array(design.state_lower), np.array(design.state_upper)
    bad |= np.minimum(enc.lower_min - lo, hi - enc.upper_max).min(axis=1) < 0.0
    for _, sep, _, _, _ in _obstacle_separation(spec, enc, selected):
        bad |= sep <= ROUNDING_MARGIN
    if final:
        late = enc.t_end > design.prescribed_time
        t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
        inside = np.minimum(enc.lower_min - t_lo, t_hi - enc.upper_max).min(axis=1)
        bad |= late & (inside <= ROUNDING_MARGIN)
    bad |= enc.move_ratio > MAX_MOVE_PER_SAMPLE
    return bad


def certify_tube(design: TubeDesign, spec: Spec, obstacles: list[int] | None = None,
                 final: bool = True, max_intervals: int = MAX_INTERVALS,
                 resume: tuple[Certificate, float] | None = None) -> Certificate:
    """Prove the tube's safety properties for every ``t >= 0``.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
        For the state space, obstacles and target set.
    obstacles : list of int, optional
        Indices of ``spec.obstacle_boxes()`` to certify against; default all.
    final : bool
        Also prove ``inside target after t_c`` (a partial design of the search skips it).
    max_intervals : int
        Refinement budget; when it runs out, the properties not yet proven fail.
    resume : (Certificate, float), optional
        The certificate of a design whose tube equals this one before the given time
        (seconds), e.g. the same circumvents but one whose window opens then: its
        partition and ``alpha`` bounds before that time are reused (work shared across
        the candidates of the design search).

    Returns
    -------
    Certificate
        Properties ``non-empty``, ``initial state inside``, ``inside state space``,
        ``avoids obstacle j`` (one per spec obstacle), ``inside target after t_c`` and
        ``sampling rate`` (no bound moves more than :data:`MAX_MOVE_PER_SAMPLE` tube
        widths in one period), each with its smallest margin.
    """
    with reference.numpy_math():
        return _certify(design, spec, obstacles, final, max_intervals, resume)


def _certify(design: TubeDesign, spec: Spec, obstacles, final: bool,
             max_intervals: int, resume) -> Certificate:
    selected = list(range(len(spec.obstacle_boxes()))) if obstacles is None else obstacles
    points, end = _breakpoints(design)
    dt = 1.0 / design.rate_hz
    min_steps = max(1, int(MIN_INTERVAL * design.rate_hz))
    budget_hit = False
    decisive = ""
    work = 0
    m = 2 * design.dimension
    previous: tuple = ([], [], [], [])      # points, rows_lo, rows_hi, entries
    reuse_limit = 0                         # intervals of `previous` that may be reused
    if resume is not None:
        parent, until = resume
        old = list(parent.state[0])
        # the parent's points up to `until`: its intervals that end by then carry over
        cut = int(np.searchsorted(np.array(old, dtype=float) * dt, until, side="right"))
        cut = min(cut, len(old) - 1)
        if cut >= 2 and old[-1] == end:
            points = sorted(set(old[:cut]) | {p for p in points if p > old[cut - 1]})
            previous = parent.state
            reuse_limit = cut - 1
    while True:
        i0 = np.array(points)
        i1 = np.append(i0[1:], -1)            # -1: the tail [T, inf)
        t0 = i0 * dt
        t1 = np.where(i1 < 0, np.inf, i1 * dt)
        pieces = _pieces(design, t0, np.where(i1 < 0, t0, t1))
        steps = np.where(i1 < 0, np.inf, (i1 - i0).astype(float))
        # the intervals before the first new cut are unchanged: resume alpha after them
        old_points, old_lo, old_hi, old_entries = previous
        same = next((q for q, (a, b) in enumerate(zip(points, old_points)) if a != b),
                    min(len(points), len(old_points)))
        keep = max(0, min(same - 1, len(old_entries) - 1, reuse_limit))
        start = old_entries[keep] if keep else ([0.0] * m, [0.0] * m)
        rows_lo, rows_hi, entries = _alpha_ranges(design, pieces.psi_lo[keep:],
                                                  pieces.psi_hi[keep:], steps[keep:], start)
        work += len(points) - keep
        rows_lo, rows_hi = old_lo[:keep] + rows_lo, old_hi[:keep] + rows_hi
        entries = old_entries[:keep] + entries
        previous = (list(points), rows_lo, rows_hi, entries)
        reuse_limit = len(entries)            # from now on `previous` is this tube's own
        a_min, a_max = np.maximum(np.array(rows_lo), 0.0), np.array(rows_hi)
        enc = _enclose(design, pieces, a_min, a_max, t0, t1)
        bad = _failing(design, spec, enc, selected, final)
        length = np.where(i1 < 0, 0, i1 - i0)
        splittable = length >= max(2, 2 * min_steps)
        split = bad & splittable
        # a thin single-sample interval: its alpha may come in loose from a long predecessor
        single = bad & ~split
        pred = np.zeros_like(bad)
        pred[:-1] = single[1:]
        split |= pred & splittable
        # stop once a single-sample interval (with a single-sample predecessor or none)
        # fails: refining elsewhere cannot change the verdict
        failed = np.flatnonzero(single)
        if failed.size and np.any((failed == 0) | (length[np.maximum(failed - 1, 0)] <= 1)):
            break
        decisive = _surely_failing(design, spec, t0[bad], a_min[bad], a_max[bad], selected)
        if decisive:
            break             # the tube itself fails at an instant: no refinement helps
        if not split.any():
            break
        if len(points) + (SPLIT - 1) * int(split.sum()) > max_intervals:
            budget_hit = True
            break
        cuts = {int(a + (b * q) // SPLIT) for a, b in zip(i0[split], length[split])
                for q in range(1, SPLIT)}
        points = sorted(set(points) | cuts)
    narrowest = _narrowest(design, enc) if final and not bad.any() else None
    certificate = _report(design, spec, enc, selected, final, budget_hit, end * dt,
                          max_intervals, narrowest)
    return replace(certificate, state=previous, decisive=decisive, work=work)


def _narrowest(design: TubeDesign, enc: Enclosure) -> tuple[float, float]:
    """A sharper lower bound of the tube's narrowest width, and where it is (s).

    On an interval the deployed ``alpha`` lies in ``[alpha_min, alpha_max]`` at every
    ``t``, so the width on any piece of it is bounded below with that range and the
    piece's own (tighter) ranges of ``rho`` and ``beta``. The intervals within
    :data:`WIDTH_BAND` of the narrowest are cut into :data:`WIDTH_PIECES` pieces,
    :data:`WIDTH_ROUNDS` times (the pieces within the band again); ``alpha`` is not
    propagated again, so this costs a few vectorized evaluations.
    """
    width = (enc.upper_min - enc.lower_max).min(axis=1)
    t0, t1 = enc.t_start, enc.t_end
    a_min, a_max = enc.alpha_min, enc.alpha_max
    keep = ~np.isfinite(t1)                       # the tail [T, inf) stays as it is
    done_w, done_t = list(width[keep]), list(t0[keep])
    t0, t1, a_min, a_max, width = t0[~keep], t1[~keep], a_min[~keep], a_max[~keep], width[~keep]
    for _ in range(WIDTH_ROUNDS):
        best = min(width.min(initial=math.inf), min(done_w, default=math.inf))
        if not best > 0.0:
            break
        band = width <= best * (1.0 + WIDTH_BAND)
        if not band.any():
            break
        done_w += list(width[~band])
        done_t += list(t0[~band])
        q = np.arange(WIDTH_PIECES)
        span = (t1[band] - t0[band])[:, None]
        s0 = (t0[band][:, None] + span * q / WIDTH_PIECES).ravel()
        s1 = (t0[band][:, None] + span * (q + 1) / WIDTH_PIECES).ravel()
        s1 = np.maximum(s1, s0)
        a_min = np.repeat(a_min[band], WIDTH_PIECES, axis=0)
        a_max = np.repeat(a_max[band], WIDTH_PIECES, axis=0)
        piece = _enclose(design, _pieces(design, s0, s1), a_min, a_max, s0, s1)
        t0, t1, width = s0, s1, (piece.upper_min - piece.lower_max).min(axis=1)
    done_w += list(width)
    done_t += list(t0)
    k = int(np.argmin(done_w))
    return float(done_w[k]), float(done_t[k])


def _surely_failing(design: TubeDesign, spec: Spec, t: np.ndarray, a_min: np.ndarray,
                    a_max: np.ndarray, selected) -> str:
    """The property the tube certainly fails at one of the instants ``t`` ("" if none).

    With ``alpha`` in ``[a_min, a_max]``, the tube box at ``t`` contains the box for
    ``a_min`` (``gamma_L`` falls and ``gamma_U`` rises with ``alpha``) and is at most as
    wide as the box for ``a_max``.
    """
    if not t.size:
        return ""
    both_l, both_u, _, _ = reference.adaptive_tube(design, np.concatenate([t, t]),
                                                   np.concatenate([a_min, a_max]))
    g_l, w_l = both_l[:t.size], both_l[t.size:]
    g_u, w_u = both_u[:t.size], both_u[t.size:]
    boxes = spec.obstacle_boxes()
    for b in selected:
        lo, hi = np.array(boxes[b].lower), np.array(boxes[b].upper)
        if np.any(np.all((g_l < hi) & (g_u > lo), axis=1)):
            return f"avoids obstacle {spec.obstacles[b].source}"
    if np.any(np.max(w_l - w_u, axis=1) > 0.0):
        return "non-empty"
    return ""


def _worst(values: np.ndarray, t: np.ndarray) -> tuple[float, float, int]:
    flat = values.min(axis=1) if values.ndim == 2 else values
    k = int(np.argmin(flat))
    return float(flat[k]), float(t[k]), k


def _report(design: TubeDesign, spec: Spec, enc: Enclosure, selected, final: bool,
            budget_hit: bool, tail_start: float, max_intervals: int,
            narrowest: tuple[float, float] | None = None) -> Certificate:
    t0 = enc.t_start
    margins = []
    note = (" (the certificate's refinement budget of "
            f"{max_intervals} intervals was exhausted)") if budget_hit else ""

    width = enc.upper_min - enc.lower_max
    min_width, t = _worst(width, t0)[:2] if narrowest is None else narrowest
    margins.append(Margin("non-empty", min_width > ROUNDING_MARGIN, min_width, t,
                          f"min width gamma_U - gamma_L >= {min_width:.6g} (interval at "
                          f"t = {t:.4f} s)" + note))

    x0 = np.array(design.initial_state)
    g_l0, g_u0, _, _ = reference.adaptive_tube(design, [0.0], np.zeros(2 * design.dimension))
    g_l0, g_u0 = g_l0[0], g_u0[0]
    m0 = float(np.min(np.minimum(x0 - g_l0, g_u0 - x0)))
    margins.append(Margin("initial state inside", m0 > ROUNDING_MARGIN, m0, 0.0,
                          f"x(0) is {m0:.6g} inside the tube at t = 0"))
    width0 = g_u0 - g_l0
    initial_error = (float(np.max(np.abs((2 * x0 - (g_u0 + g_l0)) / width0)))
                     if np.all(width0 > 0) else math.inf)

    lo, hi = np.array(design.state_lower), np.array(design.state_upper)
    room = np.minimum(enc.lower_min - lo, hi - enc.upper_max)
    m, t, _ = _worst(room, t0)
    # the smooth max/min keep gamma inside [beta_L, beta_U] within [X, X-bar] exactly
    margins.append(Margin("inside state space", m >= 0.0, m, t,
                          f"min distance to the state-space boundary {m:.6g} at t = {t:.4f} s"))

    for j, sep, members, seps, gaps in _obstacle_separation(spec, enc, selected):
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
                              f"(every t >= {tail_start:.4f} s enclosed at once)" + note))

    k = int(np.argmax(enc.move_ratio))
    ratio = float(enc.move_ratio[k])
    margins.append(Margin("sampling rate", ratio <= MAX_MOVE_PER_SAMPLE,
                          MAX_MOVE_PER_SAMPLE - ratio, float(t0[k]),
                          f"a tube bound moves at most {ratio:.3g} tube widths in one sampling "
                          f"period at {design.rate_hz:g} Hz (limit {MAX_MOVE_PER_SAMPLE}; "
                          f"worst on the interval at t = {float(t0[k]):.3f} s)" + note))
    return Certificate(math.inf, int(t0.size), tuple(margins), ratio, min_width,
                       initial_error, enc)
