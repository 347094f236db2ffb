"""The tube at the sampling instants of the deployed controller (per-sample, on a budget).

The design and its certificate never work per sample; the closed-loop simulation and
the tests that compare backends do, and refuse runs over :data:`STEP_BUDGET` steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SpecError
from ..tube import reference
from ..tube.model import alpha_trajectory_function
from ..tube.parameters import TubeDesign

__all__ = ["HORIZON_FACTOR", "STEP_BUDGET", "TubeSamples", "check_step_budget", "sample_tube"]

#: Default horizon of a sampled tube, as a multiple of ``t_c``.
HORIZON_FACTOR = 1.1
#: Most controller steps a per-sample computation (:func:`sample_tube`, ``simulate``)
#: accepts: about 10 minutes of simulated time at 1 kHz, a few hundred MB of arrays.
STEP_BUDGET = 1_000_000


def check_step_budget(steps: int, horizon: float, rate_hz: float) -> None:
    """Refuse a per-sample run of more than :data:`STEP_BUDGET` steps.

    Parameters
    ----------
    steps : int
        The number of sampling periods of the run.
    horizon : float
        The run's length, s.
    rate_hz : float
        The sampling rate, Hz.

    Raises
    ------
    SpecError
        Naming ``prescribed_time`` and ``controller.rate_hz``, whose product is the count.
    """
    if steps > STEP_BUDGET:
        raise SpecError("prescribed_time", f"a sampled run of {horizon:g} s at controller.rate_hz "
                        f"= {rate_hz:g} Hz takes {steps:.3g} steps, over the budget of "
                        f"{STEP_BUDGET} for a per-sample simulation (the design and its "
                        "certificate have no such limit)")


@dataclass(frozen=True)
class TubeSamples:
    """The tube sampled on a grid: ``t`` (N,), ``alpha`` (N, 2n), ``gamma_*`` (N, n).

    Attributes
    ----------
    t : ndarray, shape (N,)
        The sampling instants ``k / rate_hz``, s, from 0.
    alpha : ndarray, shape (N, 2n)
        ``[alpha_L, alpha_U]`` of eq. (11) at each instant, state units.
    gamma_lower, gamma_upper : ndarray, shape (N, n)
        The adaptive tube ``gamma_L``, ``gamma_U`` of eq. (10), state units.
    gamma_lower_dot, gamma_upper_dot : ndarray, shape (N, n)
        Their time derivatives along the adaptive law, state units/s.
    """

    t: np.ndarray
    alpha: np.ndarray
    gamma_lower: np.ndarray
    gamma_upper: np.ndarray
    gamma_lower_dot: np.ndarray
    gamma_upper_dot: np.ndarray


def sample_tube(design: TubeDesign, horizon: float | None = None) -> TubeSamples:
    """The tube at every sampling instant of the deployed controller.

    ``alpha`` follows the deployed implicit step (the same Newton iteration as the
    generated code), starting from ``alpha(0) = 0``.

    Parameters
    ----------
    design : TubeDesign
    horizon : float, optional
        End time, seconds; default ``HORIZON_FACTOR * t_c``.

    Returns
    -------
    TubeSamples
        The tube at ``N = ceil(horizon rate_hz) + 1`` instants.

    Raises
    ------
    SpecError
        More than :data:`STEP_BUDGET` steps.
    """
    if horizon is None:
        horizon = HORIZON_FACTOR * design.prescribed_time
    dt = 1.0 / design.rate_hz
    steps = int(math.ceil(horizon * design.rate_hz))
    check_step_budget(steps, horizon, design.rate_hz)
    t = np.arange(steps + 1) * dt
    psi = reference.conflict_distance(design, t[1:])
    trajectory = alpha_trajectory_function(design, steps)
    alpha_tail = np.array(trajectory(np.zeros(2 * design.dimension), psi.T, dt)).T
    alpha = np.vstack([np.zeros((1, 2 * design.dimension)), alpha_tail])
    g_l, g_u, g_l_dot, g_u_dot = reference.adaptive_tube(design, t, alpha)
    return TubeSamples(t, alpha, g_l, g_u, g_l_dot, g_u_dot)
