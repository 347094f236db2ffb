"""The sampled-data proof carried across a switch of tubes (docs/sensing.md, "The switch").

A replanned tube takes over at a sample ``t_s`` where the state lies wherever the active
tube's proof leaves it: its sampled-data check (:func:`~.certificate.sampled.check_sampled`)
bounds ``|e_i(t_k)|`` at every sample, so at ``t_s`` the state lies in the active tube's box
there shrunk to that bound (:func:`state_at`). The run-time switch test adds
``|e_i| <= MAX_INITIAL_ERROR`` in the new tube. The new tube's own check then starts from
the box of ``e(0)`` both allow (:func:`switch_error`), not from its ``x(0)``
(:func:`proved_error`): a plan is certified from the state it may meet at its switch, and
carries its bound of ``|e|`` to the next switch. The spec's own tube starts the chain from
its ``x(0)``.
"""

from __future__ import annotations

import numpy as np

from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube import reference
from .certificate.sampled import sampled_check_of
from .result import Design
from .samples import sample_tube
from .search import MAX_INITIAL_ERROR

__all__ = ["ROUNDING", "proved_error", "state_at", "switch_error"]

#: Each end of a box of ``e(0)`` is moved out by this (dimensionless): the state's box and
#: the switch test are computed in floating point on both sides (the proof's floats here,
#: the deployed step's there), far below every margin the check proves.
ROUNDING = 1e-9


def state_at(bounds: tuple[np.ndarray, np.ndarray] | None, rate_hz: float, t_local: float
             ) -> tuple[np.ndarray, np.ndarray] | None:
    """Where the state may be at the sample ``t_local`` of a plan's tube (its time), by its
    proof (:func:`proved_error`); ``None`` where the plan carries no bound there.

    Parameters
    ----------
    bounds : (ndarray, ndarray) or None
        The plan's proved boxes of the state at its samples ``t_k = k / rate_hz``, lower
        and upper corners, shape (K + 1, n) each.
    rate_hz : float
        The controller's rate, Hz.
    t_local : float
        A sample of the tube's time, s.

    Returns
    -------
    (ndarray, ndarray) or None
        Lower and upper corners, state units, shape (n,) each.
    """
    if bounds is None:
        return None
    k = int(round(t_local * rate_hz))
    if not 0 <= k < bounds[0].shape[0]:
        return None
    return bounds[0][k], bounds[1][k]


def switch_error(design: Design, state: tuple[np.ndarray, np.ndarray] | None
                 ) -> tuple[tuple[float, float], ...] | None:
    """The box of ``e(0)`` of ``design``'s tube at a switch: the state's box ``state``
    (:func:`state_at`) in the tube's coordinates at ``t' = 0``, cut to the switch test's
    ``|e_i| <= MAX_INITIAL_ERROR`` (that test alone where ``state`` is ``None``), each end
    moved out by :data:`ROUNDING`; ``None`` when the two do not meet (every switch to it
    would be refused).

    Parameters
    ----------
    design : Design
        The new tube's design.
    state : (ndarray, ndarray) or None
        Where the state may be at the switch, state units.

    Returns
    -------
    tuple of (float, float) or None
        One interval per dimension.
    """
    n = design.tube.dimension
    # the deployed test's e and these floats may differ by rounding: widened by ROUNDING
    edge = MAX_INITIAL_ERROR + ROUNDING
    if state is None:
        return ((-edge, edge),) * n
    with reference.numpy_math():
        samples = sample_tube(design.tube, horizon=1.0 / design.tube.rate_hz)
    lo, hi = samples.gamma_lower[0], samples.gamma_upper[0]
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    out = []
    for i in range(n):
        a = max(float((state[0][i] - centre[i]) / half[i]) - ROUNDING, -edge)
        b = min(float((state[1][i] - centre[i]) / half[i]) + ROUNDING, edge)
        if not a <= b:
            return None
        out.append((a, b))
    return tuple(out)


def proved_error(design: Design, spec: Spec,
                 initial_error: tuple[tuple[float, float], ...] | None = None
                 ) -> tuple[tuple[np.ndarray, np.ndarray] | None, str]:
    """The sampled-data check of ``design``'s tube for ``spec``'s plant class from
    ``initial_error`` (default its ``x(0)``), and with ``[actuator]`` the variant's input
    proof from there too: where the proof keeps the state at every sample (the tube's box
    shrunk to the proved ``|e_i(t_k)|``), or ``None`` and why.

    Parameters
    ----------
    design : Design
        A certified design.
    spec : Spec
        Its plant class and ``[actuator]``.
    initial_error : tuple of (float, float), optional
        :func:`switch_error`.

    Returns
    -------
    bounds : (ndarray, ndarray) or None
        Lower and upper corners of the state at the samples ``t_k = k / rate_hz``, state
        units, shape (K + 1, n) each.
    reason : str
        Empty when proved.
    """
    samples, check = sampled_check_of(design.tube, spec, initial_error=initial_error)
    if not check.passed or check.abs_e is None:
        return None, f"the sampled loop is not proved from the switch: {check.reason}"
    if spec.input_bound is not None:
        proof = variant_of(spec).entry("input_proof")(design, spec,
                                                      initial_error=initial_error)
        if not proof.meets(spec.input_bound):
            return None, ("the input bound is not proved from the switch: "
                          + (proof.reason or f"peaks {list(proof.peak)}"))
    abs_e = np.asarray(check.abs_e, dtype=float)
    k = min(abs_e.shape[0], samples.t.size)
    lo, hi = samples.gamma_lower[:k], samples.gamma_upper[:k]
    centre, reach = 0.5 * (lo + hi), 0.5 * (hi - lo) * abs_e[:k]
    return (centre - reach, centre + reach), ""
