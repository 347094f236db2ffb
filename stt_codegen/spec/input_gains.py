"""The input gain range of the plant class a variant's certificate covers: the range the
delay-compensating prediction takes its middle from (docs/sampled-data.md, "Compensating a
delay"). One function per variant, named by the variant's ``input_gain`` role."""

from __future__ import annotations

from .loader import Spec

__all__ = ["cascade_input_gain", "declared_input_gain"]


def declared_input_gain(spec: Spec) -> tuple[float, float]:
    """``(g_min, g_max)`` of ``[assumptions] input_gain`` (law (13) and the look-ahead law).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    (float, float)
        The plant's input units to state units per second.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> declared_input_gain(stt.load_spec("omnirobot-s1"))[0] > 0.0
    True
    """
    low, high = spec.assumptions.input_gain
    return float(low), float(high)


def cascade_input_gain(spec: Spec) -> tuple[float, float]:
    """``(g_min, g_max)`` of the second-order plant's input gain (the eigenvalue range of
    ``g`` the cascade's certificate covers, ``CascadeClass.g_min``, ``g_max``).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.

    Returns
    -------
    (float, float)
        Force (or torque) units to acceleration.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> cascade_input_gain(stt.load_spec("second-order-s1"))[0] > 0.0
    True
    """
    low, high = spec.second_order.input_gain
    return float(low), float(high)
