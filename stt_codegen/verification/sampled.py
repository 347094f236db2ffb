"""The checks of ``stt-codegen verify`` for the sampled closed loop of the first order.

The certificates are the design's (:mod:`stt_codegen.design.certificate.sampled`, the
sampled-data check; :mod:`stt_codegen.design.certificate.actuator`, the proved peak input);
this module words them as checks: ``sampled.gain``, ``sampled.tube_kept`` (with a member of
the class that leaves the tube when the check fails, :mod:`.class_search`),
``sampled.input_bound`` and ``sampled.plant_within_assumptions``.
"""

from __future__ import annotations

import math

from ..design.certificate import Certificate
from ..design.certificate.plant_class import plant_class
from ..design.certificate.sampled import (DELAY_HALVINGS, RATE_FACTORS, SampledCheck,
                                          check_sampled_first_per_axis, largest_delay,
                                          lowest_rate, sampled_check_of)
from ..design.gain import gain_derivation
from ..design.input_bound import InputProof
from ..rounding import distinct
from ..spec.assumptions import G_KEYS, Assumptions, combine_assumptions
from ..spec.loader import Spec
from ..spec.model_bounds import model_bounds
from ..spec.plants import PLANTS
from ..tube.parameters import TubeDesign
from ..proofs.check import Check

__all__ = ["delay_check", "delay_result", "input_bound_check", "plant_bounds_checks",
           "sampled_checks"]


def _bounds_words(a: Assumptions, refined: tuple[str, ...] = ()) -> str:
    g_min, g_max = a.input_gain
    if a.model and a.model in PLANTS and PLANTS[a.model].declared_bounds:
        source = (f"declared: {', '.join(a.declared)}; the rest their defaults (the {a.model} "
                  "plant has no equations here)")
    elif a.model and not a.declared:
        source = f"the {a.model} model's own bounds over the state space"
    elif a.model:
        source = (f"declared: {', '.join(a.declared)}; the rest from the {a.model} model "
                  "over the state space")
    else:
        source = "given"
    if refined:
        source += f"; {', '.join(refined)} evaluated on the tube per sampling interval"
    words = (f"eig((g + g^T)/2) in [{g_min:.6g}, {g_max:.6g}], |skew part| <= "
             f"{a.input_gain_skew:.6g}, row coupling <= {a.input_gain_coupling:.6g}, |f| <= "
             f"{a.drift_bound:.6g}, |w| <= {a.disturbance_bound:.3g}")
    if len(a.blocks) > 1:
        words += f", g block diagonal on {[list(b) for b in a.blocks]}"
    if a.input_gain_turn is not None:
        words += (f", g turned while a command is held by the heading's change, |omega| <= "
                  f"{a.input_gain_turn[0]:.4g} |u| + {a.input_gain_turn[1]:.4g} rad/s")
    return f"{words} ({source})"


