"""Default numbers of the cascade's second stage from declared bounds (docs/second-order.md).

Linearized at ``e1 = e2 = 0`` the cascade is two first-order loops: the velocity error
``z = x2 - r`` obeys ``z_dot = -(4 k2 lambda / rho2^2) z + (f + w - r_dot)`` for each
eigenvalue ``lambda`` of the symmetric part of ``g``, and the position error
``x1_dot = -(16 k1 / gamma_d^2) (x1 - gamma_s / 2) + z + ...``. The defaults put

* the inner bandwidth ``omega2 = 4 k2 lambda / rho2_floor^2`` at ``0.1 / dt`` for
  ``lambda = g_max`` (the sampled inner loop's factor ``1 - omega2 dt`` in ``[0.9, 1 -
  0.1 g_min / g_max]``; where the slope of ``epsilon2`` grows 12.8-fold, ``|e2| = 0.96``,
  it is -0.28 at ``g_max``, and -1 where it grows 20-fold, ``|e2| = 0.975``; the law's own
  slope ``d u/d z`` grows faster, see :func:`cascade_rate`);
* the outer bandwidth at the narrowest tube, ``omega1 = 16 k1 / gamma_d,min^2``, a tenth
  of the slowest inner one (time-scale separation);
* the floor ``rho2_floor = 4 (F + omega1 V) / omega2,min``: four times the linear loop's
  steady velocity error under the declared bound ``F`` on ``|f + w|`` and the estimate
  ``omega1 V`` of ``|r_dot|`` (``V``: the fastest bound of the designed tube, sampled);
* ``rho2(0) = |x2(0) - r(x1(0), 0)| + rho2_floor`` (contains the initial error), shrinking
  at ``l = omega1``.

These are engineering defaults, not a proof: the sampled cascade is not certified
(docs/second-order.md, "What is not proved"). :func:`cascade_rate` gives the linearized
sampled loops' factors for deployed gains and the lowest rate at which they stay in
``(-1, 1)`` (``verify``'s ``cascade.rate``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..rounding import round_up
from ..tube import reference
from ..tube.parameters import TubeDesign
from ..tube.second_stage import SecondStage

__all__ = ["INNER_STEP_FRACTION", "cascade_rate", "cascade_rate_words", "derived_second_stage",
           "law_slope_growth", "transform_slope_growth"]

#: ``omega2 dt`` at ``lambda = g_max``.
INNER_STEP_FRACTION = 0.1
#: ``omega2,min / omega1``.
TIME_SCALE_SEPARATION = 10.0
#: ``rho2_floor`` over the linear loop's steady velocity error.
FLOOR_MARGIN = 4.0
#: Samples of the tube's speed over ``[0, t_c]``.
SPEED_SAMPLES = 4001


def tube_speed(design: TubeDesign, samples: int = SPEED_SAMPLES) -> float:
    """``V``: the largest ``|rho_dot|`` and ``|beta_dot|`` of the designed tube on a grid of
    ``[0, t_c]``, state units per second (sampled: an estimate, not a bound), rounded up to
    :data:`~stt_codegen.rounding.DIGITS` significant digits so that the gains derived from
    it are the same on every CPU."""
    t = np.linspace(0.0, design.prescribed_time, samples)
    with reference.numpy_math():
        _, _, rho_l_dot, rho_u_dot = reference.reach_tube(design, t)
        _, _, beta_l_dot, beta_u_dot = reference.circumvent(design, t)
    rates = np.concatenate([np.abs(v).ravel() for v in (rho_l_dot, rho_u_dot, beta_l_dot,
                                                         beta_u_dot)])
    return round_up(float(np.max(rates[np.isfinite(rates)])))


def derived_second_stage(design: TubeDesign, min_width: float, input_gain: tuple,
                         drift_bound: float, initial_velocity) -> tuple[SecondStage, dict]:
    """Default ``k1``, ``k2`` and ``rho2`` (module docstring) and their derivation.

    Parameters
    ----------
    design : TubeDesign
        The position tube (its ``rate_hz``, ``initial_state``).
    min_width : float
        ``gamma_d,min``, the certified narrowest width of the tube, state units.
    input_gain : (float, float)
        ``(g_min, g_max)``: bounds of the eigenvalues of the symmetric part of ``g`` over
        the declared plants (e.g. ``1 / m`` for mass ``m``), > 0.
    drift_bound : float
        ``F >= sup |f + w|`` over the declared plants and the state space (gravity, drag
        at the velocity bound, disturbance), velocity units per second.
    initial_velocity : sequence of float, length n
        ``x2(0)``.

    Returns
    -------
    stage : SecondStage
    derivation : dict
        The numbers above (``omega1``, ``omega2_min``, ``tube_speed``, ...), JSON-ready.

    Raises
    ------
    ValueError
        Non-positive gains or width, a negative drift bound, or a wrong length.
    """
    g_min, g_max = (float(v) for v in input_gain)
    if not 0 < g_min <= g_max or min_width <= 0 or drift_bound < 0:
        raise ValueError("need 0 < g_min <= g_max, min_width > 0 and drift_bound >= 0")
    n = design.dimension
    x2 = np.asarray(initial_velocity, dtype=float)
    if x2.shape != (n,):
        raise ValueError(f"initial_velocity needs {n} entries")
    dt = 1.0 / design.rate_hz
    omega2_min = INNER_STEP_FRACTION * g_min / (g_max * dt)
    omega1 = omega2_min / TIME_SCALE_SEPARATION
    k1 = omega1 * min_width**2 / 16.0
    speed = float(tube_speed(design))
    floor = float(FLOOR_MARGIN * (drift_bound + omega1 * speed) / omega2_min)
    k2 = INNER_STEP_FRACTION * floor**2 / (4.0 * dt * g_max)
    first = dataclasses.replace(design, gain=k1, input_bound=None)
    x1 = np.array(design.initial_state, dtype=float)
    r0, _, _ = reference.law_step(first, x1[None], 0.0, dt, np.zeros((1, 2 * n)))
    z0 = np.abs(x2 - r0[0])
    stage = SecondStage(k1, k2, tuple(float(v) for v in z0 + floor), (floor,) * n, omega1)
    return stage, {"dt": dt, "input_gain": [g_min, g_max], "min_width": float(min_width),
                   "drift_bound": float(drift_bound), "tube_speed": speed,
                   "omega1": omega1, "omega2_min": omega2_min, "position_gain": k1,
                   "velocity_gain": k2, "width_floor": floor,
                   "width_start": list(stage.width_start), "decay": omega1,
                   "initial_velocity_error": z0.tolist()}


#: ``|e2|`` at which the transform's slope is taken for :func:`cascade_rate`.
CONSIDERED_E2 = 0.96


def transform_slope_growth(e2: float) -> float:
    """``d epsilon2/d e2`` at ``e2`` over its value at 0: ``1 / (1 - e2^2)`` (the slope of
    ``epsilon2 = ln((1+e2)/(1-e2))`` is ``2 / (1 - e2^2)``).

    Parameters
    ----------
    e2 : float
        The second stage's normalized error, ``|e2| < 1``.

    Returns
    -------
    float
        ``1 / (1 - e2^2)``, at least 1.
    """
    return 1.0 / (1.0 - e2 * e2)


def law_slope_growth(e2: float) -> float:
    """``d u/d z`` at ``e2`` over its value at 0, for ``u = -k2 xi2 epsilon2`` with ``xi2 =
    2 / (rho2 (1 - e2^2))`` also depending on ``z``: ``(1 + e2 epsilon2) / (1 - e2^2)^2``.

    Parameters
    ----------
    e2 : float
        The second stage's normalized error, ``|e2| < 1``.

    Returns
    -------
    float
        ``(1 + e2 epsilon2) / (1 - e2^2)^2``, at least 1.
    """
    eps = math.log((1.0 + e2) / (1.0 - e2))
    return (1.0 + e2 * eps) / (1.0 - e2 * e2) ** 2


def _largest_e2(growth, limit: float) -> float:
    """The largest ``e2`` in ``[0, 1)`` with ``growth(e2) < limit`` (increasing ``growth``,
    ``growth(0) = 1``); 0 if ``limit <= 1``."""
    if limit <= 1.0:
        return 0.0
    lo, hi = 0.0, 1.0 - 1e-15
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if growth(mid) < limit else (lo, mid)
    return lo


def cascade_rate(stage: SecondStage, input_gain: tuple, min_width: float, rate_hz: float,
                 e2: float = CONSIDERED_E2) -> dict:
    """Linearized estimates of the sampled cascade and the lowest rate they allow.

    Linearized at ``e1 = e2 = 0`` (module docstring), with ``u`` held for ``dt``, the inner
    loop is ``z+ = (1 - omega2 dt) z``, ``omega2 = 4 k2 lambda / rho2^2`` (largest at the
    floor ``rho2 = rho2_inf``), for ``lambda`` in ``[g_min, g_max]``, and the outer loop
    ``x1+ = (1 - omega1 dt) x1``, ``omega1 = 16 k1 / gamma_d,min^2``. Away from ``e2 = 0``
    the transform's slope ``d epsilon2/d e2`` grows by :func:`transform_slope_growth`; the
    law's own slope ``d u/d z`` (``xi2`` grows too) by :func:`law_slope_growth`. A factor
    ``1 - omega dt`` is in ``(-1, 1)`` iff ``0 < omega dt < 2``, i.e. the rate is above
    ``omega / 2``.

    These are linearized estimates, not a certificate: the sampled cascade is not
    certified (docs/second-order.md, "What is not proved").

    Parameters
    ----------
    stage : SecondStage
        The deployed gains (``k1``, ``k2``, ``rho2_inf``).
    input_gain : (float, float)
        ``(g_min, g_max)``.
    min_width : float
        ``gamma_d,min``, state units.
    rate_hz : float
        The rate to judge, Hz (the gains are not re-derived for it).
    e2 : float, optional
        The ``|e2|`` in ``[0, 1)`` at which the transform's slope is taken.

    Returns
    -------
    dict
        JSON-ready: ``rate_hz``, ``dt``, ``e2``, ``omega1``, ``omega2`` (at ``g_min``,
        ``g_max``), the factors (``inner_factors``, ``inner_factors_grown``,
        ``outer_factor``, ``inner_factors_law_slope``), the slope growths,
        ``lowest_rate_hz`` (of the inner loop at the grown transform slope and the outer
        loop), ``rate_ratio`` (``rate_hz / lowest_rate_hz``), ``passed``
        (``rate_hz >= lowest_rate_hz``), ``law_slope_lowest_rate_hz`` and
        ``largest_stable_e2`` (transform slope and law slope, at ``g_max``, at
        ``rate_hz``).
    """
    g_min, g_max = (float(v) for v in input_gain)
    if not 0.0 <= e2 < 1.0 or rate_hz <= 0:
        raise ValueError("need 0 <= e2 < 1 and rate_hz > 0")
    dt = 1.0 / rate_hz
    floor = float(min(stage.width_floor))
    omega2 = [4.0 * stage.velocity_gain * lam / floor**2 for lam in (g_min, g_max)]
    omega1 = 16.0 * stage.position_gain / float(min_width) ** 2
    grow, law = transform_slope_growth(e2), law_slope_growth(e2)
    lowest = max(grow * omega2[1], omega1) / 2.0
    limit = 2.0 / (omega2[1] * dt)           # growth at which the g_max factor reaches -1
    return {
        "rate_hz": float(rate_hz), "dt": dt, "e2": float(e2), "input_gain": [g_min, g_max],
        "width_floor": floor, "min_width": float(min_width),
        "omega1": omega1, "omega2": omega2,
        "inner_factors": [1.0 - w * dt for w in omega2],
        "transform_slope_growth": grow,
        "inner_factors_grown": [1.0 - grow * w * dt for w in omega2],
        "outer_factor": 1.0 - omega1 * dt,
        "law_slope_growth": law,
        "inner_factors_law_slope": [1.0 - law * w * dt for w in omega2],
        "lowest_rate_hz": lowest, "rate_ratio": float(rate_hz) / lowest,
        "passed": bool(rate_hz >= lowest),
        "law_slope_lowest_rate_hz": law * omega2[1] / 2.0,
        "largest_stable_e2": {"transform_slope": _largest_e2(transform_slope_growth, limit),
                              "law_slope": _largest_e2(law_slope_growth, limit)},
    }


def cascade_rate_words(rate: dict) -> str:
    """:func:`cascade_rate`'s figures in one sentence (``cascade.rate``'s detail).

    Parameters
    ----------
    rate : dict
        What :func:`cascade_rate` returns.

    Returns
    -------
    str
        One sentence: the inner and outer loops' factors, the lowest rate and the verdict.
    """
    lo, hi = rate["inner_factors"]
    glo, ghi = rate["inner_factors_grown"]
    llo, lhi = rate["inner_factors_law_slope"]
    verdict = (f"{rate['rate_hz']:g} Hz is {rate['rate_ratio']:.3g} times above it"
               if rate["passed"] else
               f"{rate['rate_hz']:g} Hz is below it (by a factor {1 / rate['rate_ratio']:.3g})")
    stable = rate["largest_stable_e2"]
    return (f"linearized estimate, not a certificate: at {rate['rate_hz']:g} Hz the sampled "
            f"inner loop's factor 1 - omega2 dt is in [{hi:.3f}, {lo:.3f}] for lambda in "
            f"[g_min, g_max] at e2 = 0, [{ghi:.3f}, {glo:.3f}] with the slope of epsilon2 "
            f"grown {rate['transform_slope_growth']:.3g}-fold (|e2| = {rate['e2']:g}); the "
            f"outer loop's factor is {rate['outer_factor']:.4f}; these stay in (-1, 1) above "
            f"the lowest rate {rate['lowest_rate_hz']:.4g} Hz, and {verdict}. Not covered: "
            f"the law's own slope d u/d z (xi2 grows too) is {rate['law_slope_growth']:.3g}-"
            f"fold at |e2| = {rate['e2']:g} (factor {lhi:.3g} at g_max, lowest rate "
            f"{rate['law_slope_lowest_rate_hz']:.4g} Hz); at this rate the g_max factor "
            f"stays above -1 for |e2| < {stable['law_slope']:.3f} with the law's slope "
            f"({stable['transform_slope']:.3f} with the transform's)")
