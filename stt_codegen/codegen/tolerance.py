"""Error bounds of the generated code against the double reference, per output entry.

Used for the tolerances of the test vectors (JSON and the C self-test) and by the
single-precision equivalence tests. ``unit`` is the unit roundoff: ``2**-53`` (double),
``2**-24`` (single). Inputs are taken as exact (the vectors' inputs are float32 numbers,
exact in both precisions); the bound covers the rounding of the generated code and of a
libm whose functions are within a few ulp of correctly rounded (a ``log`` within
:data:`LOG_ERROR_ULP`; single precision's own ``stt_expf`` and ``stt_logf``,
:mod:`stt_codegen.codegen.emit.c_maths`, are within 0.89 and 0.84 ulp).

* **Tube bounds.** Every ``gamma`` is a short chain (``tanh`` progress, the linear
  reach tube, the circumvent bump, the overflow-safe smooth max/min, ``alpha``) of about
  16 roundings, each of at most ``unit`` times the arena's scale
  ``S = 1 + max_i max(|X_i|, |X-bar_i|) + max_j |alpha_j|``; the conditioning of
  ``tanh(t/(t_c - t))`` near ``t_c`` and of the bump near its window edges is below 6
  (``sech^2(y) y (1+y) < 1``, ``z^2 e^-z < 0.6``). Bound: ``GAMMA_FACTOR * unit * S``
  with ``GAMMA_FACTOR = 64`` (4x the count).
* **Control u.** ``u = -(4k/w) g(e)``, ``g(e) = ln((1+e)/(1-e)) / (1 - e^2)``,
  increasing in ``e``. With ``dg = GAMMA_FACTOR unit S`` the error of each bound,
  ``e`` computed from ``x`` and the bounds has error at most
  ``de = (2 |x| unit + 2 (1 + |e|) dg) / w + 4 unit |e|``; the bound is the exact
  spread of ``g`` over ``[e - de, e + de]`` (clamped to ``+-E_MAX`` as the code does, not
  linearised: the conditioning ``g'/g ~ 1/(1-|e|)`` is large near the boundary), plus
  the width's relative error ``2 dg / w`` times ``|u|``, plus ``16 unit`` of local
  rounding (``log``, quotients) times ``(4k/w)(|g| + 1/(1-e^2))``.
  Where ``|e| + de >= 1`` the computed state may be outside the tube: the status is not
  determined by the precision and the bound covers the clamped value.
* **alpha_next.** The Newton iteration converges to a few ulp of the root (single
  precision may stop after the first iteration, when its proven error bound is below
  ``unit |alpha_next|``: :data:`NEWTON_STOP_SINGLE`); the root's
  sensitivity to ``psi`` is at most 1 and to ``theta``'s relative error at most
  ``|alpha_next| + |alpha|``. Bound: ``GAMMA_FACTOR * unit * (S + |alpha| + |alpha_next|)``.
* **The look-ahead variant** (differential-drive bases, :func:`look_ahead_bounds`): the
  point ``p = (x + l cos theta, y + l sin theta)`` is off by ``dp = 4 unit (|p| + 4 l)``
  (``cos``/``sin`` within 2 unit, the literal ``l``, the product and the sum, 4x margin);
  law (13) at ``p`` as the cascade's ``r`` below with ``dp`` in the numerator of ``e``;
  ``(v, omega) = (c u0 + s u1, (c u1 - s u0) / l)`` adds ``du0 + du1`` plus
  ``8 unit (|u0| + |u1|)`` (and for ``omega`` divides by ``l``, plus ``2 unit |omega|``).
* **The cascade** (second-order plants, :func:`cascade_bounds`): ``r`` is law (13) with
  gain ``k1``, bounded as ``u`` above (``dr``); the velocity error ``e2 = (x2 - r) / rho2``
  takes ``dr``, the difference's rounding and ``rho2(t)``'s error
  (:func:`velocity_tube_bound`); ``u = -(2 k2 / rho2) g(e2)`` is again the spread of
  ``g`` over ``[e2 - de2, e2 + de2]``, scaled, plus local rounding, the latter evaluated
  at the interval's far end (:func:`_law_error`); ``alpha_next`` as above.
"""

from __future__ import annotations

import numpy as np

from ..tube import reference
from ..tube.parameters import E_MAX, GAMMA_D_MIN, TubeDesign

