"""The delay-compensating prediction of a spec with ``[controller] compensate_delay``: the
variant's ``predictor`` role at the spec's delay and the middle of its declared input gain
(docs/sampled-data.md, "Compensating a delay"). One place, so that the certificate
(:mod:`.certificate.predicted`), the simulated loops and the generated code predict with
the same numbers."""

from __future__ import annotations

import casadi as ca

from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube.parameters import TubeDesign

__all__ = ["delay_predictor", "mid_gain"]


def mid_gain(spec: Spec) -> float:
    """``g_mid = (g_min + g_max) / 2`` of the input gain range of the plant class the
    variant's certificate covers (its ``input_gain`` role: ``[assumptions] input_gain``,
    the second-order plant's for the cascade): the gain the prediction moves the state
    with.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    float
        The gain, in the units of the plant's ``g``.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> mid_gain(stt.load_spec("omnirobot-s1")) > 0.0
    True
    """
    low, high = variant_of(spec).entry("input_gain")(spec)
    return 0.5 * (low + high)


def delay_predictor(spec: Spec, tube: TubeDesign, stage) -> ca.Function | None:
    """``predict(x, u_held) -> x_hat`` of a spec with ``[controller] compensate_delay``, or
    ``None`` without it.

    Parameters
    ----------
    spec : Spec
        Its ``delay``, ``compensate_delay`` and ``[assumptions] input_gain``.
    tube : TubeDesign
        The design's tube.
    stage : object
        The design's stage (:attr:`~stt_codegen.design.result.Design.stage`).

    Returns
    -------
    casadi.Function or None
        The variant's ``predictor`` role (:func:`~stt_codegen.tube.variant_steps.law13_predictor`,
        :func:`~stt_codegen.tube.look_ahead.look_ahead_predictor`,
        :func:`~stt_codegen.tube.cascade.cascade_predictor`): inputs ``x`` (the plant's
        state), ``u_held`` (the command acting at the sample); output ``x_hat``.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> delay_predictor(design.spec, design.tube, design.stage) is None
    True
    """
    if not spec.compensate_delay:
        return None
    return variant_of(spec).entry("predictor")(tube, stage, spec.delay, mid_gain(spec))
