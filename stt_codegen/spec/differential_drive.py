"""A differential-drive base, ``[plant] model = "differential-drive"``: its numbers and bounds.

The base (states ``x, y, theta`` of the axle's midpoint and the heading; inputs the
forward speed ``v`` and the turn rate ``omega``) is non-holonomic, so the tube holds its
*look-ahead point* ``p = (x, y) + l (cos theta, sin theta)``, at ``l = axle_offset`` ahead
of the axle, whose velocity is ``p_dot = R(theta) diag(1, l) (v, omega)``: a full-rank
function of the inputs. The controller computes law (13) for ``p`` and sends ``(v, omega)
= diag(1, 1/l) R(theta)^T u``; the plant then moves ``p`` as system (1) with ``f = 0`` and

    g(theta) = R(theta) diag(1, l) W diag(1, 1/l) R(theta)^T,
    W = [[1 + m, (b/2) d], [(2/b) d, 1 + m]],

where the wheels' relative radius errors ``delta_R``, ``delta_L`` give ``m = (delta_R +
delta_L)/2`` and ``d = (delta_R - delta_L)/2``, ``b`` is the track width
(docs/differential-drive.md derives it). With ``beta = b / (2 l)``, ``s = (beta +
1/beta)/2`` and ``k = (beta - 1/beta)/2``, for every heading:

* the symmetric part of ``g`` has the eigenvalues ``1 + m -+ |d| s`` (``input_gain``);
* the skew part has the norm ``|d| |k|`` (``input_gain_skew``);
* an off-diagonal entry is at most ``|d| (s + |k|)`` (``input_gain_coupling``).

Slip is a bounded disturbance on the body's velocities (forward, lateral, turn): it moves
``p`` by ``R(theta) (w_v, w_lat + l w_omega)``, at most ``sqrt(s_v^2 + (s_lat + l
s_omega)^2)`` (``disturbance_bound``). ``g`` depends on the heading, which is not a state
of the tube: it may change between samples however the inputs turn the base, so the class
is the one whose ``g`` may jump (no Lipschitz bound in ``p``) unless ``d = 0``.

Plain Python, as the loader needs it; the bounds are
:func:`stt_codegen.spec.model_bounds.differential_drive_bounds`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DifferentialDrive"]


@dataclass(frozen=True)
class DifferentialDrive:
    """The differential-drive base of a spec (``[plant]`` and ``initial.heading``).

    Attributes
    ----------
    axle_offset : float
        ``l`` (``plant.axle_offset``): how far ahead of the axle's midpoint the look-ahead
        point lies, m, positive.
    track_width : float
        ``b`` (``plant.track_width``): the distance between the wheels, m, positive.
    wheel_radius_error : tuple of float, (delta_R, delta_L)
        The simulated base's relative wheel-radius errors (right, left), each in ``(-1,
        1)``: a wheel of radius ``r (1 + delta)`` where the controller assumes ``r``.
    slip : tuple of float, (s_v, s_lat, s_omega)
        Amplitudes of the simulated slip: the forward and lateral speeds (m/s) and the
        turn rate (rad/s) the ground adds, each ``>= 0``.
    heading : float
        ``theta(0)`` (``initial.heading``), rad.
    wheel_radius : float or None
        ``plant.wheel_radius``, m: the nominal radius that turns ``(v, omega)`` into wheel
        speeds for a MuJoCo base (``plant.mjcf``); ``None`` without one.
    """

    axle_offset: float
    track_width: float
    wheel_radius_error: tuple[float, float] = (0.0, 0.0)
    slip: tuple[float, float, float] = (0.0, 0.0, 0.0)
    heading: float = 0.0
    wheel_radius: float | None = None

    @property
    def mean_error(self) -> float:
        """``m = (delta_R + delta_L) / 2``: the error both wheels share."""
        return 0.5 * (self.wheel_radius_error[0] + self.wheel_radius_error[1])

    @property
    def differential_error(self) -> float:
        """``d = (delta_R - delta_L) / 2``: the error that turns the base."""
        return 0.5 * (self.wheel_radius_error[0] - self.wheel_radius_error[1])

    def wheel_speeds(self, u) -> list[float]:
        """The wheels' angular speeds ``(right, left)`` that give ``u = (v, omega)`` with
        wheels of :attr:`wheel_radius`, rad/s.

        Parameters
        ----------
        u : sequence of float, length 2
            ``v`` (m/s) and ``omega`` (rad/s).

        Returns
        -------
        list of float
            ``((v + b omega / 2) / r, (v - b omega / 2) / r)``.
        """
        half = 0.5 * self.track_width * float(u[1])
        return [(float(u[0]) + half) / self.wheel_radius, (float(u[0]) - half) / self.wheel_radius]

    def initial_axle(self, point: tuple[float, ...]) -> tuple[float, float, float]:
        """The base's state ``(x, y, theta)`` at ``t = 0`` whose look-ahead point is
        ``point``.

        Parameters
        ----------
        point : sequence of float, length 2
            ``p(0)``, m.

        Returns
        -------
        tuple of float, (x, y, theta)
            The axle's midpoint (m) and the heading (rad).
        """
        l, th = self.axle_offset, self.heading
        return (point[0] - l * math.cos(th), point[1] - l * math.sin(th), th)