__all__ = ["GAMMA_FACTOR", "LOG_ERROR_ULP", "NEWTON_STOP_SINGLE", "UNIT_SINGLE", "alpha_bound",
           "cascade_bounds", "gamma_bound", "look_ahead_bounds", "status_certain", "u_bound",
           "unit_roundoff", "with_double_floor"]

UNIT_DOUBLE = 2.0 ** -53
UNIT_SINGLE = 2.0 ** -24
#: Rounding count of a tube bound, with a 4x margin.
GAMMA_FACTOR = 64.0
#: Local roundings of the law (13) after ``e``.
LAW_FACTOR = 16.0
#: Error of one ``log`` call that :data:`LAW_FACTOR` assumes, in ulps of its result
#: (:func:`_law_error`): the C library's (fdlibm's ``logf`` and ``log`` are below one ulp)
#: and single precision's own ``stt_logf`` (below 0.84 ulp on its fast path, the C
#: library's ``logf`` elsewhere).
LOG_ERROR_ULP = 1.0
#: Single precision's implicit step stops its Newton iteration after the first step ``d``
#: from ``a`` (``z = psi + a``) when the remaining error's bound ``6 A d^2 / (c z^4)`` (``g``
#: concave and increasing, the iterates left of the root: docs/codegen.md, "Fewer
#: operations") is at most ``NEWTON_STOP_SINGLE`` times the new iterate: one unit roundoff
#: of ``alpha_next``, as at the fixed point the double code iterates to.
NEWTON_STOP_SINGLE = UNIT_SINGLE
#: Floor of the double tolerance: the acceptance criterion ``1e-12 max(1, |ref|)``.
DOUBLE_FLOOR = 1e-12


def unit_roundoff(precision: str) -> float:
    """``2**-53`` for ``"double"``, ``2**-24`` for ``"single"``.

    Parameters
    ----------
    precision : str
        ``"double"`` or ``"single"``.

    Returns
    -------
    float
        The unit roundoff ``u`` of the precision.
    """
    return UNIT_DOUBLE if precision == "double" else UNIT_SINGLE


def scale(design: TubeDesign, alpha: np.ndarray) -> np.ndarray:
    """``S`` per point, shape (N,): ``1 + max |state bound| + max |alpha|``."""
    bound = max(max(abs(v) for v in design.state_lower), max(abs(v) for v in design.state_upper))
    return 1.0 + bound + np.max(np.abs(np.atleast_2d(alpha)), axis=1)


def _g(e: np.ndarray) -> np.ndarray:
    e = np.clip(e, -E_MAX, E_MAX)
    return reference.log((1.0 + e) / (1.0 - e)) / (1.0 - e * e)   # libm: the same on every CPU


def gamma_bound(design: TubeDesign, alpha, unit: float) -> np.ndarray:
    """Bound on the error of ``gamma_L``/``gamma_U``, shape (N, 1) (broadcasts over n).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at the points, state units.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    ndarray, shape (N, 1)
        State units.
    """
    return (GAMMA_FACTOR * unit * scale(design, alpha))[:, None]


