"""The differential drive's limits ``(v_max, omega_max)`` proved from law (13)'s peaks.

The look-ahead variant sends the base ``v = h . u`` and ``omega = (h_perp . u) / l`` for law
(13)'s ``u`` at the look-ahead point (``h`` the heading's unit vector, ``l`` the axle
offset; docs/differential-drive.md), so ``|v| <= |u|`` and ``|omega| <= |u| / l`` with
``|u| <= sqrt(peak_1^2 + peak_2^2)`` at every sample, whatever the heading, from the
per-input peaks the first-order prover (:func:`~.certificate.actuator.prove_input_bound`) proves for
the point's plant class. The input is held between samples, so the bound holds at every
``t``. :func:`look_ahead_input_proof` is that conversion; :func:`look_ahead_within_bound`
the design of a differential-drive spec with ``[actuator]``: the first order's procedure
(:func:`~.actuator.design_within_bound`: the default design, softer circumvents, via
points, slower tubes) with it as the proof.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from ..spec.loader import Spec
from .actuator import design_within_bound
from .certificate.actuator import prove_input_bound
from .input_bound import InputProof
from .result import Design

__all__ = ["look_ahead_design_proof", "look_ahead_input_proof", "look_ahead_within_bound"]


def look_ahead_input_proof(proof: InputProof, axle_offset: float) -> InputProof:
    """The base's peaks ``(|v|, |omega|)`` from law (13)'s per-input peaks at the point.

    Parameters
    ----------
    proof : InputProof
        Of law (13) for the look-ahead point (two inputs, m/s).
    axle_offset : float
        ``l``, m.

    Returns
    -------
    InputProof
        ``peak = (|u|, |u| / l)`` with ``|u| = hypot(peak_1, peak_2)`` (m/s, rad/s), at
        the time of the larger point peak; ``proof`` itself when not proved.
    """
    if not proof.proved:
        return proof
    speed = math.hypot(*proof.peak)
    when = proof.time[max(range(len(proof.peak)), key=lambda i: proof.peak[i])]
    return replace(proof, peak=(speed, speed / axle_offset), time=(when, when))


def look_ahead_design_proof(design: Design, spec: Spec) -> InputProof:
    """The base's proved peaks ``(|v|, |omega|)`` along ``design`` for ``spec``'s plants
    (the look-ahead variant's role ``input_proof``).

    Parameters
    ----------
    design : Design
    spec : Spec
        A differential-drive spec (its ``axle_offset``).

    Returns
    -------
    InputProof
        :func:`look_ahead_input_proof` of law (13)'s proof at the point.
    """
    return look_ahead_input_proof(prove_input_bound(design.tube, spec),
                                  spec.drive.axle_offset)


def look_ahead_within_bound(spec: Spec, design_free: Callable[[Spec], Design]) -> Design:
    """The certified design of a differential-drive spec whose ``(v, omega)`` stay within
    ``[actuator] input_bound``, or the first order's refusal naming the
    ``prescribed_time`` that works.

    Parameters
    ----------
    spec : Spec
        A differential-drive spec with ``input_bound`` ``(v_max, omega_max)``.
    design_free : callable
        ``Spec -> Design`` without an input bound.

    Returns
    -------
    Design
        Its ``input_proof`` the base's proved peaks; its tube without an ``input_bound``
        of its own (the generated code clamps ``(v, omega)``, :attr:`Design.look_ahead`).

    Raises
    ------
    DesignError
        As :func:`~.actuator.design_within_bound` (kind ``INPUT_BOUND``).
    """
    design = design_within_bound(spec, design_free)
    return replace(design, tube=replace(design.tube, input_bound=None))
