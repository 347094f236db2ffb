"""A design for a spec with ``[controller] delay`` or ``jitter``: the sampled-data proof must
hold with them, else a refusal that names the delay or the rate that works.

The tube's candidates do not depend on the timing; the sampled proofs the search runs on
them (the tracking screen, the ``[actuator]`` proof) read it through
:func:`~.certificate.sampled.sampled_check_of`. A design whose own proof fails with the
timing is refused (``verify`` would fail it); the refusal names the largest delay the
design without the timing tolerates with ``|e| <= TRACKING_ERROR`` and the lowest rate
that passes with the delay, each only once :func:`~.search.design_tube` has certified it
(docs/sampled-data.md, "Computation delay and jitter").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from ..errors import DesignError, number_text
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube import reference
from .certificate.plant_class import plant_class
from .certificate.sampled import (check_sampled_first_per_axis, delay_room, largest_passing,
                                  lowest_rate, sampled_check_of)
from .failures import FailureKind, advice_text, advice_wanted
from .result import Design
from .samples import sample_tube
from .tracking import TRACKING_ERROR

__all__ = ["design_with_timing"]


def _timing_words(spec: Spec) -> str:
    words = f"controller.delay = {number_text(spec.delay)} s"
    if spec.jitter > 0.0:
        words += f", controller.jitter = {number_text(spec.jitter)} s"
    return words


def _certified(spec: Spec, search: Callable[[Spec], Design]) -> Design:
    """``search(spec)`` whose sampled-data proof holds with the spec's timing, else a
    :class:`DesignError` of kind ``TIMING`` (or the search's own)."""
    design = search(spec)
    check = sampled_check_of(design.tube, spec)[1]
    if not check.passed:
        raise DesignError(f"the sampled-data proof fails: {check.reason}",
                          kind=FailureKind.TIMING, tried=design.tube)
    return design


def _passes(spec: Spec, search: Callable[[Spec], Design]) -> bool:
    """Whether :func:`_certified` designs ``spec`` (a refusal's advice is named only then)."""
    try:
        _certified(spec, search)
    except DesignError:
        return False
    return True


def _followable_delay(design: Design, spec: Spec) -> float | None:
    """The largest delay (to ``dt / 2^DELAY_HALVINGS``) with which ``design``'s sampled
    proof holds at ``|e| <= TRACKING_ERROR`` with the spec's jitter; ``None`` if none."""
    tube = design.tube
    with reference.numpy_math():
        samples, plants = sample_tube(tube), plant_class(spec)

        def passes(delay: float) -> bool:
            check = check_sampled_first_per_axis(tube, samples, plants, delay=delay,
                                                 jitter=spec.jitter,
                                                 compensate=spec.compensate_delay)
            return check.passed and check.level <= TRACKING_ERROR

        return largest_passing(passes, delay_room(tube.rate_hz, spec))


def _can_compensate(spec: Spec) -> bool:
    """Whether ``[controller] compensate_delay`` could take the spec's timing."""
    return (variant_of(spec).predicts_delay and not spec.compensate_delay
            and spec.jitter == 0.0 and 0.0 < spec.delay * spec.rate_hz <= 1.0)


def _compensated_advice(spec: Spec, search: Callable[[Spec], Design],
                        refused: DesignError) -> DesignError:
    """``refused``, naming ``controller.compensate_delay = true`` and what the refusal of the
    compensated spec names (its advice, each field designed), when that spec is certified
    with them; else ``refused`` itself."""
    if not _can_compensate(spec):
        return refused
    compensated = replace(spec, compensate_delay=True)
    try:
        _certified(compensated, search)
        advice: dict = {}
    except DesignError as failure:
        advice = dict(failure.advice)
        if not advice:
            return refused
    words = " and ".join(advice_text(name, value) for name, value in advice.items())
    return DesignError(f"{refused}; controller.compensate_delay = true"
                       + (f" with {words}" if words else "") + " is certified",
                       kind=refused.kind, tried=getattr(refused, "tried", None),
                       advice={"controller.compensate_delay": True, **advice})


def design_with_timing(spec: Spec, search: Callable[[Spec], Design]) -> Design:
    """The design of a spec with ``[controller] delay`` or ``jitter`` whose sampled-data
    proof holds with them.

    Parameters
    ----------
    spec : Spec
        With ``delay > 0`` or ``jitter > 0``. A variant whose stage's certificate proves
        the timing (``timing_in_stage``, the cascade) is designed by ``search`` alone.
    search : callable
        ``search(spec) -> Design``: the design search of
        :func:`~stt_codegen.design.search.design_tube`, which reads no timing itself.

    Returns
    -------
    Design
        Its ``sampled_check_of`` passes with the spec's delay and jitter.

    Raises
    ------
    DesignError
        Kind ``TIMING`` when no design's proof holds with the timing; the message names
        ``controller.delay`` (the largest that works at this rate) and
        ``controller.rate_hz`` (the lowest that works with this delay) when
        :func:`~stt_codegen.design.search.design_tube` certifies them; the search's own
        error when the spec fails without the timing too.
    """
    if variant_of(spec).timing_in_stage:        # the stage's certificate reads the timing
        return search(spec)
    try:
        return _certified(spec, search)
    except DesignError as failure:
        if not advice_wanted():
            raise
        refused = failure
    untimed = replace(spec, delay=0.0, jitter=0.0)
    try:
        plain = search(untimed)
    except DesignError:
        # the design fails without the timing too: what the predicted law needs, if it can
        # take the delay, else the refusal as it is
        raise _compensated_advice(spec, search, refused) from None
    trials = []
    delay = _followable_delay(plain, spec)
    if delay is not None and 0.0 < delay < spec.delay:
        trials.append((replace(spec, delay=delay), f"controller.delay = "
                       f"{number_text(delay, 3)} s is certified at {number_text(spec.rate_hz)} Hz",
                       ("controller.delay", delay)))
    with reference.numpy_math():
        rate, _ = lowest_rate(plain.tube, spec, plant_class(spec), spec.gain)
    if rate is not None and rate != spec.rate_hz:
        trials.append((replace(spec, rate_hz=rate), f"controller.rate_hz = "
                       f"{number_text(rate)} is certified with {_timing_words(spec)}",
                       ("controller.rate_hz", rate)))
    if _can_compensate(spec):
        trials.insert(0, (replace(spec, compensate_delay=True),
                          f"controller.compensate_delay = true is certified with "
                          f"{_timing_words(spec)} at {number_text(spec.rate_hz)} Hz",
                          ("controller.compensate_delay", True)))
    kept = [(words, field) for trial, words, field in trials if _passes(trial, search)]
    works = [words for words, _ in kept]
    # a faster rate must hold delay + 2 jitter in its period
    faster = (spec.delay + 2.0 * spec.jitter) * spec.rate_hz < 1.0 - 1e-12
    rates = ("a rate up to 16 times it" if faster else
             "a faster rate (its period could not hold controller.delay + 2 jitter)")
    whole = ("; a delay near a whole period is beyond law (13)'s check at any rate "
             "(docs/sampled-data.md, 'How large a delay it can prove')"
             if spec.delay * spec.rate_hz >= 0.5 else "")
    advice = ("; " + "; ".join(works)) if works else (
        f"; neither a shorter delay at this rate nor {rates} is certified (the design "
        f"without the timing is){whole}")
    raise DesignError(f"no design is certified with {_timing_words(spec)} at "
                      f"{number_text(spec.rate_hz)} Hz ({refused}){advice}",
                      kind=FailureKind.TIMING,
                      tried=getattr(refused, "tried", None),
                      advice=dict(field for _, field in kept)) from None
