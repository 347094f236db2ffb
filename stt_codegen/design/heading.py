"""A differential-drive base's turn ``omega`` bounded from the heading it can have.

The look-ahead variant sends ``v = h(theta) . u`` and ``omega = h_perp(theta) . u / l`` for
law (13)'s ``u`` at the look-ahead point (docs/differential-drive.md). Whatever the
heading, ``|v| <= |u|`` and ``|omega| <= |u| / l`` (:mod:`.look_ahead`). This module
bounds them sample by sample from the heading the base can have at each sample, and from
the *direction* of ``u``, which the per-axis sampled check knows where its box of the
signed ``e_i(t_k)`` excludes 0 (law (13)'s ``u_i = -(4 k / gamma_d,i) phi(e_i)``, ``phi``
odd and increasing):

1. **The command's box.** From the check's box ``e_i(t_k) in [a_i, b_i]``
   (:attr:`~.certificate.sampled.SampledCheck.e_box`) and the width's enclosure on the
   interval, ``u_i`` lies in the product of ``-4 k [phi(a_i), phi(b_i)]`` and ``[1 /
   W_hi, 1 / W_lo]`` (``W`` at least ``GAMMA_D_MIN``, as the law clamps it).
2. **The turn's bound.** ``h_perp . u`` is linear in ``u``, so its largest magnitude over
   the box is at a corner ``c``; at a corner, ``|h_perp(theta) . c| = |c| |sin(angle(c) -
   theta)|``, whose largest value over an interval of ``theta`` is at an end or at a right
   angle inside it. (``|v| = |h . u|`` keeps the bound of ``|u|``: a base aligned with its
   command asks that much.) Backing up, ``-v = -|c| cos(angle(c) - theta)`` at a corner,
   is largest at an end or where ``angle(c) - theta`` is an odd multiple of ``pi``.
3. **The heading's enclosure.** Under the held command the base turns by ``theta_{k+1} =
   theta_k + dt ((2 d / b) h(theta_k) . u_k + M h_perp(theta_k) . u_k / l) + int w_omega``
   (the wheel model of docs/differential-drive.md: ``M = 1 + m``, ``|d|``, ``|w_omega| <=
   s_omega``). Its derivative in ``theta_k`` is at least ``1 - dt |u| sqrt((2 |d| / b)^2
   + (M / l)^2)``: where that is positive for every ``u`` of the box the map is
   increasing, so the interval ``[theta_lo, theta_hi]`` maps into ``[min theta_{k+1}
   (theta_lo), max theta_{k+1}(theta_hi)]``, the extremes over the box's corners and the
   ends of ``M`` and ``d`` (the map is linear in each), ``-+ dt s_omega``. Where it is not
   increasing, or the interval is a whole turn wide, the heading is unknown from there
   on, and the bounds are those of the worst heading.

Starting at the spec's ``initial.heading``, the enclosure holds for every base of the
class and every sample; ``omega``'s bound is then the largest over the box and the
enclosure, never above ``|u| / l`` (up to :data:`ROUNDING`). Only without a computation
delay or jitter (the command acts for exactly one period from its sample):
:func:`~.look_ahead.heading_known`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tube.parameters import GAMMA_D_MIN
from .certificate.sampled_axis import phi

__all__ = ["CommandBounds", "ROUNDING", "command_bounds", "corner_boxes"]

#: The relative margin added to each bound and each end of the heading's enclosure for the
#: floating-point rounding of their computation (far above it, far below any margin a
#: verdict turns on).
ROUNDING = 1e-9


@dataclass(frozen=True)
class CommandBounds:
    """Sample by sample bounds of a base's command.

    Attributes
    ----------
    turn : ndarray, shape (K,)
        A bound of ``|omega_k|``, rad/s (at most the bound of ``|u_k| / l``).
    heading : ndarray, shape (K, 2)
        An enclosure of ``theta(t_k)``, rad (``-inf, inf`` where unknown).
    backward : ndarray, shape (K,)
        A bound of ``max(0, -v_k)``, the speed the base may be asked to back up at, m/s
        (the bound of ``|u_k|`` where the heading is unknown).
    """

    turn: np.ndarray
    heading: np.ndarray
    backward: np.ndarray


def corner_boxes(e_box: np.ndarray, width_lo: np.ndarray, width_hi: np.ndarray,
                 gain: float) -> np.ndarray:
    """The box of law (13)'s ``u(t_k)`` from a box of the signed ``e(t_k)`` and of the
    width, per sample and axis.

    Parameters
    ----------
    e_box : ndarray, shape (K, n, 2)
        ``[lo, hi]`` of each ``e_i(t_k)``, inside ``(-1, 1)``.
    width_lo, width_hi : ndarray, shape (K, n)
        Bounds of ``gamma_d,i(t_k)`` (the law divides by at least ``GAMMA_D_MIN``).
    gain : float
        ``k``.

    Returns
    -------
    ndarray, shape (K, n, 2)
        ``[lo, hi]`` of each ``u_i(t_k)``, state units per second.
    """
    f = -4.0 * gain * phi(e_box)                       # -4 k phi(e): [f(hi), f(lo)]
    inv = 1.0 / np.maximum(np.stack([width_hi, width_lo], axis=2), GAMMA_D_MIN)
    products = f[:, :, :, None] * inv[:, :, None, :]   # every end times every end
    flat = products.reshape(*products.shape[:2], 4)
    lo, hi = flat.min(axis=2), flat.max(axis=2)
    return np.stack([lo - ROUNDING * np.abs(lo), hi + ROUNDING * np.abs(hi)], axis=2)


def _largest_sine(angle: float, lo: float, hi: float) -> float:
    """``max |sin(angle - theta)|`` over ``theta`` in ``[lo, hi]`` (``hi - lo < pi``)."""
    a, b = angle - hi, angle - lo                      # the arguments' interval
    # a right angle (pi/2 + j pi) inside [a, b] reaches 1
    if math.floor((b - math.pi / 2) / math.pi) >= math.ceil((a - math.pi / 2) / math.pi):
        return 1.0
    return max(abs(math.sin(a)), abs(math.sin(b)))


def _smallest_cosine(angle: float, lo: float, hi: float) -> float:
    """``min cos(angle - theta)`` over ``theta`` in ``[lo, hi]`` (``hi - lo < pi``)."""
    a, b = angle - hi, angle - lo
    # an odd multiple of pi inside [a, b] reaches -1
    if math.floor((b - math.pi) / (2.0 * math.pi)) >= math.ceil((a - math.pi) / (2.0 * math.pi)):
        return -1.0
    return min(math.cos(a), math.cos(b))


def command_bounds(u_box: np.ndarray, heading0: float, dt: float, axle_offset: float,
                   track_width: float, mean_gain: tuple[float, float],
                   differential: float, turn_noise: float) -> CommandBounds:
    """:class:`CommandBounds` of a base whose look-ahead point's command lies in ``u_box``
    and whose heading is ``heading0`` at ``t_0``.

    Parameters
    ----------
    u_box : ndarray, shape (K, 2, 2)
        ``[lo, hi]`` of each ``u_i(t_k)`` (:func:`corner_boxes`), m/s.
    heading0 : float
        ``theta(0)``, rad.
    dt : float
        The period, s: each command acts for exactly ``dt``.
    axle_offset, track_width : float
        ``l`` and ``b``, m.
    mean_gain : (float, float)
        The range of ``M = 1 + m`` (the wheels' mean radius error).
    differential : float
        ``|d|``, the bound of the wheels' differential radius error.
    turn_noise : float
        ``s_omega``, rad/s: the heading's rate beyond the wheels' (slip).

    Returns
    -------
    CommandBounds
    """
    count = u_box.shape[0]
    lean = math.hypot(2.0 * differential / track_width, max(mean_gain) / axle_offset)
    signs = [(g, 2.0 * d / track_width) for g in mean_gain for d in (-differential, differential)]
    turn = np.empty(count)
    backward = np.empty(count)
    heading = np.empty((count, 2))
    lo = hi = float(heading0)
    boxes = u_box.tolist()
    for k in range(count):
        heading[k] = lo, hi
        (x_lo, x_hi), (y_lo, y_hi) = boxes[k]
        corners = ((x_lo, y_lo), (x_lo, y_hi), (x_hi, y_lo), (x_hi, y_hi))
        known = math.isfinite(lo) and math.isfinite(hi) and hi - lo < math.pi
        largest = top = back = 0.0
        for cx, cy in corners:
            r = math.hypot(cx, cy)
            largest = max(largest, r)
            angle = math.atan2(cy, cx)
            top = max(top, r * (_largest_sine(angle, lo, hi) if known else 1.0))
            back = max(back, -r * (_smallest_cosine(angle, lo, hi) if known else -1.0))
        # a relative ROUNDING above the floats' value (sin, hypot, the products); backing
        # up also ROUNDING |u| above it, since its value crosses 0
        turn[k] = top / axle_offset * (1.0 + ROUNDING)
        backward[k] = max(back, 0.0) * (1.0 + ROUNDING) + ROUNDING * largest
        if not (math.isfinite(lo) and math.isfinite(hi)):
            continue
        if dt * largest * lean >= 1.0:                     # not increasing: unknown
            lo, hi = -math.inf, math.inf
            continue
        ends = []
        for theta, pick in ((lo, min), (hi, max)):
            cos, sin = math.cos(theta), math.sin(theta)
            ends.append(theta + dt * pick(
                g * (cy * cos - cx * sin) / axle_offset + e * (cx * cos + cy * sin)
                for cx, cy in corners for g, e in signs))
        lo = ends[0] - dt * turn_noise - ROUNDING * (1.0 + abs(ends[0]))
        hi = ends[1] + dt * turn_noise + ROUNDING * (1.0 + abs(ends[1]))
        if hi - lo >= 2.0 * math.pi:
            lo, hi = -math.inf, math.inf
    return CommandBounds(turn, heading, backward)