def u_bound(design: TubeDesign, x, alpha, gamma_l, gamma_u, u_ref, unit: float) -> np.ndarray:
    """Bound on the error of ``u``, shape (N, n); see the module docstring.

    Parameters
    ----------
    design : TubeDesign
        The tube (its gain).
    x : array_like, shape (N, n)
        States, state units.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at the points.
    gamma_l, gamma_u : ndarray, shape (N, n)
        The reference's adaptive tube, state units.
    u_ref : ndarray, shape (N, n)
        The reference's ``u``.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    ndarray, shape (N, n)
        Input units.
    """
    x = np.atleast_2d(x)
    dg = gamma_bound(design, alpha, unit)
    width = np.maximum(gamma_u - gamma_l, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / width
    de = (2.0 * np.abs(x) * unit + 2.0 * (1.0 + np.abs(e)) * dg) / width + 4.0 * unit * np.abs(e)
    g0 = _g(e)
    spread = np.maximum(_g(e + de) - g0, g0 - _g(e - de))
    factor = 4.0 * design.gain / width
    e_c = np.clip(e, -E_MAX, E_MAX)
    local = LAW_FACTOR * unit * (np.abs(g0) + 1.0 / (1.0 - e_c * e_c))
    return factor * (spread + local) + np.abs(u_ref) * 2.0 * dg / width


def status_certain(design: TubeDesign, x, alpha, gamma_l, gamma_u, unit: float) -> np.ndarray:
    """Whether the inside/outside status cannot depend on rounding, shape (N,).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    x : array_like, shape (N, n)
        States, state units.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at the points.
    gamma_l, gamma_u : ndarray, shape (N, n)
        The reference's adaptive tube, state units.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    ndarray of bool, shape (N,)
        True where every ``|e_i|`` is clear of 1 by more than its rounding error and the
        tube is wider than its own.
    """
    x = np.atleast_2d(x)
    dg = gamma_bound(design, alpha, unit)
    width = gamma_u - gamma_l
    safe_width = np.maximum(width, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / safe_width
    de = (2.0 * np.abs(x) * unit + 2.0 * (1.0 + np.abs(e)) * dg) / safe_width + 4.0 * unit
    clear = (np.abs(np.abs(e) - 1.0) > 2.0 * de) & (np.abs(width) > 4.0 * dg)
    return np.all(clear, axis=1)


def alpha_bound(design: TubeDesign, alpha, alpha_next, unit: float) -> np.ndarray:
    """Bound on the error of ``alpha_next``, shape (N, 2n).

    Parameters
    ----------
    design : TubeDesign
        The tube.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at the points.
    alpha_next : ndarray, shape (N, 2n)
        The reference's next ``alpha``.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    ndarray, shape (N, 2n)
        State units.
    """
    alpha = np.atleast_2d(alpha)
    return GAMMA_FACTOR * unit * (scale(design, alpha)[:, None] + np.abs(alpha)
                                  + np.abs(alpha_next))


def with_double_floor(bound: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``max(bound, 1e-12 max(1, |reference|))``: the double tolerance of the vectors.

    Parameters
    ----------
    bound : ndarray
        A rounding-error bound.
    reference : ndarray
        The reference value it is for, the shape of ``bound``.

    Returns
    -------
    ndarray
        The floored bound.
    """
    return np.maximum(bound, DOUBLE_FLOOR * np.maximum(1.0, np.abs(reference)))


#: Roundings of the velocity tube ``rho2(t)``: the literals ``rho2(0)``, ``rho2(inf)``,
#: ``l`` (3), ``rho2(0) - rho2(inf)``, ``-l t``, ``exp`` (2), the product and the sum (5):
#: 8, with the 4x margin of :data:`GAMMA_FACTOR`.
VELOCITY_TUBE_FACTOR = 32.0


def velocity_tube_bound(stage, t, rho2, unit: float) -> np.ndarray:
    """Bound on the error of ``rho2(t)``, shape (N, n): ``(32 + 8 l min(t, 80/l)) unit
    rho2``. The exponent's relative error (``l``'s literal and the product, ``2 unit``) is
    multiplied by ``l t`` in ``exp``; the other roundings are relative to terms of ``rho2``
    (each at most ``rho2``); ``4x`` margin on both."""
    t = np.maximum(np.atleast_1d(np.asarray(t, dtype=float)), 0.0)
    exponent = np.minimum(stage.decay * t, 80.0)
    return (VELOCITY_TUBE_FACTOR + 4.0 * 2.0 * exponent)[:, None] * unit * np.asarray(rho2)


def _divided(numerator_error, value, width, width_error, unit: float) -> np.ndarray:
    """Error bound of a computed ``e = z / w`` (``value = e`` exact): ``z`` off by
    ``numerator_error``, ``w`` by ``width_error`` (2 wherever ``w <= width_error``: ``e`` is
    then undetermined and the clamp bounds it), plus the quotient's rounding."""
    safe = width > width_error
    de = (numerator_error + np.abs(value) * width_error) / np.where(safe, width - width_error, 1.0)
    de = de + 2.0 * unit * (np.abs(value) + de)
    return np.where(safe, de, 2.0)


def _law_error(e, de, factor, relative, unit: float) -> np.ndarray:
    """Error bound of a computed ``factor g(e)`` (law (13)'s form) whose ``e`` is off by at
    most ``de`` and whose ``factor`` by ``relative`` (relative): the exact spread of ``g``
    over ``[e - de, e + de]`` (clamped to ``+-E_MAX`` as the code does), plus, at the far
    end of the interval (``|g| <= g_far``, ``|e| <= e_far``), the factor's error
    ``relative g_far`` and the local rounding of ``g`` there, ``16 unit (g_far + 1) /
    (1 - e_far^2)``: ``log`` of the rounded quotient ``(1+e)/(1-e)`` is off by ``3 unit``
    plus its own error (:data:`LOG_ERROR_ULP`, one ulp), and the computed ``1 - e*e`` by
    ``unit (e^2 + 1 - e^2)`` absolute, a relative ``unit / (1 - e^2)`` (this is what grows
    near the boundary), with the quotients and products: at most ``unit (5 |g| + 3) / (1 - e^2)``, 3x margin."""
    g0 = _g(e)
    low, high = _g(e - de), _g(e + de)
    spread = np.maximum(high - g0, g0 - low)
    g_far = np.maximum(np.abs(low), np.abs(high))
    e_far = np.minimum(np.abs(e) + de, E_MAX)
    local = LAW_FACTOR * unit * (g_far + 1.0) / (1.0 - e_far * e_far)
    return factor * (spread + local + relative * g_far)


def cascade_bounds(design: TubeDesign, stage, x1, x2, t, alpha, r_ref, alpha_next,
                   unit: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bounds on the errors of the cascade step's ``u``, ``r`` (shape (N, n)) and
    ``alpha_next`` (N, 2n) against the double reference (docs/second-order.md, "Generated
    code"). Inputs exact in the precision, as in the module docstring; ``r_ref``,
    ``alpha_next`` the reference's outputs; ``stage`` a
    :class:`~stt_codegen.tube.second_stage.SecondStage`.

    * **r** ``= -(4 k1 / w) g(e1)``, law (13) with gain ``k1`` on the adaptive tube: the
      argument of "Control u" above, with the tube bounds' ``dg = GAMMA_FACTOR unit S``,
      ``e1``'s error ``de1 = (2 |x1| unit + 2 (1 + |e1|) dg) / (w - 2 dg) + 4 unit (|e1| +
      de1)`` (:func:`u_bound`'s ``de`` with the computed width ``w - 2 dg`` as divisor),
      and :func:`_law_error` (the spread of ``g`` over ``[e1 - de1, e1 + de1]``, ``w``'s
      relative error ``2 dg / (w - 2 dg)``, the local rounding at the interval's far
      end): ``dr``.
    * **rho2(t)**: :func:`velocity_tube_bound`, ``drho``.
    * **e2** ``= (x2 - r) / rho2`` (``rho2`` floored at ``GAMMA_D_MIN``): the computed
      difference is off by ``dr (1 + unit) + unit |x2 - r|``; divided by the computed
      ``rho2`` (off by ``drho``) and rounded, ``de2`` (:func:`_divided`).
    * **u** ``= -(2 k2 / rho2) g(e2)``, the same ``g`` (``xi2 eps2`` on the tube of width
      ``2 rho2``): :func:`_law_error` with ``factor = 2 k2 / rho2`` and ``rho2``'s relative
      error ``drho / (rho2 - drho)``.
    * **alpha_next**: the first stage's implicit step, unchanged: :func:`alpha_bound`.

    Where ``e +- de`` reaches ``+-E_MAX`` the bound covers the clamped value and is as wide
    as ``g``'s range there (the computed state may be outside the tube).

    Parameters
    ----------
    design : TubeDesign
        The first stage's tube.
    stage : SecondStage
        The second stage (gains ``k1``, ``k2``, velocity tube).
    x1, x2 : array_like, shape (N, n)
        Positions and velocities.
    t : array_like, shape (N,)
        Times, s.
    alpha : array_like, shape (N, 2n)
        ``alpha`` at the points.
    r_ref : ndarray, shape (N, n)
        The reference's virtual velocity ``r``.
    alpha_next : ndarray, shape (N, 2n)
        The reference's next ``alpha``.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    tol_u, tol_r : ndarray, shape (N, n)
        Bounds on the errors of ``u`` and ``r``.
    tol_alpha : ndarray, shape (N, 2n)
        Bound on the error of ``alpha_next``.
    """
    import dataclasses

    from ..tube import reference
    from ..tube.cascade_reference import velocity_tube

    x1, x2 = np.atleast_2d(x1), np.atleast_2d(x2)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    alpha = np.atleast_2d(alpha)
    first = dataclasses.replace(design, gain=stage.position_gain, input_bound=None)
    gamma_l, gamma_u, _, _ = reference.adaptive_tube(first, t, alpha)
    dg = gamma_bound(first, alpha, unit)
    width = np.maximum(gamma_u - gamma_l, GAMMA_D_MIN)
    e1 = (2.0 * x1 - (gamma_u + gamma_l)) / width
    # numerator 2 x1 - (gamma_U + gamma_L): the bounds' 2 dg and the roundings of the sum
    # and the difference, unit (2 |x1| + 2 |e1| w); the width's 2 dg in _divided
    de1 = _divided(2.0 * dg + unit * (2.0 * np.abs(x1) + 2.0 * np.abs(e1) * width), e1,
                   width, 2.0 * dg, unit)
    relative1 = np.where(width > 2.0 * dg, 2.0 * dg / np.maximum(width - 2.0 * dg, 1e-300),
                         np.inf)
    tol_r = _law_error(e1, de1, 4.0 * stage.position_gain / width, relative1, unit)
    rho2 = np.maximum(velocity_tube(stage, t), GAMMA_D_MIN)
    drho = velocity_tube_bound(stage, t, rho2, unit)
    z = x2 - r_ref
    e2 = z / rho2
    de2 = _divided((1.0 + unit) * tol_r + unit * np.abs(z), e2, rho2, drho, unit)
    relative2 = drho / (rho2 - drho)
    tol_u = _law_error(e2, de2, 2.0 * stage.velocity_gain / rho2, relative2, unit)
    return tol_u, tol_r, alpha_bound(first, alpha, alpha_next, unit)


def look_ahead_bounds(design: TubeDesign, axle_offset: float, states, t, alpha, u_point,
                      u_ref, unit: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the error of the look-ahead step's ``(v, omega)``, shape (N, 2), and
    whether each point's inside/outside status is certain, shape (N,); see the module
    docstring. Inputs exact in the precision.

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube (its gain).
    axle_offset : float
        ``l``, m.
    states : array_like, shape (N, 3)
        ``(x, y, theta)``: m, m, rad.
    t : array_like, shape (N,)
        Times, s.
    alpha : array_like, shape (N, 4)
        ``alpha`` at the points, m.
    u_point : ndarray, shape (N, 2)
        The reference's law (13) at the point, m/s.
    u_ref : ndarray, shape (N, 2)
        The reference's ``(v, omega)`` before any clamp.
    unit : float
        Unit roundoff of the generated code's precision.

    Returns
    -------
    tol_u : ndarray, shape (N, 2)
        m/s and rad/s.
    certain : ndarray of bool, shape (N,)
        Every ``|e_i|`` of the point clear of 1 by twice its error bound, and the tube
        wider than four times its bounds' error.
    """
    from ..tube.look_ahead_reference import point

    states = np.atleast_2d(states)
    alpha = np.atleast_2d(alpha)
    p = point(states, axle_offset)
    gamma_l, gamma_u, _, _ = reference.adaptive_tube(design, np.atleast_1d(t), alpha)
    dg = gamma_bound(design, alpha, unit)
    width = np.maximum(gamma_u - gamma_l, GAMMA_D_MIN)
    e = (2.0 * p - (gamma_u + gamma_l)) / width
    dp = 4.0 * unit * (np.abs(p) + 4.0 * axle_offset)
    de = _divided(2.0 * dp + 2.0 * dg + unit * (2.0 * np.abs(p) + 2.0 * np.abs(e) * width), e,
                  width, 2.0 * dg, unit)
    relative = np.where(width > 2.0 * dg, 2.0 * dg / np.maximum(width - 2.0 * dg, 1e-300),
                        np.inf)
    du = _law_error(e, de, 4.0 * design.gain / width, relative, unit)
    spread = np.sum(du, axis=1) + 8.0 * unit * np.sum(np.abs(u_point) + du, axis=1)
    tol = np.stack([spread, spread / axle_offset + 2.0 * unit * np.abs(u_ref[:, 1])], axis=1)
    certain = np.all((np.abs(np.abs(e) - 1.0) > 2.0 * de) & (gamma_u - gamma_l > 4.0 * dg),
                     axis=1)
    return tol, certain
