"""Window geometry of the paper's design: overlap windows (5), candidate circumvents (6).

* **Windows, eq. (5)**, computed robustly: with ``s = tanh(t / (t_c - t))`` the reach
  tube is linear in ``s``, so the times at which its box overlaps an obstacle box form
  one interval of ``s`` per dimension; intersected over dimensions and mapped back with
  ``t = t_c a / (1 + a)``, ``a = atanh(s)``. No 0/0 on degenerate dimensions.
* **Dimension and side, eq. (6)**: every valid (dimension, side) of an obstacle is a
  candidate, in a fixed order (longest overlap first; :func:`candidates`).
* **Bump window**: the active window is widened around the overlap interval so that
  the bump, whose sharpness ``k^j`` the spec fixes (or :data:`SHARPNESS_LADDER`
  offers), is within ``delta_B / 2`` of its peak where the reach tube first and last
  overlaps the obstacle.
"""

from __future__ import annotations

import math

import numpy as np

from ..spec.loader import Box, Spec
from ..tube import reference
from ..tube.parameters import LOWER, UPPER, Circumvent, TubeDesign
from .certificate import MAX_MOVE_PER_SAMPLE

__all__ = ["SHARPNESS_LADDER", "WINDOW_INFLATION", "candidates", "overlap_interval",
           "progress_time"]

#: Obstacles are inflated by this fraction of ``delta_b`` to compute overlap windows.
WINDOW_INFLATION = 0.5
#: Circumvent sharpness values ``k^j`` the automatic choice picks from, sharpest first.
SHARPNESS_LADDER = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0)
#: Ladder values tried per circumvent, from the sharpest that passes the quick estimate.
AUTO_SHARPNESS_TRIES = 3
#: The quick estimate's tube width, as a fraction of the reach tube's (the adaptive
#: tube is narrower where it circumvents).
AUTO_WIDTH_FRACTION = 0.25


def dimension_interval(design: TubeDesign, box: Box, i: int,
                       margin: float) -> tuple[float, float] | None:
    """Interval of ``s`` in ``[0, 1]`` where the reach tube's projection on ``i`` meets ``box``'s.

    ``rho_L_i(s) <= upper_i + margin`` and ``rho_U_i(s) >= lower_i - margin`` are linear
    in ``s`` (eq. (4)); ``None`` when they never hold together.
    """
    lo, hi = 0.0, 1.0
    x_l, x_u = design.initial_lower[i], design.initial_upper[i]
    for a, slope, bound, sign in ((x_l, design.target_lower[i] - x_l, box.upper[i] + margin, 1),
                                  (x_u, design.target_upper[i] - x_u, box.lower[i] - margin, -1)):
        a, slope, bound = sign * a, sign * slope, sign * bound  # a + slope s <= bound
        if slope == 0:
            if a > bound:
                return None
            continue
        limit = (bound - a) / slope
        if slope > 0:
            hi = min(hi, limit)
        else:
            lo = max(lo, limit)
    return (lo, hi) if lo <= hi else None


def overlap_interval(design: TubeDesign, box: Box, margin: float) -> tuple[float, float] | None:
    """Interval of ``s = tanh(t/(t_c - t))`` in ``[0, 1]`` where the reach tube box meets ``box``.

    The robust reading of eq. (5): the intersection over dimensions of
    :func:`dimension_interval`, with ``box`` inflated by ``margin``. ``None`` when the
    tube never meets the inflated box.

    Parameters
    ----------
    design : TubeDesign
        The tube (its reach segments).
    box : Box
        An obstacle box.
    margin : float
        Inflation of ``box`` on every side, state units.

    Returns
    -------
    (float, float) or None
        ``(s_1, s_2)``, ``0 <= s_1 <= s_2 <= 1``, or None.
    """
    lo, hi = 0.0, 1.0
    for i in range(design.dimension):
        interval = dimension_interval(design, box, i, margin)
        if interval is None:
            return None
        lo, hi = max(lo, interval[0]), min(hi, interval[1])
    return (lo, hi) if lo <= hi else None


def progress_time(design: TubeDesign, s: float) -> float:
    """Inverse of ``s = tanh(t/(t_c - t))``: ``t = t_c a / (1 + a)``, ``a = atanh(s)``.

    Parameters
    ----------
    design : TubeDesign
        The tube (its prescribed time ``t_c``).
    s : float
        Progress in ``[0, 1]`` (1 and above give ``t_c``).

    Returns
    -------
    float
        The time ``t``, s, in ``[0, t_c]``.
    """
    if s >= 1.0:
        return design.prescribed_time
    a = math.atanh(max(s, 0.0))
    return design.prescribed_time * a / (1.0 + a)


