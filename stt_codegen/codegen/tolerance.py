"""Error bounds of the generated code against the double reference, per output entry.

Used for the tolerances of the test vectors (JSON and the C self-test) and by the
single-precision equivalence tests. ``unit`` is the unit roundoff: ``2**-53`` (double),
``2**-24`` (single). Inputs are taken as exact (the vectors' inputs are float32 numbers,
exact in both precisions); the bound covers the rounding of the generated code and of a
libm whose functions are within a few ulp of correctly rounded.

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
* **alpha_next.** The Newton iteration converges to a few ulp of the root; the root's
  sensitivity to ``psi`` is at most 1 and to ``theta``'s relative error at most
  ``|alpha_next| + |alpha|``. Bound: ``GAMMA_FACTOR * unit * (S + |alpha| + |alpha_next|)``.
"""

from __future__ import annotations

import numpy as np

from ..tube.parameters import E_MAX, GAMMA_D_MIN, TubeDesign

UNIT_DOUBLE = 2.0 ** -53
UNIT_SINGLE = 2.0 ** -24
#: Rounding count of a tube bound, with a 4x margin.
GAMMA_FACTOR = 64.0
#: Local roundings of the law (13) after ``e``.
LAW_FACTOR = 16.0
#: Floor of the double tolerance: the acceptance criterion ``1e-12 max(1, |ref|)``.
DOUBLE_FLOOR = 1e-12


def unit_roundoff(precision: str) -> float:
    """``2**-53`` for ``"double"``, ``2**-24`` for ``"single"``."""
    return UNIT_DOUBLE if precision == "double" else UNIT_SINGLE


def scale(design: TubeDesign, alpha: np.ndarray) -> np.ndarray:
    """``S`` per point, shape (N,): ``1 + max |state bound| + max |alpha|``."""
    bound = max(max(abs(v) for v in design.state_lower), max(abs(v) for v in design.state_upper))
    return 1.0 + bound + np.max(np.abs(np.atleast_2d(alpha)), axis=1)


def _g(e: np.ndarray) -> np.ndarray:
    e = np.clip(e, -E_MAX, E_MAX)
    return np.log((1.0 + e) / (1.0 - e)) / (1.0 - e * e)


def gamma_bound(design: TubeDesign, alpha, unit: float) -> np.ndarray:
    """Bound on the error of ``gamma_L``/``gamma_U``, shape (N, 1) (broadcasts over n)."""
    return (GAMMA_FACTOR * unit * scale(design, alpha))[:, None]


def u_bound(design: TubeDesign, x, alpha, gamma_l, gamma_u, u_ref, unit: float) -> np.ndarray:
    """Bound on the error of ``u``, shape (N, n); see the module docstring."""
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
    """Whether the inside/outside status cannot depend on rounding, shape (N,)."""
    x = np.atleast_2d(x)
    dg = gamma_bound(design, alpha, unit)
    width = gamma_u - gamma_l
    safe_width = np.maximum(width, GAMMA_D_MIN)
    e = (2.0 * x - (gamma_u + gamma_l)) / safe_width
    de = (2.0 * np.abs(x) * unit + 2.0 * (1.0 + np.abs(e)) * dg) / safe_width + 4.0 * unit
    clear = (np.abs(np.abs(e) - 1.0) > 2.0 * de) & (np.abs(width) > 4.0 * dg)
    return np.all(clear, axis=1)


def alpha_bound(design: TubeDesign, alpha, alpha_next, unit: float) -> np.ndarray:
    """Bound on the error of ``alpha_next``, shape (N, 2n)."""
    alpha = np.atleast_2d(alpha)
    return GAMMA_FACTOR * unit * (scale(design, alpha)[:, None] + np.abs(alpha)
                                  + np.abs(alpha_next))


def with_double_floor(bound: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``max(bound, 1e-12 max(1, |reference|))``: the double tolerance of the vectors."""
    return np.maximum(bound, DOUBLE_FLOOR * np.maximum(1.0, np.abs(reference)))
