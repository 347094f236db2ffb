"""What bounds the command of a design without ``[actuator]``: the peak the certificate
proves inside the declared class, and the clamp of the deployed code outside it.

Without ``[actuator] input_bound`` nothing limits the command to an actuator's range. Inside
the declared class of plants the certificate bounds it (the cascade's certified peak of the
physical input; for the differential drive, law (13)'s peak at the look-ahead point mapped
to ``(v, omega)``). Outside it (a heavier plant, a contact, an undeclared delay) the only
bound is the deployed law's clamp of the normalized errors at ``E_MAX``:

* law (13) at a point: ``|u_i| <= 4 k phi(E_MAX) / GAMMA_D_MIN`` (the width floored);
  the base's ``|v| <= |u|``, ``|omega| <= |u| / l``;
* the cascade's second stage: ``|u_i| <= 2 k2 phi(E_MAX) / rho2_floor_i``
  (``rho2 >= rho2_floor`` for ``t >= 0``),

with ``phi(s) = 2 atanh(s) / (1 - s^2)`` (:mod:`.input_bound`). These are far beyond any
actuator, which is what :attr:`~.result.Design.output_warning` says (docs/second-order.md,
"Force limits"; docs/differential-drive.md). Each variant names its function by the role
``output_limits`` (:mod:`~stt_codegen.spec.variants`); the first order's law (13) is the
paper's and takes no warning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..tube.parameters import E_MAX, GAMMA_D_MIN
from .input_bound import InputProof
from .look_ahead import base_proof, point_proof

if TYPE_CHECKING:
    from ..tube.second_stage import SecondStage
    from .result import Design

__all__ = ["OutputLimits", "ROUNDING", "base_clamp", "cascade_clamp", "cascade_output_limits",
           "clamp_phi", "look_ahead_output_limits", "no_output_limits"]


@dataclass(frozen=True)
class OutputLimits:
    """The command's bounds of a design without ``[actuator]``, per physical input.

    Attributes
    ----------
    proved : InputProof
        Inside the declared class: the certificate's peak of each input (input units).
    clamp : tuple of float
        Whatever the state and the plant: the deployed code's bound, from the clamp of the
        errors at ``E_MAX`` (input units).
    """

    proved: InputProof
    clamp: tuple[float, ...]


#: Relative outward rounding of the clamp's bounds (above the rounding of their terms).
ROUNDING = 1e-12


def clamp_phi() -> float:
    """``phi(E_MAX) = 2 atanh(E_MAX) / (1 - E_MAX^2)``, rounded up by :data:`ROUNDING`: a
    bound of the largest ``|u_i| gamma_d_i / (4 k)`` law (13)'s clamped errors give
    (about 7.6e6).

    Returns
    -------
    float
    """
    return (1.0 + ROUNDING) * 2.0 * math.atanh(E_MAX) / (1.0 - E_MAX * E_MAX)


def cascade_clamp(stage: SecondStage) -> tuple[float, ...]:
    """The cascade's ``|u_i| <= 2 k2 phi(E_MAX) / rho2_floor_i``, whatever the state and
    the plant (input units).

    Parameters
    ----------
    stage : SecondStage

    Returns
    -------
    tuple of float
        One per physical input.
    """
    return tuple(2.0 * stage.velocity_gain * clamp_phi() / floor for floor in stage.width_floor)


def base_clamp(gain: float, axle_offset: float) -> tuple[float, float]:
    """The base's ``(|v|, |omega|)`` from law (13)'s clamp at the 2-D look-ahead point,
    ``|u_i| <= 4 k phi(E_MAX) / GAMMA_D_MIN``: ``|v| <= |u|``, ``|omega| <= |u| / l``.

    Parameters
    ----------
    gain : float
        ``k`` of law (13).
    axle_offset : float
        ``l``, m.

    Returns
    -------
    (float, float)
        m/s, rad/s.
    """
    speed = math.sqrt(2.0) * 4.0 * gain * clamp_phi() / GAMMA_D_MIN
    return speed, speed / axle_offset


def no_output_limits(design: Design) -> None:
    """The first order's role ``output_limits``: none (law (13) on the plant's state).

    Parameters
    ----------
    design : Design

    Returns
    -------
    None
    """
    return None


def cascade_output_limits(design: Design) -> OutputLimits:
    """The cascade's physical inputs: the certified peak of its second stage, and ``2 k2
    phi(E_MAX) / rho2_floor_i`` (role ``output_limits``).

    Parameters
    ----------
    design : Design
        Of a second-order spec.

    Returns
    -------
    OutputLimits

    Raises
    ------
    DesignError
        The second stage is not certified.
    """
    stage, derivation = design.second_stage
    report = derivation["certificate"]
    proved = InputProof(True, tuple(report["peak_input"]), tuple(report["peak_input_time"]),
                        float(report["horizon"]))
    return OutputLimits(proved, cascade_clamp(stage))


def look_ahead_output_limits(design: Design) -> OutputLimits:
    """The base's ``(v, omega)``: law (13)'s proved peak at the look-ahead point mapped by
    ``|v| <= |u|``, ``|omega| <= |u| / l``, and the clamp's ``|u_i| <= 4 k phi(E_MAX) /
    GAMMA_D_MIN`` mapped alike (role ``output_limits``).

    Parameters
    ----------
    design : Design
        Of a differential-drive spec.

    Returns
    -------
    OutputLimits
        ``proved`` not proved when the sampled-data check fails.
    """
    offset = design.spec.drive.axle_offset
    proved = base_proof(point_proof(design.tube, design.spec), design.tube, design.spec)
    return OutputLimits(proved, base_clamp(design.tube.gain, offset))
