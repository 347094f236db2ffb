"""The checks of ``stt-codegen verify`` for the sampled cascade of a second-order plant.

``cascade.sampled`` (:func:`sampled_cascade_check`) reports the sampled cascade's
certificate (:mod:`stt_codegen.design.certificate.cascade_sampled`), and, with
``[actuator]``, ``cascade.input_bound`` (:func:`cascade_input_bound_check`) its certified
peak of each physical input against the bound; ``cascade.plant_within_assumptions``
(:func:`plant_within_class_check`) whether the spec's plant lies in the certified class;
``cascade.delay`` (:func:`cascade_delay_check`) the largest computation delay the
certificate proves. The cascade's SymPy proofs are :mod:`stt_codegen.proofs.cascade`.
"""

from __future__ import annotations

from ..proofs.check import Check

__all__ = ["CASCADE_DELAY_HALVINGS", "cascade_delay_check", "cascade_input_bound_check",
           "judged_stage", "plant_within_class_check", "sampled_cascade_check"]

#: Halvings of the bisection of ``cascade.delay`` (the first order's ``DELAY_HALVINGS``:
#: a resolution of ``h / 64``).
CASCADE_DELAY_HALVINGS = 6


def _timing_words(spec) -> str:
    """`` with a computation delay up to ... and jitter ...`` when the spec has them."""
    parts = ([f"a computation delay up to {spec.delay * 1000:.4g} ms"] if spec.delay > 0.0
             else []) + ([f"sampling jitter {spec.jitter * 1000:.4g} ms"] if spec.jitter > 0.0
                         else [])
    return (" with " + " and ".join(parts)) if parts else ""


def sampled_cascade_check(spec, tube, min_width: float) -> Check:
    """``cascade.sampled``: the sampled cascade's certificate
    (:func:`~stt_codegen.design.certificate.cascade_sampled.check_cascade_sampled`) for the deployed
    second stage and the spec's declared plants, with its margins and the lowest certified
    rate (:func:`~stt_codegen.design.cascade_gain.lowest_certified_rate`).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.
    tube : TubeDesign
        The position tube; the second stage is :func:`judged_stage`'s.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    Check
        PASS when the certificate holds at the spec's rate; FAIL with its figures otherwise.
    """
    from ..design.cascade_gain import fastest_searched_rate, lowest_certified_rate
    from ..design.certificate.cascade_sampled import cascade_check_of
    stage, derivation = judged_stage(spec, tube, min_width)
    result = cascade_check_of(tube, spec, stage)
    rate = lowest_certified_rate(tube, spec, passes_at_rate=result.passed)
    lowest = (f"lowest certified rate {rate:g} Hz (on the two-digit grid, a second stage "
              "derived there)" if rate is not None else
              f"no rate up to {fastest_searched_rate(tube.rate_hz, spec):g} Hz is certified")
    words = result.data["class"]
    timing = _timing_words(spec)
    if result.passed:
        detail = (f"proved: every plant with {words} keeps |e1| < 1 and |e2| < 1 at and "
                  f"between samples at {tube.rate_hz:g} Hz{timing} over [0, "
                  f"{result.data['horizon']:.4g}] s, with k1 = {stage.position_gain:.4g}, "
                  f"k2 = {stage.velocity_gain:.4g}, rho2 from {max(stage.width_start):.4g} "
                  f"to {min(stage.width_floor):.4g} (l = {stage.decay:.4g}): |e1| <= "
                  f"{result.max_abs_e1:.3g}, |e2| <= {result.max_abs_e2:.3g} at the "
                  f"samples; room >= {result.position_margin:.3g} of the position tube's "
                  f"half-width and {result.velocity_margin:.3g} of rho2 between samples "
                  f"(least at t = {result.time:.4f} s, dimension {result.dimension}); "
                  f"|u_i| <= {[round(v, 4) for v in result.peak_input]}, |x2_i| <= "
                  f"{[round(v, 4) for v in result.peak_velocity]}; {lowest}")
    else:
        detail = (f"not proved at {tube.rate_hz:g} Hz{timing} for plants with {words}: "
                  f"{result.reason}; {lowest}")
    data = {**result.data, "passed": result.passed, "reason": result.reason,
            "time": result.time, "dimension": result.dimension, "lowest_rate_hz": rate,
            "gains": derivation}
    return Check("cascade.sampled", result.passed, detail, data)


