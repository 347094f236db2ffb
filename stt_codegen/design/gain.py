"""The default gain ``k`` of law (13) and the lowest sampling rate, from the declared bounds.

The spec's ``[assumptions]`` (:class:`~stt_codegen.spec.loader.Assumptions`) bound the
symmetric part of the unknown input matrix ``g(x)`` by ``[g_min, g_max]``. Linearizing the
sampled loop of law (13) at ``e = 0``, where the tube is narrowest, gives
``e+ = (1 - 16 k dt lambda / gamma_d^2) e`` for each eigenvalue ``lambda`` of ``g``. The
gain that makes the worst factor smallest over ``lambda`` in ``[g_min, g_max]`` is

    k = gamma_d,min^2 / (8 dt (g_min + g_max)),

with factors in ``[-q, q]``, ``q = (g_max - g_min) / (g_max + g_min)``. For the default
``g_min = g_max = 1`` this is ``gamma_d,min^2 / (16 dt)``, the gain the toolkit has always
used. Whether the gain and rate really keep every plant of the assumptions in the tube
(drift, disturbance, coupling, the law's nonlinearity, the tube's motion) is decided by
:func:`stt_codegen.design.certificate.sampled.check_sampled`, and
:func:`stt_codegen.design.certificate.sampled.lowest_rate` searches the rate at which it passes (the
design layer never imports verify: verify builds on design).
"""

from __future__ import annotations

from dataclasses import replace

from ..spec.loader import Assumptions, Spec
from ..tube.parameters import TubeDesign

__all__ = ["derived_gain", "gain_derivation", "with_gain"]


def derived_gain(min_width: float, rate_hz: float, assumptions: Assumptions) -> float:
    """Default ``k`` of law (13): ``gamma_d,min^2 / (8 dt (g_min + g_max))``.

    Parameters
    ----------
    min_width : float
        ``gamma_d,min``, the tube's smallest width over time and dimensions, state units
        (the design uses its certificate's lower bound,
        :attr:`~stt_codegen.design.search.TubeCheck.min_width`).
    rate_hz : float
        ``1 / dt``, Hz.
    assumptions : Assumptions
        ``input_gain = (g_min, g_max)``.

    Returns
    -------
    float
        ``k``, (state units)^2 per second.
    """
    g_min, g_max = assumptions.input_gain
    dt = 1.0 / rate_hz
    return min_width**2 / (8.0 * dt * (g_min + g_max))  # for g = I: exactly the former default


def with_gain(tube: TubeDesign, min_width: float, spec: Spec) -> TubeDesign:
    """``tube`` with the spec's ``controller.gain``, or else the gain :func:`derived_gain`
    gives for its certified narrowest width: every design path sets ``k`` this way.

    Parameters
    ----------
    tube : TubeDesign
    min_width : float
        ``gamma_d,min``, the certificate's lower bound of the tube's width, state units.
    spec : Spec
        Its ``gain`` (``None``: derive) and ``[assumptions]``.

    Returns
    -------
    TubeDesign
        ``tube`` with ``gain`` set.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> with_gain(design.tube, design.check.min_width, design.spec).gain == design.tube.gain
    True
    """
    gain = (spec.gain if spec.gain is not None
            else derived_gain(min_width, tube.rate_hz, spec.assumptions))
    return replace(tube, gain=gain)


def gain_derivation(design: TubeDesign, min_width: float, min_width_time: float,
                    assumptions: Assumptions, explicit_gain: float | None = None) -> dict:
    """How ``k`` follows from the declared bounds, as a JSON-ready dict (``gain_derivation``).

    Parameters
    ----------
    design : TubeDesign
        The designed tube (its ``rate_hz`` and ``gain``).
    min_width, min_width_time : float
        The certified lower bound of the tube's width (state units) and the start of the
        interval where it is least (s): the width the design derived its gain from.
    assumptions : Assumptions
    explicit_gain : float, optional
        ``controller.gain`` when the spec sets it (then it is used, and the derived gain
        is reported next to it).

    Returns
    -------
    dict
        ``input_gain``, ``min_width`` (``gamma_d,min``) and where it occurs, ``dt``,
        ``derived_gain``, ``gain`` (the one used), ``source`` (``"derived"`` or
        ``"controller.gain"``), the linearized factors at the narrowest point for
        ``g_min`` and ``g_max`` and ``explanation`` (the derivation in words).
    """
    g_min, g_max = assumptions.input_gain
    w = float(min_width)
    dt = 1.0 / design.rate_hz
    derived = derived_gain(w, design.rate_hz, assumptions)
    gain = derived if explicit_gain is None else float(explicit_gain)
    factors = [1.0 - 16.0 * gain * dt * lam / w**2 for lam in (g_min, g_max)]
    stable_below = w**2 / (8.0 * dt * g_max)
    spread = (g_max - g_min) / (g_max + g_min)
    words = (f"narrowest tube gamma_d,min >= {w:.6g} (certified; least near t = "
             f"{min_width_time:.4f} s), dt = {dt:.6g} s, eigenvalues of the "
             f"symmetric part of g in [{g_min:g}, {g_max:g}]; the sampled loop linearized "
             f"there is e+ = (1 - 16 k dt lambda / gamma_d^2) e, stable for k < gamma_d,min^2"
             f" / (8 dt g_max) = {stable_below:.6g}; k = gamma_d,min^2 / (8 dt (g_min + "
             f"g_max)) = {derived:.6g} puts the factor in [-{spread:.3f}, {spread:.3f}]")
    if explicit_gain is not None:
        words += (f"; controller.gain = {gain:.6g} is used instead (factors "
                  f"{factors[0]:.3f} at g_min, {factors[1]:.3f} at g_max)")
    return {"input_gain": [g_min, g_max], "min_width": w, "min_width_time": min_width_time,
            "dt": dt, "derived_gain": derived, "gain": gain,
            "source": "derived" if explicit_gain is None else "controller.gain",
            "factor_at_g_min": factors[0], "factor_at_g_max": factors[1],
            "stable_gain_limit": stable_below, "explanation": words}
