"""Default numbers of the cascade's second stage from declared bounds (docs/second-order.md).

Linearized at ``e1 = e2 = 0`` the cascade is two first-order loops: the velocity error
``z = x2 - r`` obeys ``z_dot = -(4 k2 lambda / rho2^2) z + (f + w - r_dot)`` for each
eigenvalue ``lambda`` of the symmetric part of ``g``, and the position error
``x1_dot = -(16 k1 / gamma_d^2) (x1 - gamma_s / 2) + z + ...``. The defaults put

* the inner bandwidth ``omega2 = 4 k2 lambda / rho2_floor^2`` at ``0.1 / dt`` for
  ``lambda = g_max`` (the sampled inner loop's factor ``1 - omega2 dt`` in ``[0.9, 1 -
  0.1 g_min / g_max]``, far from -1 also where the transform's slope grows 20-fold, near
  ``|e2| = 0.96``);
* the outer bandwidth at the narrowest tube, ``omega1 = 16 k1 / gamma_d,min^2``, a tenth
  of the slowest inner one (time-scale separation);
* the floor ``rho2_floor = 4 (F + omega1 V) / omega2,min``: four times the linear loop's
  steady velocity error under the declared bound ``F`` on ``|f + w|`` and the estimate
  ``omega1 V`` of ``|r_dot|`` (``V``: the fastest bound of the designed tube, sampled);
* ``rho2(0) = |x2(0) - r(x1(0), 0)| + rho2_floor`` (contains the initial error), shrinking
  at ``l = omega1``.

These are engineering defaults, not a proof: the sampled cascade is not certified
(docs/second-order.md, "What is not proved").
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ..tube import reference
from ..tube.parameters import TubeDesign
from ..tube.second_stage import SecondStage

if TYPE_CHECKING:
    from .result import Design

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
    ``[0, t_c]``, state units per second (sampled: an estimate, not a bound)."""
    t = np.linspace(0.0, design.prescribed_time, samples)
    with reference.numpy_math():
        _, _, rho_l_dot, rho_u_dot = reference.reach_tube(design, t)
        _, _, beta_l_dot, beta_u_dot = reference.circumvent(design, t)
    rates = np.concatenate([np.abs(v).ravel() for v in (rho_l_dot, rho_u_dot, beta_l_dot,
                                                         beta_u_dot)])
    return float(np.max(rates[np.isfinite(rates)]))


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


def second_stage_of(design: "Design") -> tuple[SecondStage, dict]:
    """The default second stage of a design whose spec has a second-order ``plant.model``.

    ``F`` is ``assumptions.drift_bound`` plus ``plant.disturbance_amplitude`` (the bound
    on every ``|w_i|``); ``g`` in ``assumptions.input_gain``; ``x2(0)`` is
    ``initial.velocity``; ``gamma_d,min`` the certified narrowest width.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`.

    Returns
    -------
    stage : SecondStage
    derivation : dict
        As :func:`derived_second_stage`.

    Raises
    ------
    SpecError
        The spec's ``plant.model`` is first order (field ``plant.model``).
    """
    from ..errors import SpecError
    order = design.spec.second_order
    if order is None:
        raise SpecError("plant.model", "the spec describes a first-order plant (not a "
                                       "second-order plant.model)")
    return derived_second_stage(design.tube, design.check.min_width, order.input_gain,
                                order.drift_bound + design.spec.disturbance_amplitude,
                                order.initial_velocity)