def cascade_delay_check(spec, tube, min_width: float,
                        halvings: int = CASCADE_DELAY_HALVINGS) -> Check | None:
    """``cascade.delay``: the largest computation delay the sampled cascade's certificate
    proves for the deployed second stage at the design's rate with the spec's jitter
    (:func:`~stt_codegen.design.certificate.cascade_sampled.largest_cascade_delay`), at
    least the spec's ``[controller] delay``; the cascade's ``sampled.delay``.

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``: its plants, ``delay`` and ``jitter``.
    tube : TubeDesign
        The position tube; the second stage is :func:`judged_stage`'s.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.
    halvings : int, optional
        Halvings of the bisection (a resolution of ``h / 2^halvings``).

    Returns
    -------
    Check or None
        Data: ``largest_delay_s``, ``period_s``, ``delay_s``, ``jitter_s``. Fails when the
        largest proved delay is below the spec's. ``None`` when the certificate fails
        without delay (``cascade.sampled`` fails then, and says why).
    """
    from ..design.certificate.cascade_sampled import cascade_check_of, largest_cascade_delay
    from .sampled import delay_result
    stage, _ = judged_stage(spec, tube, min_width)
    # with compensate_delay a prediction over one delay proves that delay, not every shorter
    proved = cascade_check_of(tube, spec, stage).passed if spec.compensate_delay else None
    return delay_result("cascade.delay", largest_cascade_delay(tube, spec, stage, halvings),
                        spec, tube.rate_hz, "keeps |e1| < 1 and |e2| < 1 when each force acts "
                        "up to that long after its state is read" + (
                            " (the law at the state predicted over the delay)"
                            if spec.compensate_delay else ""),
                        f"k1 = {stage.position_gain:.4g}, k2 = {stage.velocity_gain:.4g}",
                        halvings, proved)


def judged_stage(spec, tube, min_width: float) -> tuple:
    """The second stage ``verify`` judges: the one the design deploys
    (:func:`~stt_codegen.design.cascade_gain.certified_stage` within ``spec.input_bound``);
    when no certified shape keeps the bound, the first certified one (its peak input is
    then reported beyond the bound); when none is certified, the first shape's (to report
    its figures).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.
    tube : TubeDesign
        The position tube.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    stage : SecondStage
    derivation : dict
        As :func:`~stt_codegen.design.cascade_gain.derived_second_stage`.
    """
    from ..design.cascade_gain import certified_stage, derived_second_stage
    for bound in ((spec.input_bound, None) if spec.input_bound is not None else (None,)):
        certified, derivation = certified_stage(tube, spec, min_width, bound)
        if certified is not None:      # a shape is certified (None: none is)
            return certified, derivation
    order = spec.second_order
    return derived_second_stage(tube, min_width, order.input_gain,
                                order.drift_bound + spec.disturbance_amplitude,
                                order.initial_velocity)


def cascade_input_bound_check(spec, tube, min_width: float) -> Check:
    """``cascade.input_bound``: the sampled cascade's certified peak of every physical
    input ``|u_i|`` (force or torque) within ``[actuator] input_bound``.

    The certificate (:mod:`.cascade_sampled`) bounds ``|u_k,i| <= (2 k2 / rho2(t_k))
    phi(E2_k,i)`` at every sample for every plant of the class; the deployed input is held
    between samples, so the bound holds at every instant of ``[0, 1.1 t_c]``
    (docs/second-order.md, "Force limits").

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model`` and ``input_bound``.
    tube : TubeDesign
        The position tube; the second stage is :func:`judged_stage`'s.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    Check
        PASS when the certificate holds and every peak is within its bound. Data:
        ``input_bound``, ``peak``, ``time`` (per input), ``margin`` (the smallest
        ``(bound - peak) / bound``), ``inputs``, ``unit``, ``horizon``.
    """
    from ..rounding import distinct
    from ..design.certificate.cascade_sampled import cascade_check_of
    bound, names, unit = spec.input_bound, spec.input_names, spec.input_unit
    stage, _ = judged_stage(spec, tube, min_width)
    result = cascade_check_of(tube, spec, stage)
    margin = min((b - p) / b for p, b in zip(result.peak_input, bound))
    data = {"input_bound": list(bound), "peak": list(result.peak_input),
            "time": list(result.peak_input_time), "margin": margin if result.passed else
            -float("inf"), "inputs": list(names), "unit": unit,
            "horizon": result.data.get("horizon", 0.0)}
    if not result.passed:
        return Check("cascade.input_bound", False, "no bound on the cascade's input is "
                     f"proved: the sampled cascade is not certified ({result.reason})", data)
    each = ", ".join(f"|{name}| <= {distinct(p, b, 4)} {unit} (bound {b:g} {unit}, at t = "
                     f"{t:.3f} s)" for name, p, b, t in zip(names, result.peak_input, bound,
                                                            result.peak_input_time))
    ok = all(p <= b for p, b in zip(result.peak_input, bound))
    detail = (f"the cascade asks at most {each} at every sample on [0, "
              f"{data['horizon']:.4g}] s, held between samples, for every plant of the "
              f"certified class (k2 = {stage.velocity_gain:.4g}): margin {margin:.3g} of the "
              "bound")
    if not ok:
        over = [name for name, p, b in zip(names, result.peak_input, bound) if p > b]
        detail += (f"; beyond the bound in {', '.join(over)} (no certified second stage "
                   "keeps it on this tube: a longer prescribed_time may)")
    return Check("cascade.input_bound", ok, detail, data)


def plant_within_class_check(spec) -> Check:
    """``cascade.plant_within_assumptions``: the spec's simulated second-order plant lies in
    the class ``cascade.sampled`` certifies
    (:func:`~stt_codegen.design.certificate.cascade_sampled.model_within_class`).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.

    Returns
    -------
    Check
        PASS when the model with its parameters is in the class, with the figures.
    """
    from .plant_within import plant_within_assumptions
    return plant_within_assumptions(spec)
