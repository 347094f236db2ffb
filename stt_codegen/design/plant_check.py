"""Assumption 2 for a plant the spec names: the symmetric part of ``g`` positive definite.

Law (13) with its positive gain ``k`` keeps ``x`` in the tube only if the symmetric part
``g_s = (g + g^T) / 2`` of the input matrix is uniformly positive definite (Assumption 2;
for a negative definite ``g_s`` Remark 4.2 asks a negative gain, which the controller
does not take). The design refuses a spec whose named plant violates it, before any tube
is built: a tube for such a plant is certified, but no controller of law (13) follows it.
Plain numpy, so that ``verify`` (which also proves the bound symbolically) can reuse it.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..spec.loader import Spec

__all__ = ["plant_failure", "wheel_error_failure"]

#: Heading range of the omnidirectional robot (eq. (14)) where ``g_s`` is positive
#: definite: ``g_s = diag(cos x3, cos x3, 1)`` (docs/decisions.md, decision 10).
HALF_PI = math.pi / 2


def symmetric_eigenvalues(g: Sequence[Sequence[float]]) -> np.ndarray:
    """Eigenvalues of ``(g + g^T) / 2``, ascending.

    Parameters
    ----------
    g : array_like, shape (n, n)

    Returns
    -------
    ndarray, shape (n,)
    """
    g = np.asarray(g, dtype=float)
    return np.linalg.eigvalsh((g + g.T) / 2)


def linear_plant_failure(g: Sequence[Sequence[float]]) -> str:
    """Why a linear plant's constant ``g`` violates Assumption 2 ("" when it holds).

    The reason names ``plant.g`` and the eigenvalue of ``(g + g^T) / 2`` closest to
    (or beyond) zero.
    """
    eig = symmetric_eigenvalues(g)
    if eig[0] > 0.0:
        return ""
    if eig[-1] < 0.0:
        return (f"plant.g: (g + g^T)/2 is negative definite (largest eigenvalue "
                f"{eig[-1]:.6g}): Assumption 2 asks it positive definite, and law (13) "
                "with its positive gain k would push x out of the tube (Remark 4.2's "
                "negative gain is not supported)")
    return (f"plant.g: (g + g^T)/2 has the eigenvalue {eig[0]:.6g} <= 0: Assumption 2 asks "
            "it positive definite, else no gain k of law (13) keeps x in the tube")


def heading_range_failure(lower: float, upper: float) -> str:
    """Why a heading range ``[lower, upper]`` (rad) of eq. (14) loses Assumption 2 ("" if not).

    ``g_s = diag(cos x3, cos x3, 1)`` is positive definite only while ``|x3| < pi/2``.
    """
    if -HALF_PI < lower and upper < HALF_PI:
        return ""
    return (f"state_space: the heading x3 ranges over [{lower:g}, {upper:g}] rad, which "
            "reaches |x3| = pi/2 where cos x3 = 0: the omnidirectional robot's (g + g^T)/2 "
            "= diag(cos x3, cos x3, 1) is then not positive definite (Assumption 2)")


def wheel_error_failure(spec: Spec) -> str:
    """Why a differential drive's wheel errors lose Assumption 2 for its look-ahead point
    ("" if not): the symmetric part of ``g(theta)`` has the smallest eigenvalue ``1 + m -
    |d| s`` (:mod:`stt_codegen.spec.differential_drive`).

    Parameters
    ----------
    spec : Spec
        A differential-drive spec.

    Returns
    -------
    str
        The reason, naming ``plant.wheel_radius_error``, or ``""``.
    """
    g_min = spec.assumptions.input_gain[0]
    if g_min > 0.0:
        return ""
    return (f"plant.wheel_radius_error: with wheel errors {list(spec.drive.wheel_radius_error)} "
            f"the look-ahead point's (g + g^T)/2 has the eigenvalue {g_min:.6g} <= 0 at some "
            "heading: Assumption 2 fails (smaller errors, or an axle_offset closer to half the "
            "track_width)")


def plant_failure(spec: Spec) -> str:
    """Why the spec's plant violates Assumption 2 ("" when it holds or is not known).

    The ``linear`` model's ``plant.g`` (:func:`linear_plant_failure`) and the
    omnidirectional robot's heading range, the third dimension of the state space
    (:func:`heading_range_failure`). The single integrator (``g = I``) always holds.

    Parameters
    ----------
    spec : Spec
        The spec (its plant model, ``plant.g`` and state space).

    Returns
    -------
    str
        The reason, naming the violated condition of Assumption 2, or ``""``.
    """
    failure = PLANT_FAILURES.get(spec.plant_model)
    return failure(spec) if failure is not None else ""


#: The design-time Assumption-2 check of each first-order model whose ``g`` can violate
#: it, ``spec -> reason`` (the single integrator's ``g = I`` cannot).
PLANT_FAILURES = {
    "linear": lambda spec: ("" if spec.linear_plant is None
                            else linear_plant_failure(spec.linear_plant.g)),
    "omnidirectional": lambda spec: heading_range_failure(spec.state_space.lower[2],
                                                          spec.state_space.upper[2]),
    "differential-drive": lambda spec: wheel_error_failure(spec),
}