def candidates(design: TubeDesign, spec: Spec, j: int, delta_b: float) -> list[Circumvent]:
    """The circumvents that could avoid obstacle box ``j``, best first (deterministic order).

    Order: dimensions where the reach tube overlaps the obstacle's projection for the
    longest part of ``[0, 1]`` in ``s`` first, then the side that needs the bound to
    move least at the middle of the window, then dimension index.

    Parameters
    ----------
    design : TubeDesign
        The design the circumvents are added to (its reach tube).
    spec : Spec
        The spec (state space and obstacle boxes).
    j : int
        Index of the obstacle box in ``spec.obstacle_boxes()``.
    delta_b : float
        ``delta_B`` of eqs. (7)-(8), the clearance kept from the obstacle, state units.

    Returns
    -------
    list of Circumvent
        Empty when the reach tube never comes near the box.
    """
    box = spec.obstacle_boxes()[j]
    margin = WINDOW_INFLATION * delta_b
    interval = overlap_interval(design, box, margin)
    if interval is None:
        return []
    t1, t2 = (progress_time(design, s) for s in interval)
    mid = np.array([0.5 * (t1 + t2)])
    rho_l, rho_u, _, _ = reference.reach_tube(design, mid, rates=False)
    result = []
    for i in range(design.dimension):
        lo_x, hi_x = spec.state_space.lower[i], spec.state_space.upper[i]
        if box.lower[i] <= lo_x and box.upper[i] >= hi_x:
            continue  # the obstacle spans this dimension
        interval_i = dimension_interval(design, box, i, margin)
        span = 0.0 if interval_i is None else interval_i[1] - interval_i[0]
        for side in (LOWER, UPPER):
            if side == LOWER:
                peak = box.upper[i] + delta_b
                if peak >= hi_x:
                    continue
                base, height = lo_x, peak - lo_x
                move = max(0.0, peak - float(rho_l[0, i]))
            else:
                peak = box.lower[i] - delta_b
                if peak <= lo_x:
                    continue
                base, height = hi_x, hi_x - peak
                move = max(0.0, float(rho_u[0, i]) - peak)
            width = float(np.min(rho_u[0] - rho_l[0]))
            for rank_k, k in enumerate(_sharpness_options(spec, height, delta_b, t1, t2,
                                                          width, design.rate_hz)):
                radius, center = _window(height, delta_b, k, t1, t2)
                result.append((-span, move, i, 0 if side == LOWER else 1, rank_k,
                               Circumvent(j, i, side, center - radius, center + radius,
                                          height, base, k)))
    result.sort(key=lambda r: r[:5])
    return [r[-1] for r in result]


def _window(height: float, delta_b: float, k: float, t1: float, t2: float):
    """Half-width and centre of the bump window: within ``delta_b / 2`` of the peak on [t1, t2]."""
    level = (height - 0.5 * delta_b) / height
    z = math.sqrt(-math.log(level) / (k - math.log(level)))
    return max(0.5 * (t2 - t1), 1e-9) / z, 0.5 * (t1 + t2)


def bump_rate_peak(k: float, radius: float) -> float:
    """``sup_t |b_dot|`` of the bump (7)-(8), 1/s (``verify.lemma.bump_rate_bound``)."""
    q = ((1.0 - k) + math.sqrt((1.0 - k) ** 2 + 3.0)) / 3.0
    return 2.0 * k / radius * math.sqrt(q) / (1.0 - q) ** 2 * math.exp(-k * q / (1.0 - q))


def _sharpness_options(spec: Spec, height: float, delta_b: float, t1: float, t2: float,
                       width: float, rate_hz: float) -> list[float]:
    """``k^j`` values to try, best first: the spec's, or the automatic ladder.

    Automatic: the sharpest value of :data:`SHARPNESS_LADDER` whose bump moves the bound
    by at most ``MAX_MOVE_PER_SAMPLE`` of :data:`AUTO_WIDTH_FRACTION` of the reach tube's
    width per sampling period (a quick necessary estimate), then the next
    :data:`AUTO_SHARPNESS_TRIES` - 1 smoother ones: the certificate's sampling-rate check
    decides among them.
    """
    if spec.tube.circumvent_sharpness is not None:
        return [spec.tube.circumvent_sharpness]
    limit = MAX_MOVE_PER_SAMPLE * AUTO_WIDTH_FRACTION * width * rate_hz
    first = len(SHARPNESS_LADDER) - 1
    for q, k in enumerate(SHARPNESS_LADDER):
        radius, _ = _window(height, delta_b, k, t1, t2)
        if height * bump_rate_peak(k, radius) <= limit:
            first = q
            break
    return list(SHARPNESS_LADDER[first:first + AUTO_SHARPNESS_TRIES])