def sampled_checks(spec: Spec, design: TubeDesign, certificate: Certificate) -> list[Check]:
    """The checks of ``stt-codegen verify`` for the sampled closed loop.

    ``sampled.gain``: ``k`` is below the linearized stability limit at the narrowest tube
    for ``g_max``, with the derivation (:func:`~stt_codegen.design.gain.gain_derivation`)
    in words. ``sampled.tube_kept``: :func:`check_sampled` for the spec's plant class
    (:func:`~stt_codegen.design.certificate.plant_class.plant_class`), with the lowest rate that
    passes (:func:`lowest_rate`), whether or not the spec's rate does.

    Parameters
    ----------
    spec : Spec
        The spec the design is for.
    design : TubeDesign
        With its gain set (the spec's ``controller.gain`` or the derived one); its tube is
        sampled by :func:`sampled_check_of` (once per process).
    certificate : Certificate
        ``design``'s tube certificate (its ``non-empty`` margin is the width the gain is
        derived from).

    Returns
    -------
    list of Check
        ``sampled.gain`` (the gain below its stability limit) and ``sampled.tube_kept``.
    """
    a = spec.assumptions
    plants = plant_class(spec)
    # the width the design derived its gain from: the certified one, rounded down
    derivation = gain_derivation(design, certificate.min_width,
                                 certificate.margin("non-empty").time, a, spec.gain)
    gain_ok = derivation["gain"] < derivation["stable_gain_limit"]
    checks = [Check("sampled.gain", gain_ok, derivation["explanation"]
                    + ("" if gain_ok else f"; k = "
                       f"{distinct(derivation['gain'], derivation['stable_gain_limit'], 6)} is "
                       f"at or beyond the limit at g_max = {a.input_gain[1]:g}"), derivation)]
    result = sampled_check_of(design, spec)[1]
    words = _bounds_words(a, tuple(result.data.get("refined_on_the_tube", ())))
    rate, gain = lowest_rate(design, spec, plants, spec.gain, passes_at_rate=result.passed)
    g_max = a.input_gain[1]
    if rate is not None:
        lowest = f"lowest passing rate {rate / 1000:.3g} kHz (k = {gain:.4g})"
    else:
        lowest = (f"no rate up to {design.rate_hz * RATE_FACTORS[-1] / 1000:g} kHz passes "
                  f"the condition at g_max = {g_max:g}")
        if a.input_gain_coupling > 0 and "input_gain_coupling" not in a.declared:
            lowest += (f" (row coupling {a.input_gain_coupling:g} next to g_min = "
                       f"{a.input_gain[0]:g}: declare a smaller input_gain_coupling if the "
                       "structure of g allows)")
    predicted = (f" (law (13) at the state predicted over controller.delay = {spec.delay:g} s "
                 "from the held command, each command acting exactly that long after its "
                 "read)" if spec.compensate_delay else "")
    if result.passed:
        detail = (f"every plant with {words} stays strictly inside the tube at and between "
                  f"samples at {design.rate_hz:g} Hz{predicted} with k = {design.gain:.6g}: "
                  f"|e| <= "
                  f"{result.level:.4g} at the samples, room >= {result.margin:.3g} of the "
                  f"half-width (least at t = {result.time:.4f} s, dimension "
                  f"{result.dimension}); {lowest}")
    else:
        need = (f"the condition needs {rate / 1000:.3g} kHz (k = {gain:.4g}) at g_max = "
                f"{g_max:g}" if rate is not None else lowest)
        label = "controller.gain" if spec.gain is not None else "the derived gain"
        detail = (f"{result.reason}, for plants with {words} at {design.rate_hz:g} Hz"
                  f"{predicted} and k = {design.gain:.6g} ({label}); {need}")
        # the adversary replays the plain law: not the predicted one
        found = None if spec.compensate_delay else _member_that_leaves(design, spec, result)
        if found is not None:
            how = ("g moving between samples by at most its Lipschitz bound times the "
                   "state's move, towards extreme members of the class" if found.gain_rates
                   else "g on each interval an extreme member of the class")
            how += ("; f likewise within its Lipschitz bound and |f| at its bound, |w| at "
                    "its bound" if found.drift_rates else ", |f + w| at its bound")
            detail += (f"; and the failure is not the check's caution: a plant of the class "
                       f"leaves the tube ({how}): |e_{found.dimension}| = {found.depth:.3g} "
                       f"at t = {found.time:.4f} s ({found.strategy}; verification/class_search.py)")
        elif a.input_gain_lipschitz is not None or a.drift_lipschitz is not None:
            detail += ("; the check's argument holds for every plant within the bounds, "
                       "also one whose g and f jump between samples: it does not use "
                       "input_gain_lipschitz or drift_lipschitz, so for the plants they "
                       "declare this failure may be the check's caution (docs/"
                       "sampled-data.md, \"Lipschitz bounds and the check\")")
        if _model_passes(design, spec):
            keys = ", ".join(k for k in G_KEYS if k in a.declared)
            detail += (f"; the {a.model} model's own g, its bounds evaluated on the tube per "
                       f"sampling interval, passes at {design.rate_hz:g} Hz: if the plant is "
                       f"that model, drop the declared {keys}")
    if a.notes:
        detail += "; " + "; ".join(a.notes) + " (the declared bounds are used; they cover the model)"
    data = {**result.data, "level": result.level, "margin": result.margin,
            "time": result.time, "lowest_rate_hz": rate, "lowest_rate_gain": gain}
    if not result.passed:
        data["class_counterexample"] = None if found is None else found.to_json()
    checks.append(Check("sampled.tube_kept", result.passed, detail, data))
    return checks


