"""The differential drive's limits ``(v_max, omega_max)`` proved from law (13)'s peaks.

The look-ahead variant sends the base ``v = h . u`` and ``omega = (h_perp . u) / l`` for law
(13)'s ``u`` at the look-ahead point (``h`` the heading's unit vector, ``l`` the axle
offset; docs/differential-drive.md), so ``|v| <= |u|`` and ``|omega| <= |u| / l`` with
``|u| <= sqrt(peak_1^2 + peak_2^2)`` at every sample, whatever the heading, from the
per-input peaks the first-order prover proves for the point's plant class
(:func:`point_proof`: :func:`~.certificate.actuator.prove_input_bound` by the per-axis
argument). The input is held between samples, so the bound holds at every
``t``. :func:`look_ahead_input_proof` is that conversion; :func:`look_ahead_within_bound`
the design of a differential-drive spec with ``[actuator]``: the first order's procedure
(:func:`~.actuator.design_within_bound`: the default design, softer circumvents, via
points, slower tubes) with it as the proof. ``omega``'s bound is then lowered to the one
from the heading the base can have at each sample (:func:`heading_proof`,
:mod:`.heading`), where the command acts one whole period from its sample. A refusal
whose best tube keeps ``|v|`` within ``v_max`` and asks too much of ``omega`` also names
the smallest ``plant.axle_offset`` (two significant digits) at which the same procedure
is certified within the spec's ``prescribed_time`` (:func:`shortest_axle_offset`):
``omega`` falls with a longer look-ahead, while the obstacles grow by it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..errors import DesignError, SpecError, number_text
from ..spec.loader import Spec
from .actuator import design_within_bound, reverse_speed_needed, verdict_limit
from .certificate.actuator import prove_input_bound
from .failures import FailureKind, advice_wanted, without_advice
from .grid import grid_index, grid_value, smallest_passing
from .heading import CommandBounds, command_bounds, corner_boxes
from .input_bound import InputProof
from .result import Design
from ..tube.parameters import TubeDesign

__all__ = ["MAX_OFFSET_FACTOR", "NEVER_BACKS_UP", "base_proof", "heading_bounds", "heading_known",
           "heading_proof", "look_ahead_design_proof", "look_ahead_input_proof",
           "look_ahead_within_bound", "point_proof", "shortest_axle_offset"]

#: The ``plant.axle_offset`` search tries up to this many times the spec's offset.
MAX_OFFSET_FACTOR = 8.0

#: Why ``[actuator] reverse_speed = 0`` is never certified (docs/differential-drive.md,
#: "Backing up").
NEVER_BACKS_UP = ("where the tube holds the look-ahead point still, law (13)'s command may "
                  "point every way within its proved box, so the base may be asked to back "
                  "up")


def look_ahead_input_proof(proof: InputProof, axle_offset: float) -> InputProof:
    """The base's peaks ``(|v|, |omega|)`` from law (13)'s proved bounds at the point.

    ``|v| = |h . u| <= |u|`` and ``|omega| = |h_perp . u| / l <= |u| / l`` whatever the
    heading, with ``|u|`` bounded sample by sample (:attr:`InputProof.speed`: the norm of
    the per-input bounds at each sample, the largest over the samples), or by
    ``hypot(peak_1, peak_2)`` for a proof that carries its peaks only.

    Parameters
    ----------
    proof : InputProof
        Of law (13) for the look-ahead point (two inputs, m/s).
    axle_offset : float
        ``l``, m.

    Returns
    -------
    InputProof
        ``peak = (|u|, |u| / l)`` (m/s, rad/s), at the sample where the bound of ``|u|``
        is largest; ``proof`` itself when not proved.

    Examples
    --------
    >>> from stt_codegen.design.input_bound import InputProof
    >>> point = InputProof(True, (0.6, 0.8), (1.0, 2.0), 11.0, speed=0.9, speed_time=1.5)
    >>> look_ahead_input_proof(point, 0.5).peak
    (0.9, 1.8)
    """
    if not proof.proved:
        return proof
    if math.isfinite(proof.speed):
        speed, when = proof.speed, proof.speed_time
    else:
        speed = math.hypot(*proof.peak)
        when = proof.time[max(range(len(proof.peak)), key=lambda i: proof.peak[i])]
    return replace(proof, peak=(speed, speed / axle_offset), time=(when, when))


def point_proof(tube: TubeDesign, spec: Spec,
                limit: Callable[[list[float]], bool] | None = None,
                initial_error: tuple[tuple[float, float], ...] | None = None) -> InputProof:
    """Law (13)'s proved peak of ``|u|`` at the base's look-ahead point along ``tube``: the
    per-axis argument's (the Lyapunov balls only where it fails the sampled check itself).

    With ``g`` turned by the held command the balls measured no tighter than the per-axis
    boxes on every base tried, bit for bit, at about a quarter of the cost
    (docs/sampled-data.md, "A base's proof is the per-axis argument's"), so a base's
    design, its refusals and its output bound read this proof; ``verify`` proves the peaks
    again with the balls everywhere (no larger).

    Parameters
    ----------
    tube : TubeDesign
    spec : Spec
        A differential-drive spec (its plant class).
    limit : callable, optional
        :func:`~.certificate.actuator.prove_input_bound`'s ``limit`` (a verdict only).
    initial_error : tuple of (float, float), optional
        Its ``initial_error``: from this box of ``e(0)``.

    Returns
    -------
    InputProof
        Of ``u`` at the point (map it with :func:`look_ahead_input_proof`).
    """
    return prove_input_bound(tube, spec, per_axis_first=True, limit=limit,
                             initial_error=initial_error)


def look_ahead_design_proof(design: Design, spec: Spec,
                            initial_error: tuple[tuple[float, float], ...] | None = None
                            ) -> InputProof:
    """The base's proved peaks ``(|v|, |omega|)`` along ``design`` for ``spec``'s plants
    (the look-ahead variant's role ``input_proof``).

    Parameters
    ----------
    design : Design
    spec : Spec
        A differential-drive spec (its ``axle_offset``).
    initial_error : tuple of (float, float), optional
        From this box of ``e(0)`` at the point (:func:`point_proof`).

    Returns
    -------
    InputProof
        :func:`look_ahead_input_proof` of :func:`point_proof`, with ``omega``'s peak from
        :func:`heading_proof` where :func:`heading_known` and no ``initial_error``; within
        :func:`~.failures.without_advice` (a search asking the verdict only), stopped at
        the first sample where ``|u|`` passes ``v_max`` (``min(v_max, omega_max l)``
        where the heading is not enclosed; partial: it meets no bound), and
        :func:`heading_proof` asked only where the worst heading does not meet the bound.
    """
    offset = spec.drive.axle_offset
    bound = spec.input_bound
    aware = initial_error is None and heading_known(spec)
    # |v| <= |u| always; |omega| <= |u| / l at the worst heading, lower from the heading
    # the base can have (heading_proof): a verdict stops where |u| passes v_max, or
    # min(v_max, omega_max l) where the heading is not enclosed
    speed = (math.inf if bound is None else bound[0] if aware
             else min(bound[0], bound[1] * offset))
    point = point_proof(design.tube, spec, verdict_limit(
        spec, lambda u: math.hypot(*u) > speed), initial_error)
    proof = look_ahead_input_proof(point, offset)
    if not aware:
        return _worst_backing_up(proof, spec)         # at the worst heading
    if spec.reverse_speed is None and not advice_wanted() and (
            bound is None or proof.meets(bound)):
        return proof            # a verdict the worst heading already gives
    return base_proof(point, design.tube, spec)


def base_proof(point: InputProof, tube: TubeDesign, spec: Spec) -> InputProof:
    """The base's proved peaks ``(|v|, |omega|)`` from law (13)'s proof at the point along
    ``tube``: :func:`look_ahead_input_proof`, then :func:`heading_proof` where the heading
    is enclosed (:func:`heading_known`).

    Parameters
    ----------
    point : InputProof
        Of ``u`` at the look-ahead point (:func:`point_proof`, or ``verify``'s).
    tube : TubeDesign
    spec : Spec
        A differential-drive spec.

    Returns
    -------
    InputProof
        With :attr:`~.input_bound.InputProof.backward` (the bound of ``|u|`` where the
        heading is not enclosed) judged against ``[actuator] reverse_speed``.
    """
    proof = _worst_backing_up(look_ahead_input_proof(point, spec.drive.axle_offset), spec)
    return heading_proof(proof, tube, spec) if heading_known(spec) else proof


def _worst_backing_up(proof: InputProof, spec: Spec) -> InputProof:
    """``proof`` with the worst heading's backing up, ``|v| <= |u|``, judged against
    ``[actuator] reverse_speed``."""
    return replace(proof, backward=proof.peak[0], backward_time=proof.time[0],
                   reverse_limit=(math.inf if spec.reverse_speed is None
                                  else spec.reverse_speed))


def heading_known(spec: Spec) -> bool:
    """Whether the base's heading is enclosed sample by sample (:mod:`.heading`): each
    command acts for exactly one period (no ``[controller] delay``, ``jitter`` or
    ``compensate_delay``)."""
    return spec.delay == 0.0 and spec.jitter == 0.0 and not spec.compensate_delay


def heading_bounds(tube: TubeDesign, spec: Spec) -> tuple[np.ndarray, CommandBounds] | None:
    """The sample by sample bound of the base's ``|omega|`` and the enclosure of its heading
    along ``tube`` (:mod:`.heading`), from the per-axis sampled check's signed box of
    ``e`` (:func:`~.certificate.sampled.sampled_check_of`), the width's enclosure and the
    wheel model within the declared class: the symmetric part's eigenvalues ``1 + m -+ |d|
    s`` lie in ``input_gain``, so ``1 + m`` does and ``|d| <= (g_max - g_min) / (2 s)``;
    ``s_omega`` is ``input_gain_turn``'s constant.

    Parameters
    ----------
    tube : TubeDesign
        The look-ahead point's tube.
    spec : Spec
        A differential-drive spec with :func:`heading_known`.

    Returns
    -------
    (t, CommandBounds) or None
        The samples' times, shape (K,), and the bounds; ``None`` where the check fails or
        gives no signed box.
    """
    from ..tube import reference
    from .certificate.actuator import width_bounds
    from .certificate.plant_class import plant_class
    from .certificate.sampled import sampled_check_of

    samples, check = sampled_check_of(tube, spec, True)
    if not check.passed or check.e_box is None:
        return None
    with reference.numpy_math():
        narrow, wide = width_bounds(tube, samples)
    box = corner_boxes(check.e_box[:samples.t.size], narrow, wide, tube.gain)
    drive, a = spec.drive, plant_class(spec).assumptions
    beta = drive.track_width / (2.0 * drive.axle_offset)
    s = 0.5 * (beta + 1.0 / beta)
    g_min, g_max = a.input_gain
    slip = a.input_gain_turn[1] if a.input_gain_turn is not None else 0.0
    return samples.t, command_bounds(box, drive.heading, 1.0 / tube.rate_hz,
                                     drive.axle_offset, drive.track_width, (g_min, g_max),
                                     (g_max - g_min) / (2.0 * s), slip)


def heading_proof(proof: InputProof, tube: TubeDesign, spec: Spec) -> InputProof:
    """``proof`` (the base's peaks at the worst heading, :func:`look_ahead_input_proof`)
    with ``omega``'s peak lowered to the largest of :func:`heading_bounds`
    (docs/differential-drive.md, "The heading the base can have").

    Parameters
    ----------
    proof : InputProof
        Whole (not stopped early) and proved, else returned as it is.
    tube : TubeDesign
        The look-ahead point's tube.
    spec : Spec
        A differential-drive spec with :func:`heading_known`.

    Returns
    -------
    InputProof
        ``peak = (|v|, |omega|)``: ``|v|``'s is ``proof``'s (the bound of ``|u|``), and
        ``|omega|``'s at most ``proof``'s, at the sample where it is largest; ``backward``
        at most ``proof``'s, from the heading likewise.
    """
    if not (proof.proved and proof.complete):
        return proof
    found = heading_bounds(tube, spec)
    if found is None:
        return proof
    t, bounds = found
    peak, back = float(bounds.turn.max()), float(bounds.backward.max())
    if back < proof.backward:
        proof = replace(proof, backward=back,
                        backward_time=float(t[int(np.argmax(bounds.backward))]))
    if peak >= proof.peak[1]:
        return proof
    return replace(proof, peak=(proof.peak[0], peak),
                   time=(proof.time[0], float(t[int(np.argmax(bounds.turn))])))


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
        As :func:`~.actuator.design_within_bound` (kind ``INPUT_BOUND``); when ``omega``
        is what the best tube exceeds, the message also names the ``plant.axle_offset``
        that :func:`shortest_axle_offset` finds certified (``advice["plant.axle_offset"]``).
    """
    if spec.reverse_speed == 0.0:
        raise _never_backing_up(spec, design_free)
    try:
        design = design_within_bound(spec, design_free)
    except DesignError as error:
        raise _naming_axle_offset(spec, design_free, error) from None
    return replace(design, tube=replace(design.tube, input_bound=None))


def _never_backing_up(spec: Spec, design_free: Callable[[Spec], Design]) -> DesignError:
    """The refusal of ``[actuator] reverse_speed = 0``, which no tube meets
    (:data:`NEVER_BACKS_UP`), with what the design allowed to back up gives: the
    ``reverse_speed`` it needs where it is certified, else its refusal (whose advice holds
    for it, not for this spec: none is given)."""
    allowed = replace(spec, reverse_speed=None)
    head = f"actuator.reverse_speed = 0 is not certified: {NEVER_BACKS_UP}"
    try:
        design = look_ahead_within_bound(allowed, design_free)
    except DesignError as error:
        return DesignError(f"{head}; allowed to back up (reverse_speed omitted), {error}",
                           kind=FailureKind.INPUT_BOUND, tried=error.tried)
    proof = design.input_proof
    needs = reverse_speed_needed(proof, spec.input_bound[0])
    return DesignError(f"{head}; its tube backs the base up at {proof.backward:.3g} m/s at "
                       f"t = {proof.backward_time:.3f} s: actuator.reverse_speed = "
                       f"{number_text(needs)} m/s is certified", kind=FailureKind.INPUT_BOUND,
                       tried=design.tube, advice={"actuator.reverse_speed": needs})


def _naming_axle_offset(spec: Spec, design_free: Callable[[Spec], Design],
                        error: DesignError) -> DesignError:
    """``error`` with the certified ``plant.axle_offset`` named when ``omega`` is what its
    best tube exceeds and ``|v|`` fits (a longer offset lowers the first only)."""
    if (error.kind is not FailureKind.INPUT_BOUND or error.tried is None
            or not advice_wanted()):
        return error
    proof = base_proof(point_proof(error.tried, spec), error.tried, spec)
    v_max, omega_max = spec.input_bound
    if not proof.proved or proof.peak[0] > v_max or proof.peak[1] <= omega_max:
        return error
    offset = shortest_axle_offset(spec, design_free, proof.peak[1] / omega_max)
    if offset is None:
        return error
    return DesignError(f"{error}; plant.axle_offset = {number_text(offset)} m is certified "
                       "with this prescribed_time (omega falls with a longer look-ahead; "
                       "the obstacles grow by it)", kind=error.kind, tried=error.tried,
                       advice={**error.advice, "plant.axle_offset": offset})


def shortest_axle_offset(spec: Spec, design_free: Callable[[Spec], Design],
                         ratio: float) -> float | None:
    """The smallest ``plant.axle_offset`` (two significant digits) above the spec's at
    which :func:`~.actuator.design_within_bound` certifies ``spec`` (its other fields
    unchanged), or ``None``.

    The proved ``|omega| <= |u| / l`` falls about as ``1 / l`` (``|u|`` changes only
    through the obstacles, which grow by ``l``), so the first try is the spec's offset
    times ``ratio``, then each try 1.25 times the last, up to :data:`MAX_OFFSET_FACTOR`
    times the spec's offset or until the robot no longer fits (:meth:`Spec.with_axle_offset`
    refuses); once one passes, a bisection on the two-digit values between the last
    failing and the passing one finds the smallest (the answer is a value where the
    design passed).

    Parameters
    ----------
    spec : Spec
        A differential-drive spec with ``input_bound``, refused at its offset.
    design_free : callable
        ``Spec -> Design`` without an input bound.
    ratio : float
        The best tube's proved ``|omega|`` over ``omega_max`` at the spec's offset (> 1).

    Returns
    -------
    float or None
        Metres; ``None`` when no offset up to the cap is certified.
    """
    given = spec.drive.axle_offset

    def passes(index: int) -> bool:
        try:
            trial = spec.with_axle_offset(grid_value(index))
        except SpecError:
            return False
        try:
            with without_advice():
                design_within_bound(trial, design_free)
        except (DesignError, SpecError):
            return False
        return True

    low = grid_index(given)
    if grid_value(low) > given:
        low -= 1
    guess = max(grid_index(given * max(ratio, 1.0)), low + 1)
    while grid_value(guess) <= MAX_OFFSET_FACTOR * given:
        try:
            spec.with_axle_offset(grid_value(guess))
        except SpecError:
            return None                    # the robot no longer fits: longer ones neither
        if passes(guess):
            return grid_value(smallest_passing(passes, low, guess))
        low, guess = guess, max(grid_index(1.25 * grid_value(guess)), guess + 1)
    return None
