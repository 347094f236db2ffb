"""The differential-drive base as a simulated plant: its kinematics written once in CasADi.

The base's state is ``(x, y, theta)``: the axle's midpoint (m) and the heading (rad). It is
commanded ``(v, omega)``; its wheels, of relative radius errors ``delta_R``, ``delta_L``
(``plant.wheel_radius_error``), turn at the speeds that command asks of exact wheels, so
the base moves with

    v_act     = (1 + m) v + (b/2) d omega + w_v,
    omega_act = (2/b) d v + (1 + m) omega + w_omega,
    x_dot = v_act cos theta - w_lat sin theta,  y_dot = v_act sin theta + w_lat cos theta,
    theta_dot = omega_act,

with ``m = (delta_R + delta_L)/2``, ``d = (delta_R - delta_L)/2``, ``b`` the track width
and the slip ``w = (w_v, w_lat, w_omega)``, a seeded :class:`~.plants.Disturbance` of
amplitudes ``plant.slip``. :func:`base_rhs` is the one definition: the simulation prints
it to Python (:func:`stt_codegen.runtime.plants.differential_drive_plant`), as the
other plants' dynamics.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

__all__ = ["base_rhs"]


@lru_cache(maxsize=None)
def base_rhs() -> ca.Function:
    """``base_rhs(state, u, wheel_radius_error, track_width, slip) -> state_dot``.

    Returns
    -------
    casadi.Function
        Inputs ``state`` (3: m, m, rad), ``u`` (2: the commanded ``v`` in m/s and
        ``omega`` in rad/s), ``wheel_radius_error`` (2, relative), ``track_width`` (m) and
        ``slip`` (3: m/s, m/s, rad/s, the slip at this instant); output ``state_dot`` (3).
    """
    state, u = ca.SX.sym("state", 3), ca.SX.sym("u", 2)
    error, width, slip = ca.SX.sym("wheel_radius_error", 2), ca.SX.sym("track_width"), \
        ca.SX.sym("slip", 3)
    m, d = 0.5 * (error[0] + error[1]), 0.5 * (error[0] - error[1])
    v = (1 + m) * u[0] + 0.5 * width * d * u[1] + slip[0]
    omega = 2 * d / width * u[0] + (1 + m) * u[1] + slip[2]
    c, s = ca.cos(state[2]), ca.sin(state[2])
    state_dot = ca.vertcat(v * c - slip[1] * s, v * s + slip[1] * c, omega)
    return ca.Function("base_rhs", [state, u, error, width, slip], [state_dot],
                       ["state", "u", "wheel_radius_error", "track_width", "slip"],
                       ["state_dot"])