def delay_check(spec: Spec, design: TubeDesign) -> Check | None:
    """``sampled.delay``: the largest computation delay the sampled-data check proves at the
    design's rate and gain (:func:`~stt_codegen.design.certificate.sampled.largest_delay`),
    at least the spec's ``[controller] delay``.

    Parameters
    ----------
    spec : Spec
        Its plant class, ``delay`` and ``jitter``.
    design : TubeDesign
        With its gain.

    Returns
    -------
    Check or None
        Data: ``largest_delay_s``, ``period_s``, ``delay_s``, ``jitter_s``. Fails when the
        largest proved delay is below the spec's. ``None`` when the check fails without
        delay (``sampled.tube_kept`` fails then, and says why).
    """
    if spec.compensate_delay:
        # the prediction is over exactly controller.delay: that check (sampled.tube_kept's)
        # decides; the largest delay a prediction would be proved over is reported beside it
        return delay_result("sampled.delay", largest_delay(design, spec), spec,
                            design.rate_hz, "stays in the tube when each command, computed "
                            "at the state predicted over a delay up to that long, acts that "
                            "long after its state is read",
                            f"k = {design.gain:.6g}", DELAY_HALVINGS,
                            sampled_check_of(design, spec)[1].passed)
    return delay_result("sampled.delay", largest_delay(design, spec), spec, design.rate_hz,
                        "stays in the tube when each command acts up to that long after its "
                        "state is read",
                        f"k = {design.gain:.6g}", DELAY_HALVINGS)


def delay_result(name: str, largest: float | None, spec: Spec, rate_hz: float, kept: str,
                 gains: str, halvings: int, proved: bool | None = None) -> Check | None:
    """The check ``name`` of a largest proved delay, in words (``sampled.delay``,
    ``cascade.delay``).

    Parameters
    ----------
    name : str
        The check's name.
    largest : float or None
        The largest delay proved, s; ``None``: the certificate fails without delay.
    spec : Spec
        Its ``delay`` and ``jitter``.
    rate_hz : float
        The design's rate, Hz.
    kept : str
        What every plant of the class does under the delay, in words.
    gains : str
        The gains judged, in words.
    halvings : int
        The bisection's halvings (its resolution, ``1 / 2^halvings`` of the period).
    proved : bool, optional
        The verdict of the check at the spec's own delay, when it is not implied by
        ``largest`` (``[controller] compensate_delay``: a prediction over one delay proves
        that delay, not every shorter one).

    Returns
    -------
    Check or None
        Passed when ``largest >= spec.delay`` (or ``proved``, given). Data: ``largest_delay_s``, ``period_s``,
        ``delay_s``, ``jitter_s``. ``None`` when ``largest`` is: the certificate's own
        check fails, and reports it.
    """
    if largest is None:
        return None
    period = 1.0 / rate_hz
    data = {"largest_delay_s": largest, "period_s": period, "delay_s": spec.delay,
            "jitter_s": spec.jitter}
    timing = f" with jitter {spec.jitter:g} s" if spec.jitter > 0.0 else ""
    passed = largest >= spec.delay if proved is None else proved
    detail = (f"a computation delay up to {largest * 1000:.4g} ms ({largest / period:.1%} of "
              f"the period {period * 1000:g} ms) is tolerated: every plant of the class "
              f"{kept}{timing}, at {rate_hz:g} Hz "
              f"with {gains} (the largest the certificate proves, to 1/{2 ** halvings} of the "
              f"period; controller.delay = {spec.delay:g} s"
              + (")" if passed else ", beyond it)"))
    return Check(name, passed, detail, data)


def _model_passes(design: TubeDesign, spec: Spec) -> bool:
    """Whether the check passes for the spec's plant model with its own bounds of ``g``
    (evaluated on the tube per interval) where the spec declares wider ones; ``False``
    when the spec declares none or its model has no ``g`` that varies on the tube."""
    a = spec.assumptions
    if a.g_from_model or a.model not in PLANTS or not PLANTS[a.model].gain_varies:
        return False
    kept = {key: getattr(a, key) for key in a.declared
            if key not in G_KEYS and key != "input_gain_lipschitz"}
    own = combine_assumptions(model_bounds(a.model, spec.state_space.lower,
                                           spec.state_space.upper, spec.plant_data(a.model)),
                              kept, spec.dimension, spec.disturbance_amplitude)
    samples = sampled_check_of(design, spec)[0]
    return check_sampled_first_per_axis(design, samples, plant_class(spec, own)).passed


