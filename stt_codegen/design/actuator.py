"""Design within the actuators' limits (``[actuator] input_bound``).

:func:`design_within_bound` is what :func:`~stt_codegen.design.search.design_tube` does
for a spec with ``[actuator]``. It accepts a tube only when the prover
(:func:`~.certificate.actuator.prove_input_bound`: the sampled-data bound on ``e`` and the
certified widths, :mod:`.input_bound`) shows that law (13) never asks any input for more
than its bound; for a second-order spec the prover is the sampled cascade's certificate
(:func:`~.cascade_gain.cascade_input_proof`: the peak force or torque of the certified
second stage). Deterministic, in this order, the first tube that meets the bound wins:

1. the design of the spec without ``[actuator]`` (the default design: a spec whose
   default tube keeps the bound gets exactly that tube), except that ``auto`` does not
   prefer the smoother via tube by its speed estimate here (``design_tube``: the proved
   peak orders the tubes instead), then :func:`slower_variants`:
2. **softer circumvents**: when the default is the paper's method with circumvents and
   the spec leaves ``tube.circumvent_sharpness`` free, the paper's search with every
   circumvent's sharpness ``k^j`` fixed to each value of the ladder above the default's
   largest, smoother each time (a longer window: the bound rises more slowly), until the
   paper's search fails;
3. **via points** (``tube.method`` ``"auto"`` or ``"via"``): smooth-step segments through
   via boxes, timed in proportion to their length over all of ``t_c`` (no circumvent
   flanks);
4. **via points timed for the force** (a variant whose input is a force, the cascade:
   ``ControllerVariant.via_timing``; tasks too): smooth-step segments timed so that every
   move asks the same peak acceleration (durations that follow the square roots of their
   lengths, :data:`~.via.ACCELERATION_TIMING`), a move whose smooth step would pass
   ``state_space.velocity_bound`` slowed to it, as a cruise where that is cheaper
   (:func:`~.via.timed_moves`); a task's legs are timed and shaped so too, not as cruise
   legs; then the same with **S-curve segments** (the least peak acceleration of the
   profiles, :data:`~stt_codegen.tube.parameters.SCURVE`, and a move whose S-curve would
   pass the velocity bound a glide, :data:`~stt_codegen.tube.parameters.GLIDE`; neither of
   the two proves the smaller force on every spec); then both again with **blended corners**
   (:data:`~.via.BLEND_CORNERS`: each move starting before the previous one ends, so the
   tube passes its via boxes without stopping; not where an obstacle moves, though one
   that exists only for a while is allowed);
5. **via points with cruise segments** (the same; not for tasks, whose legs have them):
   the same via boxes and times, each segment's rate rising to 1.25 times its mean, not
   1.875 times; then, where the input is a velocity (law (13), a base), the same with
   **blended corners** (not where an obstacle moves): the tube
   stops at no via box, so it asks less speed of the same time, and a base's heading
   stays aligned with its command through the corners
   (:mod:`~stt_codegen.design.heading`); then, for a base, via points with cruise
   segments **timed for the turn** into each move (:data:`~.via.TURN_TIMING`), stopped,
   then blended.

When none does, the design is refused (``DesignError``, kind ``INPUT_BOUND``) naming the
smallest ``prescribed_time`` at which the same procedure meets the bound (a search on
two-significant-digit values: growing, then a bisection) and the bound the best design
within ``t_c`` needs. The accepted :class:`~.result.Design` carries the bound in its tube
(the generated code clamps ``u`` to it) and the proof (``Design.input_proof``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..errors import DesignError, SpecError, number_text
from ..progress import report, reporting
from ..spec.deadline import (ending_windows, fixed_in_time, later_advice, moved_words,
                             with_deadline)
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube.parameters import CRUISE, SCURVE, SMOOTHSTEP
from .grid import MAX_TIME_FACTOR, grid_index, grid_value, half_step_below, smallest_passing
from .deadline import SLOWER_HELPS
from .failures import FailureKind, advice_wanted, without_advice
from .certificate.actuator import prove_input_bound
from .input_bound import InputProof
from .result import METHOD_PAPER, METHOD_VIA, Design
from .via import ACCELERATION_TIMING, BLEND_CORNERS, STOP_CORNERS, TURN_TIMING
from .samples import HORIZON_FACTOR, STEP_BUDGET
from .windows import SHARPNESS_LADDER

__all__ = ["design_within_bound", "law13_input_proof", "reverse_speed_needed", "verdict_limit"]

#: A longer ``t_c`` must lower the best peak-to-bound ratio by at least this factor, or the
#: search stops: the peak no longer falls with the tube's speed (the disturbance and drift
#: bounds alone ask for it).
MIN_IMPROVEMENT = 0.95

#: ``(design, spec) -> InputProof``: the proved peak of each input along a design, for the
#: plants of ``spec`` (law (13)'s or the cascade's).
DesignProver = Callable[[Design, Spec], InputProof]


@dataclass(frozen=True)
class Candidate:
    """One tube tried against the bound.

    Attributes
    ----------
    label : str
        How it was made (``"default design"``, ``"softer circumvents (k = 0.2)"``,
        ``"via points"``).
    design : Design
        The certified design (without the bound).
    proof : InputProof
        The proved peak of each input along it.
    """

    label: str
    design: Design
    proof: InputProof


def slower_variants(spec: Spec, default: Design | None,
                    bound: tuple[float, ...] | None = None) -> list[tuple[str, Spec]]:
    """The specs to design after the default one, in order, as ``(label, spec)``.

    Parameters
    ----------
    spec : Spec
        Without ``[actuator]``.
    default : Design or None
        Its default design; ``None`` where it failed (too fast for the rate or the
        velocity bound): then no softer circumvents, the via points first.
    bound : tuple of float, optional
        The ``[actuator] input_bound`` taken off ``spec``: a base's ``(v_max, omega_max)``
        times its moves for the turn too.

    Returns
    -------
    list of (str, Spec)
        Softer circumvents (the paper's tube with every ``k^j`` fixed to each ladder value
        above the default's largest), when the default is the paper's tube with
        circumvents and ``tube.circumvent_sharpness`` is free; then via points, when
        ``tube.method`` allows them and the default is not already a via tube; then, for
        a variant whose input is a force (``via_timing = "acceleration"``), via points
        timed for the acceleration (tasks too) with ``"smoothstep"`` segments, then with
        ``"scurve"`` ones, then both with blended corners (no obstacle that moves); then
        via points with ``"cruise"`` segments (peak rate 1.25 times the mean, where the
        smooth step's is 1.875), when ``tube.method`` allows via points and the spec has
        no tasks (whose legs are cruise segments already), and for a variant whose input
        is a velocity, the same with blended corners (no obstacle that moves, no
        ``[sensing]``); then, for a variant that ``turns`` (a base, given ``bound``), via
        points with cruise segments timed for the turn into each move
        (``via_timing = "turn"``, ``via_turn = v_max / omega_max``), stopped, then blended
        where blends are tried.
    """
    out: list[tuple[str, Spec]] = []
    if (default is not None and default.method == METHOD_PAPER and default.tube.circumvents
            and spec.tube.circumvent_sharpness is None and spec.tube.method != METHOD_VIA):
        sharpest = max(c.sharpness for c in default.tube.circumvents)
        out += [(f"softer circumvents (k = {k:g})",
                 replace(spec, tube=replace(spec.tube, circumvent_sharpness=k,
                                            method=METHOD_PAPER)))
                for k in SHARPNESS_LADDER if k > sharpest]
    if spec.tube.method in ("auto", METHOD_VIA) and (default is None
                                                    or default.method != METHOD_VIA):
        out.append(("via points", replace(spec, tube=replace(spec.tube, method=METHOD_VIA))))
    if (spec.tube.method in ("auto", METHOD_VIA)
            and variant_of(spec).via_timing == ACCELERATION_TIMING):
        # obstacles that move: their timed vias and detours plan one segment at a time
        moves = any(ob.motion != "still" for ob in spec.moving_obstacles)
        blend = [] if moves else [BLEND_CORNERS]
        for corners in [STOP_CORNERS, *blend]:
            for label, profile in (("via points timed for the force", SMOOTHSTEP),
                                   ("via points timed for the force, S-curve segments",
                                    SCURVE)):
                out.append((label + (", blended corners" if corners == BLEND_CORNERS else ""),
                            replace(spec, tube=replace(spec.tube, method=METHOD_VIA,
                                                       via_timing=ACCELERATION_TIMING,
                                                       via_profile=profile,
                                                       via_corners=corners))))
    if spec.tube.method in ("auto", METHOD_VIA) and not spec.tasks:
        out.append(("via points, cruise segments",
                    replace(spec, tube=replace(spec.tube, method=METHOD_VIA,
                                               via_profile=CRUISE))))
        # where the input is a velocity: the same with blended corners, which stop at no
        # via box (not where an obstacle moves; with [sensing] too: the tube as data runs
        # them)
        blend = (variant_of(spec).via_timing != ACCELERATION_TIMING
                 and not any(ob.motion != "still" for ob in spec.moving_obstacles))
        if blend:
            out.append(("via points, cruise segments, blended corners",
                        replace(spec, tube=replace(spec.tube, method=METHOD_VIA,
                                                   via_profile=CRUISE,
                                                   via_corners=BLEND_CORNERS))))
        if variant_of(spec).turns and bound is not None:
            # a base: each move also given the time to turn into it at omega_max
            turned = replace(spec.tube, method=METHOD_VIA, via_profile=CRUISE,
                             via_timing=TURN_TIMING, via_turn=bound[0] / bound[1])
            out.append(("via points timed for the turn, cruise segments",
                        replace(spec, tube=turned)))
            if blend:
                out.append(("via points timed for the turn, cruise segments, blended corners",
                            replace(spec, tube=replace(turned, via_corners=BLEND_CORNERS))))
    return out


def candidates(spec: Spec, design_free: Callable[[Spec], Design],
               prove: DesignProver) -> tuple[Candidate | None, list[Candidate]]:
    """Try the default design, then :func:`slower_variants`, on ``spec`` (which has
    ``[actuator]``), until one is proved within the bound.

    Parameters
    ----------
    spec : Spec
        With ``input_bound``.
    design_free : callable
        ``Spec -> Design``, the design without an input bound.
    prove : callable
        ``(Design, Spec) -> InputProof``: the proved peak of each input along a design.

    Returns
    -------
    accepted : Candidate or None
        The first whose proof meets ``spec.input_bound``.
    tried : list of Candidate
        Every candidate built, in order (the accepted one last).

    Raises
    ------
    DesignError
        The default design itself fails (no tube at all, whatever the bound), and, where
        a slower tube may cure its failure (:data:`~.deadline.SLOWER_HELPS`), no slower
        variant is certified within the bound either: the default's refusal.
    """
    bound = spec.input_bound
    free = spec.without_actuator()
    report("input bound", 0.0, "input bound: the default design")
    try:
        with reporting(None, (0.0, 0.5)):
            default = design_free(free)
    except DesignError as error:
        # a tube too fast for the rate or for the velocity bound: a slower one of the
        # variants below may be certified; else the default's refusal stands
        if error.kind not in SLOWER_HELPS:
            raise
        accepted, tried = _slower_candidates(spec, free, None, [], design_free, prove)
        if accepted is None:
            raise
        return accepted, tried
    tried = [Candidate("default design", default, prove(default, spec))]
    if tried[0].proof.meets(bound):
        return tried[0], tried
    return _slower_candidates(spec, free, default, tried, design_free, prove)


def _slower_candidates(spec: Spec, free: Spec, default: Design | None, tried: list,
                       design_free: Callable[[Spec], Design], prove: DesignProver
                       ) -> tuple[Candidate | None, list[Candidate]]:
    """:func:`candidates` after the default design: each of :func:`slower_variants` (of
    ``default``, or of a default that failed, ``None``) designed and proved, until one
    meets ``spec.input_bound``."""
    bound = spec.input_bound
    softer_failed = False
    slower = slower_variants(free, default, bound)
    for k, (label, variant) in enumerate(slower):
        share = (0.5 + 0.5 * k / len(slower), 0.5 + 0.5 * (k + 1) / len(slower))
        report("input bound", share[0], f"input bound: {label} ({k + 2} of at most "
                                        f"{len(slower) + 1})")
        softer = variant.tube.method == METHOD_PAPER
        if softer and softer_failed:
            continue
        try:
            with reporting(None, share):
                design = design_free(variant)
        except DesignError:
            # a smoother bump has a longer window: once the paper's search fails with one,
            # the smoother ones are not tried (on to via points)
            softer_failed = softer_failed or softer
            continue
        tried.append(Candidate(label, design, prove(design, spec)))
        if tried[-1].proof.meets(bound):
            return tried[-1], tried
    return None, tried


def _certified_rate(spec: Spec, tube, design_free: Callable[[Spec], Design],
                    prove: DesignProver | None) -> float | None:
    """The lowest rate (:func:`~.certificate.sampled.lowest_rate`) at which law (13)'s
    sampled check passes on ``tube``, if :func:`design_within_bound` (what
    :func:`~stt_codegen.design.search.design_tube` runs for it) then designs ``spec``
    there; else ``None``."""
    from ..tube import reference
    from .certificate.plant_class import plant_class
    from .certificate.sampled import lowest_rate
    with reference.numpy_math():
        rate, _ = lowest_rate(tube, spec, plant_class(spec), spec.gain)
    if rate is None or rate == spec.rate_hz:
        return None
    try:
        with without_advice():
            design_within_bound(replace(spec, rate_hz=rate), design_free, prove)
    except DesignError:
        return None
    return rate


def law13_input_proof(design: Design, spec: Spec,
                      initial_error: tuple[tuple[float, float], ...] | None = None
                      ) -> InputProof:
    """Law (13)'s proved peak of each input along ``design`` for ``spec``'s plants (the
    first order's role ``input_proof``).

    Parameters
    ----------
    design : Design
    spec : Spec
        Its plant class is the one proved.
    initial_error : tuple of (float, float), optional
        From this box of ``e(0)`` (:func:`~.certificate.sampled.check_sampled`).

    Returns
    -------
    InputProof
        :func:`~.certificate.actuator.prove_input_bound` of the design's tube; within
        :func:`~.failures.without_advice` (a search asking the verdict only), stopped at
        the first sample where an input's bound passes ``spec.input_bound`` (partial:
        it meets no bound, and a proof that meets it is the same).
    """
    limits = np.asarray(spec.input_bound or (), dtype=float)
    return prove_input_bound(design.tube, spec, limit=verdict_limit(
        spec, lambda u: bool(np.any(u > limits))), initial_error=initial_error)


def verdict_limit(spec: Spec, breaks: Callable[[np.ndarray], bool]
                  ) -> Callable[[np.ndarray], bool] | None:
    """The ``limit`` of an input proof
    (:func:`~.certificate.actuator.prove_input_bound`): ``breaks`` (true where a
    sample's bound of ``|u|`` breaks ``spec.input_bound``) within
    :func:`~.failures.without_advice` for a spec with ``[actuator]``, where a search asks
    the verdict only; else ``None`` (the whole proof, whose peaks a refusal names).

    Parameters
    ----------
    spec : Spec
    breaks : callable
        ``(bound of |u_i(t_k)|, a list of n floats) -> bool``, the variant's test of the bound.

    Returns
    -------
    callable or None
    """
    return breaks if spec.input_bound is not None and not advice_wanted() else None


def design_within_bound(spec: Spec, design_free: Callable[[Spec], Design],
                        prove: DesignProver | None = None, name_rate: bool = True) -> Design:
    """The certified design of ``spec`` whose controller is proved to stay within
    ``[actuator]``.

    Parameters
    ----------
    spec : Spec
        With ``input_bound`` set.
    design_free : callable
        ``Spec -> Design``, the design without an input bound
        (:func:`~stt_codegen.design.search.design_tube` on a spec without ``[actuator]``).
    prove : callable, optional
        ``(Design, Spec) -> InputProof``, the proved peak of each input along a design;
        default the variant's (role ``input_proof``: law (13)'s :func:`law13_input_proof`,
        the cascade's physical input of the certified second stage, the base's
        ``(v, omega)``).
    name_rate : bool
        When no design's proof holds, name the lowest rate at which law (13)'s sampled
        check passes and :func:`~stt_codegen.design.search.design_tube` then certifies the
        spec (``False`` for the cascade, whose stage names its own rate).

    Returns
    -------
    Design
        Its tube carries ``input_bound`` (the generated code clamps ``u`` to it),
        ``input_proof`` the proved peaks, ``spec`` the given spec.

    Raises
    ------
    DesignError
        No tube at all (as without ``[actuator]``); or no design within ``t_c`` keeps the
        bound (kind ``INPUT_BOUND``; ``tried``: the tube with the lowest peak-to-bound
        ratio): the message names the smallest ``prescribed_time`` that works, or why none
        up to :data:`MAX_TIME_FACTOR` times ``t_c`` does, and the bound the best design
        within ``t_c`` needs.
    """
    started = time.perf_counter()
    if prove is None:
        prove = variant_of(spec).entry("input_proof")
    bound = spec.input_bound
    accepted, tried = candidates(spec, design_free, prove)
    if accepted is not None:
        design = accepted.design
        return replace(design, tube=replace(design.tube, input_bound=bound), spec=spec,
                       input_proof=accepted.proof,
                       design_time_s=time.perf_counter() - started)
    proved = [c for c in tried if c.proof.proved]
    names = spec.input_names
    # the controller in the user's words: law (13)'s input, the cascade's force/torque, the
    # base's command
    law = variant_of(spec).input_words
    unit = f" {spec.input_unit}" if spec.input_unit else ""
    if not proved:
        reasons = "; ".join(f"{c.label}: {c.proof.reason}" for c in tried)
        named = name_rate and advice_wanted() and bool(tried)
        rate = (_certified_rate(spec, tried[0].design.tube, design_free, prove)
                if named else None)
        later = None
        if named and rate is None and not fixed_in_time(spec):
            # no rate holds (a delay no faster rate can hold, say): a slower tube asks
            # smaller commands; name the prescribed_time at which the whole design holds
            from .deadline import certified_time
            later = certified_time(spec, lambda trial: design_within_bound(
                trial, design_free, prove, name_rate=False))
        raise DesignError(
            f"no bound on {law} can be proved for actuator.input_bound: the "
            f"sampled-data check fails for every design tried ({reasons})"
            + (f"; controller.rate_hz = {rate:g} is certified" if rate is not None else "")
            + (f"; prescribed_time = {number_text(later)} s{moved_words(spec)} is certified"
               if later is not None else ""),
            kind=FailureKind.INPUT_BOUND, tried=tried[0].design.tube if tried else None,
            advice=({"controller.rate_hz": rate} if rate is not None else
                    later_advice(spec, later) if later is not None else {}))
    backing = _backing_up(spec, [c for c in proved if c.proof.complete
                                 and _peak_ratio(c.proof, bound) <= 1.0], law)
    if backing is not None:
        raise backing
    best = min(proved, key=lambda c: (_peak_ratio(c.proof, bound), c.proof.ratio(bound)))
    worst = max(range(len(bound)), key=lambda i: best.proof.peak[i] / bound[i])
    needs = ", ".join(f"{_round_up(v):g}" for v in best.proof.peak)
    asks = "up to" if best.proof.complete else "at least"     # a partial proof's peak
    message = (f"no design within prescribed_time = {spec.prescribed_time:g} s keeps {law} "
               f"within actuator.input_bound = [{', '.join(f'{b:g}{unit}' for b in bound)}]: "
               f"the best ({best.label}) asks {asks} {best.proof.peak[worst]:.3g}{unit} of "
               f"input {names[worst]} (bound {bound[worst]:g}{unit}) at t = "
               f"{best.proof.time[worst]:.3f} s")
    if not best.proof.backs_up_within:
        message += (f", and backs the base up at {best.proof.backward:.3g} m/s at t = "
                    f"{best.proof.backward_time:.3f} s (actuator.reverse_speed = "
                    f"{best.proof.reverse_limit:g} m/s)")
    if not advice_wanted():                   # the verdict only (a probe of a search)
        raise DesignError(message, kind=FailureKind.INPUT_BOUND, tried=best.design.tube)
    works, why = smallest_prescribed_time(spec, design_free, prove,
                                          best.proof.ratio(bound))
    needs = f"[{needs}]" + (f" ({spec.input_unit})" if unit else "")
    if works is not None:
        message += (f"; prescribed_time = {works:g} s works (the smallest to two significant "
                    f"digits or a half step{moved_words(spec)}), or input_bound = {needs} "
                    "with this prescribed_time")
    else:
        message += f"; {why}; input_bound = {needs} works with this prescribed_time"
    raise DesignError(message, kind=FailureKind.INPUT_BOUND, tried=best.design.tube,
                      advice={} if works is None else later_advice(spec, works))



def _peak_ratio(proof: InputProof, bound: tuple[float, ...]) -> float:
    """``max_i peak_i / bound_i`` of a proved ``proof`` (its backing up left out)."""
    return max(p / b for p, b in zip(proof.peak, bound)) if proof.proved else math.inf


def _backing_up(spec: Spec, fitting: list[Candidate], law: str) -> DesignError | None:
    """The refusal of a base whose candidates in ``fitting`` (each within
    ``input_bound``) all back up faster than ``[actuator] reverse_speed``, naming the
    ``reverse_speed`` the lowest of them needs; ``None`` when ``fitting`` is empty.

    Following the advice designs the same candidates, in the same order, with the same
    proofs: the first within the bound and backing up at most that fast is certified.
    """
    if not fitting:
        return None
    best = min(fitting, key=lambda c: c.proof.backward)
    proof = best.proof
    message = (f"no design within prescribed_time = {spec.prescribed_time:g} s keeps {law} "
               f"within actuator.reverse_speed = {proof.reverse_limit:g} m/s: the best "
               f"({best.label}) keeps within input_bound but backs the base up at "
               f"{proof.backward:.3g} m/s at t = {proof.backward_time:.3f} s")
    needs = reverse_speed_needed(proof, spec.input_bound[0])
    return DesignError(message + f"; actuator.reverse_speed = {needs:g} m/s works with this "
                       "prescribed_time", kind=FailureKind.INPUT_BOUND, tried=best.design.tube,
                       advice={"actuator.reverse_speed": needs})


def reverse_speed_needed(proof: InputProof, v_max: float) -> float:
    """The ``[actuator] reverse_speed`` that a base's ``proof`` meets: its ``backward``
    rounded up to two significant digits, at most ``v_max`` (m/s; a proof within
    ``input_bound`` backs up no faster than ``v_max``)."""
    return min(_round_up(proof.backward, 2), v_max)


def _round_up(value: float, digits: int = 3) -> float:
    """The smallest number of ``digits`` significant digits ``>= value`` (> 0)."""
    e = math.floor(math.log10(value)) - digits + 1
    up = math.ceil(value / 10.0 ** e * (1.0 - 1e-12)) * 10.0 ** e
    return float(f"{up:.{digits}g}") if float(f"{up:.{digits}g}") >= value else up



def smallest_prescribed_time(spec: Spec, design_free: Callable[[Spec], Design],
                             prove: DesignProver, ratio: float) -> tuple[float | None, str]:
    """The smallest ``prescribed_time`` (two significant digits, or the half step below:
    :func:`~.grid.half_step_below`) at which the procedure of :func:`candidates` meets the
    bound, above the spec's ``t_c`` (which fails).

    Law (13)'s peak input falls about as ``1 / t_c`` while the tube's speed dominates it,
    so each try grows ``t_c`` by the best peak-to-bound ratio found so far (between 1.25
    and 4); once a try passes, a bisection on the two-digit values between the last
    failing and the passing one finds the smallest (the check at each value decides; the
    answer is a value where it passed). The bisection asks verdicts only
    (:func:`~.failures.without_advice`): a shape's check stops where its input passes the
    bound, and a failing trial names nothing.

    Parameters
    ----------
    spec : Spec
        With ``input_bound``.
    design_free, prove
        As in :func:`candidates`.
    ratio : float
        The best ``max_i peak_i / bound_i`` at the spec's ``t_c`` (> 1).

    Returns
    -------
    prescribed_time : float or None
        Seconds.
    why : str
        When ``None``: why the search stopped (at once for a spec with ``[[tasks]]`` none of
        whose windows ends at ``t_c``: its legs are timed by the windows, which a later
        ``t_c`` does not move). Each trial is :func:`~stt_codegen.spec.deadline.with_deadline`
        of the spec: the windows that end at ``t_c`` end at the trial's.
    """
    if spec.tasks and not ending_windows(spec):
        # the legs' times are the tasks' windows, and none of them moves with t_c
        return None, ("a longer prescribed_time does not slow the legs: their times are "
                      "the [[tasks]] windows, none of which ends at prescribed_time; wider "
                      "windows may")
    cap = min(MAX_TIME_FACTOR * spec.prescribed_time,
              STEP_BUDGET / (HORIZON_FACTOR * spec.rate_hz))

    def passes_at(value: float) -> tuple[bool, float]:
        trial = with_deadline(spec, value)
        try:
            accepted, tried = candidates(trial, design_free, prove)
        except (DesignError, SpecError):
            return False, math.inf
        best = min((c.proof.ratio(spec.input_bound) for c in tried), default=math.inf)
        return accepted is not None, best

    def passes(index: int) -> tuple[bool, float]:
        return passes_at(grid_value(index))

    low = grid_index(spec.prescribed_time)
    if grid_value(low) > spec.prescribed_time:
        low -= 1
    high = None
    while high is None:
        guess = max(grid_index(grid_value(low) * min(max(ratio, 1.25), 4.0)), low + 1)
        if grid_value(guess) > cap:
            return None, (f"no prescribed_time up to {cap:.3g} s meets it "
                          f"({MAX_TIME_FACTOR:g} t_c or the step budget of the sampled check)")
        ok, found = passes(guess)
        if ok:
            high = guess
        elif not found < MIN_IMPROVEMENT * ratio:
            return None, (f"a longer prescribed_time does not lower the peak enough (at "
                          f"{grid_value(guess):g} s the best design still asks {found:.3g} "
                          "times the bound): the disturbance and drift bounds of "
                          "[assumptions] alone ask for about that much")
        else:
            low, ratio = guess, found
    # the bisection asks verdicts only: each shape's check stops where its input passes
    # the bound (the verdicts are the same), and no failing trial searches for advice
    with without_advice():
        found = smallest_passing(lambda i: passes(i)[0], low, high)
        return half_step_below(lambda value: passes_at(value)[0], found,
                               spec.prescribed_time), ""