def _member_that_leaves(design: TubeDesign, spec: Spec, result: SampledCheck):
    """A member of the spec's plant class that leaves the tube under the sampled law
    (:func:`~stt_codegen.verification.class_search.search_class`, greedy strategies only),
    confirmed on the numpy reference of the deployed controller (a member that respects
    the class's Lipschitz bounds when the spec has them); ``None`` when the check
    passed, when the class's bounds are evaluated on the tube per interval (the search's
    members obey the bounds over the whole state space, which may be wider), or when none
    is found."""
    if result.passed or result.data.get("refined_on_the_tube") or \
            spec.assumptions.input_gain[0] <= 0:
        return None
    from .class_search import replay, search_class
    samples = sampled_check_of(design, spec)[0]
    found = search_class(design, samples, spec.assumptions, held_runs=0)
    return found if found is not None and replay(design, found, "reference") else None


def plant_bounds_checks(spec: Spec, model: str | None = None) -> list[Check]:
    """Whether the plant model meets the assumptions ``verify`` judges it against.

    ``sampled.plant_within_assumptions``: the model's bounds over the state space
    (:func:`~stt_codegen.spec.model_bounds.model_bounds`: eigenvalues of the symmetric part
    of ``g``, norm of its skew part, row coupling, ``max |f|``) lie within
    ``spec.assumptions``. The loader makes this hold for every spec it builds (a bound the
    model violates is a ``SpecError``); a spec changed in Python
    (``dataclasses.replace``) can break it, and then the sampled verdict is not about the
    model, which this check says (:func:`~.plant_within.plant_within_assumptions`, the
    one membership check of both orders). Assumption 2 itself is the model's own check
    (:func:`~stt_codegen.proofs.assumption.assumption2_check`).

    Parameters
    ----------
    spec : Spec
        The spec: its state space, linear matrices and ``[assumptions]``.
    model : str, optional
        Plant model, default the spec's.

    Returns
    -------
    list of Check
        ``sampled.plant_within_assumptions``.
    """
    from .plant_within import plant_within_assumptions
    return [plant_within_assumptions(spec, model)]


def input_bound_check(spec: Spec, proof: InputProof) -> Check:
    """``sampled.input_bound``: every input's proved peak within ``spec.input_bound``.

    Parameters
    ----------
    spec : Spec
        With ``input_bound``.
    proof : InputProof
        :func:`prove_input_bound` of the design.

    Returns
    -------
    Check
        Data: ``input_bound``, ``peak``, ``time`` (per input), ``margin`` (the smallest
        ``(bound - peak) / bound``), ``horizon``.
    """
    bound = spec.input_bound
    names = spec.input_names
    data = {"input_bound": list(bound), "peak": list(proof.peak), "time": list(proof.time),
            "margin": proof.margin(bound), "horizon": proof.horizon, "inputs": list(names)}
    if not proof.proved:
        return Check("sampled.input_bound", False,
                     f"no bound on law (13)'s input is proved: {proof.reason}", data)
    each = ", ".join(f"|{name}| <= {distinct(p, b, 4)} (bound {b:g}, at t = {t:.3f} s)"
                     for name, p, b, t in zip(names, proof.peak, bound, proof.time))
    if math.isfinite(proof.reverse_limit):
        each += (f", backing up at most {distinct(proof.backward, proof.reverse_limit, 4)} "
                 f"m/s (reverse_speed {proof.reverse_limit:g}, at t = "
                 f"{proof.backward_time:.3f} s)")
        data.update(backward=proof.backward, backward_time=proof.backward_time,
                    reverse_speed=proof.reverse_limit)
    ok = proof.meets(bound)
    detail = (f"law (13) asks at most {each} at every sample on [0, {proof.horizon:.4g}] s, "
              f"for every plant of [assumptions] (from the sampled check's bound on |e| at "
              f"each sample and the certified width there): margin {proof.margin(bound):.3g} "
              "of the bound")
    if not ok:
        over = [name for name, p, b in zip(names, proof.peak, bound) if p > b]
        if not proof.backs_up_within:
            over.append("backing up (actuator.reverse_speed)")
        detail += f"; beyond the bound in {', '.join(over)}"
    return Check("sampled.input_bound", ok, detail, data)
