"""Design of the spatiotemporal tube for a spec: the search over circumvents (6), the gain.

The paper leaves several points open or, read literally, fails (see
docs/decisions.md). This module decides them deterministically:

* **Windows and candidates, eqs. (5)-(6)**: :mod:`stt_codegen.design.windows`.
* **Search**: a design is accepted only if its tube passes :func:`check_tube`: the
  continuous-time certificate (:mod:`stt_codegen.design.certificate`) and the
  sampling-rate limit. The search is a depth-first search with backtracking over
  obstacles in the order of their windows (one choice per spec obstacle, shared by the
  boxes of a covering); it fails with a :class:`DesignError` naming the obstacle when no
  candidate passes. Every :class:`DesignError` raised here carries a
  :class:`~stt_codegen.design.failures.FailureKind` and, where a tube was built, the
  best rejected one (``tried``).
* **Default gain** of law (13): half the sampled-loop stability limit at the tube's
  narrowest point, for the plants the spec's ``[assumptions]`` declare
  (:func:`~stt_codegen.design.gain.derived_gain`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..errors import DesignError
from ..progress import ProgressCallback, report, reporting
from ..spec.deadline import WINDOW_END
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube.parameters import Circumvent, TubeDesign, paper_segments
from .certificate import MAX_INTERVALS, MAX_MOVE_PER_SAMPLE, certify_tube
from .certificate.motion import certify_motion
from .actuator import design_within_bound
from .failures import (FailureKind, advice_text, advice_wanted, property_kind,
                       without_advice)
from .grid import grid_index, grid_value, smallest_passing
from .moving import MOTION_SPACE_TIME, design_moving, moves
from .gain import with_gain
from .plant_check import plant_failure
from .result import METHOD_PAPER, METHOD_VIA, Design, TubeCheck
from .tracking import SMOOTHER_RATIO, centre_speed, tracking_demand, unfollowable
from .tasks import TaskPlan, plan_tasks, task_plans
from .via import via_design
from .windows import WINDOW_INFLATION, candidates, overlap_interval, progress_time

__all__ = ["FASTER_RATE_FACTORS", "MAX_INITIAL_ERROR", "MAX_MOVE_PER_SAMPLE", "base_design",
           "cascade_within_bound", "check_tube", "design_tube", "paper_design"]

#: Largest ``|e_i|`` of ``x(0)`` in the tube at ``t = 0``: near the tube's edge law (13)
#: is so steep that the first sampled step overshoots (measured: at ``|e| ~ 1`` the
#: first input was 1e8 and the state left the arena in one period).
MAX_INITIAL_ERROR = 0.5
#: Candidate certificates the paper's search may run before it gives up.
MAX_CANDIDATE_CHECKS = 40
#: The same for the first try of ``tube.method = "auto"`` (via points come next).
AUTO_CANDIDATE_CHECKS = 5
#: Work budget of that first try: intervals whose ``alpha`` bounds its certificates
#: compute, summed over its candidate tubes (``Certificate.work``, a deterministic
#: measure of the cost; a paper design that needs more is rare, and via points are
#: cheaper to certify). The full search comes after via points.
AUTO_CANDIDATE_INTERVALS = 1000
#: Refinement budget of a candidate's certificate in the search (intervals): a candidate
#: that needs more is too thin to keep (the bundled cases need about 500).
CANDIDATE_INTERVALS = 3000
#: Default target half-width shrinks by this factor (at most TARGET_SHRINK_STEPS times)
#: while an obstacle lies within the window inflation of the target box.
TARGET_SHRINK = 0.5
TARGET_SHRINK_STEPS = 4
#: A tube refused for its sampling rate is checked at rates up to this factor above it
#: (:func:`lowest_passing_rate`), to name the lowest that passes.
RATE_SEARCH_FACTOR = 1000.0


def check_tube(design: TubeDesign, spec: Spec, obstacles: list[int] | None = None,
               final: bool = True, max_intervals: int = MAX_INTERVALS,
               resume: tuple | None = None) -> TubeCheck:
    """Check a designed tube: the continuous-time certificate and the sampling limit.

    Conditions, in order: no bound moves more than ``MAX_MOVE_PER_SAMPLE`` of the tube
    width in one sampling period; the tube is non-empty; ``x(0)`` starts with
    ``|e_i| <= MAX_INITIAL_ERROR`` (room for the first sampled steps); and every property
    of :func:`~stt_codegen.design.certificate.certify_tube` (``x(0)`` inside, inside the
    state space, missing each listed obstacle and, with ``final``, inside the target from
    ``t_c`` on) holds for all ``t >= 0``.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
    obstacles : list of int, optional
        Indices of the obstacle boxes to check against; default all.
    final : bool
    max_intervals, resume
        Passed to :func:`~stt_codegen.design.certificate.certify_tube`.

    Returns
    -------
    TubeCheck
    """
    certificate = certify_tube(design, spec, obstacles=obstacles, final=final,
                               max_intervals=max_intervals, resume=resume)
    if spec.moving_obstacles:           # space-time disjointness (certificate/motion.py)
        certificate = certify_motion(design, spec, certificate)
    margins = {m.name: m for m in certificate.margins}
    clearances = [m.margin for m in certificate.margins if m.name.startswith("avoids")]
    initial_error = certificate.initial_error
    max_ratio = certificate.max_move_ratio

    def result(reason: str, kind: FailureKind | None) -> TubeCheck:
        return TubeCheck(not reason, reason, certificate.min_width,
                         min(clearances, default=math.inf), max_ratio, initial_error,
                         certificate, kind)

    if certificate.decisive:               # fails for certain at some instant
        failure = certificate.first_failure()
        return result(f"{failure.name} fails: {failure.detail}", property_kind(failure.name))
    if not margins["sampling rate"].passed:  # first: a tube this fast also fails the rest
        also = ("" if margins["non-empty"].passed else
                f"; non-empty fails too: {margins['non-empty'].detail}")
        sharper = " or tube.circumvent_sharpness" if design.circumvents else ""
        return result(f"{margins['sampling rate'].detail}; a larger controller.rate_hz"
                      f"{sharper} helps{also}", FailureKind.SAMPLING_RATE)
    if not margins["non-empty"].passed:
        return result(f"non-empty fails: {margins['non-empty'].detail}", FailureKind.NON_EMPTY)
    if initial_error > MAX_INITIAL_ERROR and margins["initial state inside"].passed:
        return result(f"x(0) starts at |e| = {initial_error:.3g} of the tube's half-width "
                      f"at t = 0 (limit {MAX_INITIAL_ERROR}): the first sampled steps would "
                      "overshoot", FailureKind.INITIAL_ERROR)
    failure = certificate.first_failure()
    if failure is not None:
        return result(f"{failure.name} fails: {failure.detail}", property_kind(failure.name))
    return result("", None)



def lowest_passing_rate(tube: TubeDesign, spec: Spec) -> float | None:
    """The lowest ``controller.rate_hz`` (two significant digits) at which ``tube`` passes
    :func:`check_tube`, or ``None`` up to :data:`RATE_SEARCH_FACTOR` times its rate.

    A bound moves at most ``|gamma_dot| / rate`` in one period, so the certified
    ``max_move_ratio`` scales about as ``1 / rate``: the first try is
    ``rate_hz * max_move_ratio / MAX_MOVE_PER_SAMPLE``; ``alpha`` (hence the width)
    changes with the rate too, so tries grow until one passes, then a bisection on the
    two-digit values between the last failing and the passing rate finds the lowest
    (the tube's check at each rate decides; the answer is a rate where it passed).

    Parameters
    ----------
    tube : TubeDesign
        A tube that fails the sampling-rate limit at ``tube.rate_hz``.
    spec : Spec

    Returns
    -------
    float or None
        Hz.
    """
    def passes(index: int) -> tuple[bool, float]:
        found = check_tube(replace(tube, rate_hz=grid_value(index)), spec)
        return found.passed, found.max_move_ratio

    cap = grid_index(tube.rate_hz * RATE_SEARCH_FACTOR)
    low = grid_index(tube.rate_hz)
    if grid_value(low) > tube.rate_hz:
        low -= 1                     # the two-digit value below the (failing) rate
    ratio = check_tube(tube, spec).max_move_ratio
    high = None
    while high is None:
        if low >= cap:
            return None
        factor = min(max(ratio / MAX_MOVE_PER_SAMPLE, 1.25), RATE_SEARCH_FACTOR)  # inf: capped
        guess = min(max(grid_index(grid_value(low) * factor), low + 1), cap)
        ok, ratio = passes(guess)
        if ok:
            high = guess
        else:
            low = guess
    return grid_value(smallest_passing(lambda i: passes(i)[0], low, high))


# --------------------------------------------------------------------------- the search


def base_design(spec: Spec, gain: float = 1.0) -> TubeDesign:
    """The design without circumvents, from the spec's boxes and parameters.

    Parameters
    ----------
    spec : Spec
        The spec (its sets, tube parameters and rate).
    gain : float
        The gain ``k`` of law (13).

    Returns
    -------
    TubeDesign
        The paper's reach tube (4) from ``X_0``-hat (2) to ``T``-hat (3), no circumvents.
    """
    x0, d0 = spec.initial_state, spec.initial_half_width
    eta, d_t = spec.target_center, target_half_width(spec)
    return TubeDesign(
        name=spec.name, prescribed_time=spec.prescribed_time,
        state_lower=spec.state_space.lower, state_upper=spec.state_space.upper,
        segments=paper_segments(tuple(a - b for a, b in zip(x0, d0)),
                                tuple(a + b for a, b in zip(x0, d0)),
                                tuple(a - b for a, b in zip(eta, d_t)),
                                tuple(a + b for a, b in zip(eta, d_t)), spec.prescribed_time),
        initial_state=x0, circumvents=(),
        smoothness=spec.tube.smoothness, theta0=spec.tube.theta0, kappa=spec.tube.kappa,
        mu=spec.tube.mu, gain=gain, rate_hz=spec.rate_hz)


def target_half_width(spec: Spec) -> tuple[float, ...]:
    """``d_T`` of eq. (3): the spec's, or its default shrunk clear of nearby obstacles.

    When ``target.half_width`` is not set and an obstacle, inflated by
    ``WINDOW_INFLATION * delta_B``, meets the box ``eta +- d_T``, the default ``d_T`` is
    halved (at most :data:`TARGET_SHRINK_STEPS` times) until none does.
    """
    d_t = spec.target_half_width
    if spec.target_half_width_given:
        return d_t
    margin = WINDOW_INFLATION * spec.tube.delta_b
    eta = np.array(spec.target_center)
    boxes = spec.obstacle_boxes()
    lows = np.array([b.lower for b in boxes]).reshape(-1, len(eta)) - margin
    highs = np.array([b.upper for b in boxes]).reshape(-1, len(eta)) + margin
    scale = 1.0
    for _ in range(TARGET_SHRINK_STEPS + 1):
        half = np.array(d_t) * scale
        meets = np.all((eta - half < highs) & (eta + half > lows), axis=1)
        if not meets.any():
            break
        scale *= TARGET_SHRINK
    else:
        return d_t
    return tuple(float(v) for v in np.array(d_t) * scale)


def _ordered(circumvents) -> tuple[Circumvent, ...]:
    return tuple(sorted(circumvents, key=lambda c: (c.dimension, c.side, c.obstacle)))


#: Share of a design's progress bar for the tube; the variant's stage (the cascade's
#: certified second stage) takes the rest.
TUBE_SHARE = 0.8


def design_tube(spec: Spec, *, progress: ProgressCallback | None = None) -> Design:
    """Design the spatiotemporal tube of a spec and certify it.

    ``spec.tube.method`` picks the reach tube: ``"paper"`` (one ``tanh`` segment, eq. (4),
    with circumvents (7)-(9), :func:`paper_design`), ``"via"`` (via-point segments,
    :mod:`stt_codegen.design.via`) or ``"auto"`` (the paper's, else via points).

    Parameters
    ----------
    spec : Spec
        From :func:`stt_codegen.load_spec` or :meth:`stt_codegen.Spec.from_dict`.
    progress : callable, optional
        Called with a :class:`~stt_codegen.progress.Progress` (``stage``, ``fraction`` of
        the call done, ``message``) at the design's stages: the reach tube, each candidate
        tube of the search and its certificate, the via points, each design tried under
        ``[actuator]``, each shape of the cascade's second stage; the fractions never
        decrease and the last event is ``("done", 1.0)``. The search's length is not known
        in advance, so a fraction is the share of the stage's budget used (it jumps when
        a stage ends early).

    Returns
    -------
    Design
        The tube with its gain (the spec's ``controller.gain``, or
        :func:`~stt_codegen.design.gain.derived_gain` at the certified narrowest width),
        the method used, its check and certificate (every ``t >= 0``), the design's
        wall time in seconds, and ``spec``. :func:`stt_codegen.generate`,
        :func:`stt_codegen.simulate`, :func:`stt_codegen.verify` and the plots take it
        whole.

    With ``[actuator]`` (``spec.input_bound``), the tube is accepted only when law (13) is
    proved to stay within the bound along it, slowed where it must be, or refused
    (:func:`~stt_codegen.design.actuator.design_within_bound`). For a second-order spec
    the bound is on the physical input (force or torque) and the proof is the sampled
    cascade's certificate: the tube is accepted only with a certified second stage whose
    peak input is within the bound (docs/second-order.md, "Force limits").

    Raises
    ------
    TypeError
        ``spec`` is not a :class:`~stt_codegen.spec.loader.Spec` (a dict or a file name:
        load it first).
    DesignError
        The spec's plant violates Assumption 2 (:mod:`~stt_codegen.design.plant_check`),
        or no tube of the allowed methods passes :func:`check_tube`; the message gives
        the reason (for via points: where the free passage is too narrow, or what walls
        off the start or the target), ``kind`` what failed
        (:class:`~stt_codegen.design.failures.FailureKind`) and ``tried`` the best
        rejected tube (``None`` where none was built). With ``[actuator]``: no design
        within ``t_c`` keeps the bound (kind ``INPUT_BOUND``; the message names the
        ``prescribed_time`` that works). A tube that moves too fast for the rate (kinds
        ``SAMPLING_RATE``, ``NON_EMPTY``): the message names the smallest
        ``prescribed_time`` that is then certified, when one up to 16 times ``t_c`` is
        (:mod:`~stt_codegen.design.deadline`). With ``[controller] delay`` or ``jitter``: the
        design's sampled-data proof fails with them (kind ``TIMING``; the message names
        the delay or the rate that is certified, :mod:`~stt_codegen.design.timing`).

    See Also
    --------
    stt_codegen.load_spec, stt_codegen.Spec.from_dict : the spec.
    stt_codegen.generate : the standalone controller of the design.
    stt_codegen.simulate : the design in closed loop.
    stt_codegen.verify : the paper's lemmas and the certificate, checked again.
    stt_codegen.plot_design : a figure of the certified tube.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> design.method, design.certificate.passed, design.spec.name
    ('paper', True, 'omnirobot-s1')
    >>> [(c.obstacle, c.side) for c in design.tube.circumvents]   # obstacle 0: its upper side
    [(0, 'upper')]
    """
    if not isinstance(spec, Spec):
        hint = ("; for a dict use Spec.from_dict" if isinstance(spec, dict)
                else "; load it with load_spec" if isinstance(spec, str) else "")
        raise TypeError(f"design_tube(): parameter 'spec' must be a Spec, not "
                        f"{type(spec).__name__}{hint}")
    try:
        return _design_call(spec, progress)
    except DesignError as error:
        from .deadline import deadline_refusal    # a deadline too short: name one that works
        raise deadline_refusal(spec, error, _design_call) from None


def _design_call(spec: Spec, progress: ProgressCallback | None = None) -> Design:
    """:func:`design_tube` without the deadline's advice on refusal."""
    started = time.perf_counter()
    if spec.delay > 0.0 or spec.jitter > 0.0:      # the sampled proof must hold with them
        from .timing import design_with_timing
        with reporting(progress, final="done" if progress is not None else ""):
            return _timed(design_with_timing(spec, _untimed_call), started)
    return _untimed_call(spec, progress, started)


def _untimed_call(spec: Spec, progress: ProgressCallback | None = None,
                  started: float | None = None) -> Design:
    """:func:`design_tube`'s search, whatever ``[controller] delay`` says (the tube's
    candidates do not depend on it; the sampled proofs they pass through do)."""
    started = time.perf_counter() if started is None else started
    with reporting(progress, final="done" if progress is not None else ""):
        if spec.target_any_of:                # [target] any_of: the first box that designs
            return _timed(_any_target(spec), started)
        with reporting(None, (0.0, TUBE_SHARE)):
            design = _position_stage(spec)
        # a second-order spec: the sampled cascade must be certified on the final tube,
        # whatever path designed it (design/cascade_gain.py)
        with reporting(None, (TUBE_SHARE, 1.0)):
            design.stage      # the variant's stage: DesignError unless the sampled cascade
        return _timed(design, started)          # is certified


def _timed(design: Design, started: float) -> Design:
    """``design`` whose ``design_time_s`` is the wall time since ``started`` (the whole
    :func:`design_tube` call: the alternatives rejected and the cascade's certification
    included), its certified second stage kept (computed once)."""
    timed = replace(design, design_time_s=time.perf_counter() - started)
    if "second_stage" in design.__dict__:       # functools.cached_property's value
        timed.__dict__["second_stage"] = design.__dict__["second_stage"]
    return timed


def _any_target(spec: Spec) -> Design:
    """:func:`design_tube` with each target box of ``[target] any_of`` in turn; the first
    designed and certified is kept, its spec carrying the alternatives (docs/tasks.md,
    "Or-goals")."""
    failures: list[tuple[int, DesignError]] = []
    count = len(spec.target_any_of)
    for k, (q, variant) in enumerate(spec.target_any_of):
        report("target any_of", k / count, f"target any_of[{q}] ({k + 1} of {count})")
        try:
            with reporting(None, (k / count, (k + 1) / count)):
                design = design_tube(replace(variant, source_hash=spec.source_hash))
        except DesignError as exc:
            failures.append((q, exc))
            continue
        chosen = replace(variant, source_hash=spec.source_hash,
                         target_any_of=spec.target_any_of, target_dropped=spec.target_dropped)
        return replace(design, spec=chosen, target_choice=q)
    q, first = failures[0]
    more = (f" (and target any_of[{', '.join(str(k) for k, _ in failures[1:])}])"
            if len(failures) > 1 else "")
    advice, notes = _any_target_advice(spec, failures)
    raise DesignError(f"target any_of[{q}]: {first}{more}{notes}", kind=first.kind,
                      tried=first.tried, advice=advice)


def _own_value(spec: Spec, key: str) -> float | None:
    """The spec's own value of an advice key (``DesignError.advice``), if it is a number."""
    return {"prescribed_time": spec.prescribed_time, WINDOW_END: spec.prescribed_time,
            "controller.rate_hz": spec.rate_hz, "controller.delay": spec.delay,
            "plant.axle_offset": getattr(spec.drive, "axle_offset", None),
            "actuator.reverse_speed": spec.reverse_speed}.get(key)


def _any_target_advice(spec: Spec, failures: list[tuple[int, DesignError]]
                       ) -> tuple[dict, str]:
    """The advice of a ``[target] any_of`` refusal, and the words for the values named
    with a later box: per key, of the values the boxes' refusals name, the nearest to the
    spec's own (the first box's where there is no number to compare).

    Each box's value was designed and certified with that box as the target and the rest
    of the spec unchanged; the spec with it tries the boxes in the same order, each designed
    as before, so it keeps an earlier box that is certified there or reaches that box: the
    whole spec is certified with it."""
    advice: dict = {}
    source: dict = {}
    for q, error in failures:
        for key, value in error.advice.items():
            own = _own_value(spec, key)
            if key not in advice or (own is not None and not isinstance(value, bool)
                                     and abs(value - own) < abs(advice[key] - own)):
                advice[key], source[key] = value, q
    first = failures[0][0]
    # (the windows' end goes with prescribed_time, from the same box)
    moved = (" (with the [[tasks]] windows that end at prescribed_time ending at it too)"
             if WINDOW_END in advice else "")
    notes = "".join(f"; with target any_of[{source[key]}], {advice_text(key, value)}"
                    + (moved if key == "prescribed_time" else "") + " is certified"
                    for key, value in advice.items() if source[key] != first
                    and key != WINDOW_END)
    return advice, notes


def _position_stage(spec: Spec) -> Design:
    """:func:`design_tube` without the second stage of a second-order spec: the tube of the
    positions, for moving obstacles, ``[actuator]`` or neither."""
    if moves(spec):                       # obstacles that move: design/moving.py
        return design_moving(spec, _position_stage, check_tube)
    if spec.input_bound is not None:      # [actuator]: design/actuator.py
        # the bound's proof orders the tubes there (default, softer circumvents, via
        # points): auto's estimate of the smoother tube plays no part
        return variant_of(spec).entry("within_bound")(
            spec, lambda free: _design(free, smoother=False))
    return _design(spec, smoother=True)


def cascade_within_bound(spec: Spec, design_free: Callable[[Spec], Design]) -> Design:
    """The tube of a second-order spec with ``[actuator]`` (the cascade's role
    ``within_bound``, :mod:`~stt_codegen.spec.variants`): the first-order procedure
    (:func:`~stt_codegen.design.actuator.design_within_bound`) with the sampled cascade's
    certified peak of the physical input as its proof
    (:func:`~stt_codegen.design.cascade_gain.cascade_design_proof`, its role ``input_proof``).

    Parameters
    ----------
    spec : Spec
        A second-order spec with ``input_bound``.
    design_free : callable
        ``design_free(spec) -> Design``: the tube of a spec without the bound.

    Returns
    -------
    Design
        Certified within ``input_bound``.

    Raises
    ------
    DesignError
        No tube tried keeps the bound, or no second stage is certified at the rate.
    """
    free = spec.without_actuator()
    default = design_free(free)
    # no second stage keeps the tubes on the default tube, bound or not: a slower variant
    # of it (cruise segments: the legs timed by their lengths) may keep them and the
    # bound; else the rate is what to change (DesignError of kind SAMPLING_RATE naming
    # the rate that is certified)
    try:
        default.second_stage
    except DesignError as error:
        with without_advice():                # the verdict only
            try:
                return design_within_bound(spec, design_free, name_rate=False)
            except DesignError:
                pass
        raise _rate_within_bound(spec, error) from None

    def design_free_or_default(candidate: Spec) -> Design:
        return default if candidate == free else design_free(candidate)

    return design_within_bound(spec, design_free_or_default, name_rate=False)


#: Multiples of the rate that keeps the tubes tried, in turn, for one at which the whole
#: design keeps ``[actuator] input_bound`` too (a faster rate: a smaller sampling error,
#: so a smaller force peak), up to 16 times the spec's rate.
FASTER_RATE_FACTORS = (2.0, 4.0)


def _rate_within_bound(spec: Spec, error: DesignError) -> DesignError:
    """``error`` (the cascade's refusal at the spec's rate, bound or not) whose named
    ``controller.rate_hz`` is kept only when the whole design with ``[actuator]`` is then
    certified (the rate was found for the tubes alone). Else twice and four times it
    (:data:`FASTER_RATE_FACTORS`, up to 16 times the spec's rate) are tried, and the first
    whole design certified there is named (the drone room: 250 Hz keeps the tubes, 1000 Hz
    the thrusts too, with the spec's own ``prescribed_time``); else the rate is said to keep
    the tubes only. A ``prescribed_time`` may be named besides (:mod:`.deadline`)."""
    rate = error.advice.get("controller.rate_hz")
    if rate is None or not advice_wanted():
        return error
    faster = [rate * f for f in FASTER_RATE_FACTORS if rate * f <= 16.0 * spec.rate_hz]
    found = None
    with without_advice():                    # the verdict only
        for candidate in [rate, *faster]:
            try:
                _design_call(replace(spec, rate_hz=candidate))
            except DesignError:
                continue
            found = candidate
            break
    if found == rate:
        return error
    named = f"controller.rate_hz = {rate:g} is certified"
    kept = (f"controller.rate_hz = {rate:g} keeps the tubes but no design there keeps "
            "actuator.input_bound")
    if found is not None:
        kept += f"; controller.rate_hz = {found:g} is certified with it"
    advice = {k: v for k, v in error.advice.items() if k != "controller.rate_hz"}
    if found is not None:
        advice["controller.rate_hz"] = found
    return DesignError(str(error).replace(named, kept), kind=error.kind, tried=error.tried,
                       advice=advice)


def _design(spec: Spec, smoother: bool) -> Design:
    """:func:`design_tube` without ``[actuator]``; ``smoother``: ``auto`` may prefer the
    smoother via tube to the paper's circumvents (:func:`_trackable`)."""
    started = time.perf_counter()
    reason = plant_failure(spec)
    if reason:
        raise DesignError(reason, kind=FailureKind.PLANT)
    report("reach tube", 0.0, "the reach tube")
    base = base_design(spec)
    if spec.tasks:              # [[tasks]]: via points through the tasks' boxes
        tube, check, choice, plan = _tasks(spec, base)
        # obstacles until a task are certified in space-time (certificate/motion.py)
        return Design(with_gain(tube, check.min_width, spec), METHOD_VIA, check,
                      time.perf_counter() - started, spec=spec, task_choices=choice,
                      task_plan=plan,
                      motion=MOTION_SPACE_TIME if spec.moving_obstacles else "")
    method = spec.tube.method
    # "auto": the paper's search on a short budget, then via points, then the paper's
    # search on its full budget (a hard arena rarely needs it)
    full = (METHOD_PAPER, MAX_CANDIDATE_CHECKS, None)
    stages = {"paper": [full], "via": [(METHOD_VIA, 0, None)],
              "auto": [(METHOD_PAPER, AUTO_CANDIDATE_CHECKS, AUTO_CANDIDATE_INTERVALS),
                       (METHOD_VIA, 0, None), full]}[method]
    errors: dict[str, DesignError] = {}
    for k, (used, budget, work) in enumerate(stages):
        if used in errors and errors[used].kind is not FailureKind.SEARCH_BUDGET:
            continue          # the paper's search ended for another reason than its budget
        try:
            with reporting(None, (k / len(stages), (k + 1) / len(stages))):
                tube, check = (_via(spec, base) if used == METHOD_VIA
                               else paper_design(spec, base, budget, work,
                                                 followable=method == METHOD_PAPER
                                                 and not variant_of(spec).tracking_in_stage))
            break
        except DesignError as exc:
            errors[used] = exc
    else:
        if len(errors) == 1:
            (only,) = errors.values()
            message, kind, tried = str(only), only.kind, only.tried
        else:
            paper, via = errors[METHOD_PAPER], errors[METHOD_VIA]
            message, kind = f"{paper}; with via points: {via}", paper.kind
            tried = paper.tried if paper.tried is not None else via.tried
            if via.kind is FailureKind.WALLED_OFF:   # the reason neither method can pass
                message, kind = f"{via} (the paper's search: {paper})", via.kind
            elif (paper.kind is FailureKind.NO_ROOM and via.tried is not None
                  and via.kind in (FailureKind.SAMPLING_RATE, FailureKind.NON_EMPTY)):
                # no room for a circumvent at all: the via tube, too fast for the rate, is
                # the design a later deadline or a faster rate can save
                kind, tried = via.kind, via.tried
        if (kind is FailureKind.SAMPLING_RATE and tried is not None and advice_wanted()
                and check_tube(tried, spec).kind is FailureKind.SAMPLING_RATE):
            rate = lowest_passing_rate(tried, spec)
            message += ("; the tube tried passes its check from controller.rate_hz = "
                        f"{rate:g} (the lowest to two significant digits)" if rate is not None
                        else "; no controller.rate_hz up to "
                        f"{RATE_SEARCH_FACTOR:g} times this one makes the tube tried pass")
        raise DesignError(message, kind=kind, tried=tried)
    tube = with_gain(tube, check.min_width, spec)
    if method == "auto" and used == METHOD_PAPER and METHOD_VIA not in errors:
        tube, used, check = _trackable(spec, base, tube, check, smoother)
    return Design(tube, used, check, time.perf_counter() - started, spec=spec)


def _trackable(spec: Spec, base: TubeDesign, tube: TubeDesign, check: TubeCheck,
               prefer_smoother: bool = True) -> tuple[TubeDesign, str, TubeCheck]:
    """``auto``'s choice between the paper's tube and via points: the via tube when the
    paper's asks for more gain than it has
    (:func:`~stt_codegen.design.tracking.tracking_demand` above 1) and the via tube asks
    for less, or (with ``prefer_smoother``: not under ``[actuator]``, whose proof orders
    the tubes) when the paper's has circumvents and the via tube's centre moves at most
    ``SMOOTHER_RATIO`` of the paper's peak speed
    (:func:`~stt_codegen.design.tracking.centre_speed`; docs/design.md, "Smoother tubes");
    else the paper's."""
    demand = tracking_demand(tube, check.certificate, spec)
    smoother = prefer_smoother and bool(tube.circumvents)
    if demand.ratio <= 1.0 and not smoother:
        return tube, METHOD_PAPER, check
    try:
        via, via_check = _via(spec, base)
    except DesignError:
        return tube, METHOD_PAPER, check
    via = with_gain(via, via_check.min_width, spec)
    if demand.ratio > 1.0 and tracking_demand(via, via_check.certificate, spec).ratio < demand.ratio:
        return via, METHOD_VIA, via_check
    if smoother and (centre_speed(via, via_check.certificate)
                     <= SMOOTHER_RATIO * centre_speed(tube, check.certificate)):
        return via, METHOD_VIA, via_check
    return tube, METHOD_PAPER, check


def _tasks(spec: Spec, base: TubeDesign) -> tuple[TubeDesign, TubeCheck, tuple[int, ...],
                                                 TaskPlan]:
    """The first plan through the tasks' boxes (:mod:`~stt_codegen.design.tasks`: the visit
    orders and ``any_of`` alternatives of :func:`~stt_codegen.design.tasks.task_plans`,
    shortest travel first) whose tube passes :func:`check_tube`, the alternatives it took
    and its visits."""
    failures: list[DesignError] = []
    for k, (order, choice) in enumerate(task_plans(spec, base)):
        report("task plans", 0.0, f"task plan {k + 1}: visit order and any_of boxes")
        try:
            tube, plan = plan_tasks(spec, base, choice, order)
        except DesignError as exc:
            failures.append(exc)
            continue
        check = check_tube(tube, spec)
        if check.passed:
            return tube, check, choice, plan
        failures.append(DesignError(f"the tube through the tasks' boxes fails its check: "
                                    f"{check.reason}", kind=check.kind, tried=tube))
    first = failures[0]
    more = (f" (and {len(failures) - 1} other plans: visit orders, any_of boxes)"
            if len(failures) > 1 else "")
    raise DesignError(f"{first}{more}", kind=first.kind, tried=first.tried)


def _via(spec: Spec, base: TubeDesign) -> tuple[TubeDesign, TubeCheck]:
    report("via points", 0.0, "via points: the tube through the free space")
    tube = via_design(spec, base)
    report("via points", 0.5, "via points: the tube's certificate")
    check = check_tube(tube, spec)
    if not check.passed:
        raise DesignError(f"the via-point tube fails its check: {check.reason}",
                          kind=check.kind, tried=tube)
    return tube, check


def paper_design(spec: Spec, base: TubeDesign, max_checks: int = MAX_CANDIDATE_CHECKS,
                 max_work: int | None = None,
                 followable: bool = False) -> tuple[TubeDesign, TubeCheck]:
    """The paper's design: circumvents (7)-(9) on the single reach tube ``base``.

    Parameters
    ----------
    spec : Spec
    base : TubeDesign
        The paper's reach tube (:func:`base_design`).
    max_checks : int
        Candidate tubes to certify at most.
    max_work : int, optional
        Certificate work (``Certificate.work``, intervals computed), summed over the
        candidates, at most (default: no limit beyond :data:`CANDIDATE_INTERVALS` per
        candidate).
    followable : bool
        Also refuse a certified tube with circumvents that law (13), with the gain derived
        for it, cannot follow (:func:`~stt_codegen.design.tracking.unfollowable`) and
        search on (``tube.method = "paper"``, which has no other tube to fall back on).

    Returns
    -------
    tube : TubeDesign
        ``base`` with the circumvents chosen (gain not yet set).
    check : TubeCheck

    Raises
    ------
    DesignError
        No choice of circumvents passes :func:`check_tube` (or ``max_checks`` candidates
        or ``max_work`` intervals were used up); with ``followable``, kind ``TRACKING``
        when every certified choice was one the gain cannot follow.
    """
    boxes = spec.obstacle_boxes()
    delta_b = spec.tube.delta_b
    # one choice of (dimension, side, sharpness) per spec obstacle: a ball or polytope
    # covered by several boxes (Remark 3.1) is passed on one side by all of them
    groups: dict[int, list[int]] = {}
    starts: dict[int, float] = {}
    per_box: dict[int, dict[tuple, Circumvent]] = {}
    rank: dict[int, list[tuple]] = {}
    for b, box in enumerate(boxes):
        j = spec.obstacles[b].source
        interval = overlap_interval(base, box, WINDOW_INFLATION * delta_b)
        if interval is None:
            continue
        if interval[1] >= 1.0:
            raise DesignError(f"obstacle {j} comes within {WINDOW_INFLATION * delta_b:g} of "
                              "the target box eta +- d_T: shrink target.half_width",
                              kind=FailureKind.OBSTACLE_AT_TARGET, tried=base)
        found_here = candidates(base, spec, b, delta_b)
        per_box[b] = {(c.dimension, c.side, q): c for q, c in enumerate(found_here)}
        groups.setdefault(j, []).append(b)
        rank.setdefault(j, list(per_box[b]))
        starts[j] = min(starts.get(j, math.inf), progress_time(base, interval[0]))
    options: dict[int, list[tuple[Circumvent, ...]]] = {}
    for j, members in groups.items():
        keys = [key for key in rank[j] if all(key in per_box[b] for b in members)]
        if not keys:
            raise DesignError(f"obstacle {j} cannot be circumvented: no dimension leaves "
                              f"room of delta_b = {delta_b:g} beside it",
                              kind=FailureKind.NO_ROOM, tried=base)
        options[j] = [tuple(per_box[b][key] for b in members) for key in keys]
    order = sorted(options, key=lambda j: (starts[j], j))
    failures: dict[int, TubeCheck] = {}     # per obstacle: its first rejected candidate
    budget: list[float] = [max_checks, math.inf if max_work is None else max_work]
    # the rejected tube that got furthest (most obstacles chosen), for DesignError.tried
    best: list = [-1, base]
    final_failure: list[TubeCheck] = []     # the complete tubes' checks

    def reasons() -> str:
        unfollowed = [f.reason for f in final_failure if f.kind is FailureKind.TRACKING][:1]
        return "; ".join([f"obstacle {j}: {f.reason}" for j, f in sorted(failures.items())]
                         + [f"the first certified tube: {r}" for r in unfollowed])

    def check(design: TubeDesign, **kwargs) -> TubeCheck:
        if budget[0] <= 0 or budget[1] <= 0:
            raise DesignError(f"no certified circumvents within {max_checks} candidate tubes"
                              + ("" if max_work is None else f" and {max_work} intervals of "
                                 "certificate work") + f" ({reasons()})",
                              kind=FailureKind.SEARCH_BUDGET, tried=best[1])
        report("candidate tubes", 1.0 - budget[0] / max_checks,
               f"candidate tube {max_checks - budget[0] + 1:g} of at most {max_checks}")
        budget[0] -= 1
        # the budget counts new work: the intervals resumed from the parent come free
        resume = kwargs.get("resume")
        reused = 0 if resume is None else int(np.searchsorted(
            np.array(resume[0].state.points, dtype=float) / design.rate_hz, resume[1],
            side="right"))
        found = check_tube(design, spec, max_intervals=int(
            min(CANDIDATE_INTERVALS, reused + budget[1])), **kwargs)
        budget[1] -= found.certificate.work
        return found

    def search(level: int, chosen: tuple[Circumvent, ...],
               parent: TubeCheck | None) -> tuple[TubeDesign, TubeCheck] | None:
        if level == len(order):
            design = replace(base, circumvents=_ordered(chosen))
            # the same tube as the last partial check: resume all of it
            accepted = check(design, resume=None if parent is None
                             else (parent.certificate, math.inf))
            if accepted.passed:
                # the circumvents are what one gain may not follow: a straight tube is the
                # method's only one, and its proved |e| is far below (docs/design.md)
                why = (unfollowable(with_gain(design, accepted.min_width, spec), accepted.certificate,
                                    spec) if followable and design.circumvents else "")
                if not why:
                    return design, accepted
                accepted = replace(accepted, passed=False, reason=why,
                                   kind=FailureKind.TRACKING)
            final_failure.append(accepted)
            if level > best[0]:
                best[:] = [level, design]
            return None
        j = order[level]
        done = [b for k in order[:level + 1] for b in groups[k]]
        hopeless: set[tuple[int, str]] = set()
        for option in options[j]:
            side = (option[0].dimension, option[0].side)
            if side in hopeless:
                continue
            design = replace(base, circumvents=_ordered(chosen + option))
            # before the new windows open the tube is the parent's
            opens = min(c.start for c in option)
            partial = check(design, obstacles=done, final=False,
                            resume=None if parent is None else (parent.certificate, opens))
            if not partial.passed:
                failures.setdefault(j, partial)
                if level > best[0]:
                    best[:] = [level, design]
                if partial.kind is not FailureKind.SAMPLING_RATE:
                    hopeless.add(side)   # a smoother bump only helps the sampling rate
                continue
            found = search(level + 1, chosen + option, partial)
            if found is not None:
                return found
        return None

    found = search(0, (), None)
    if found is None:
        if not order:
            base_check = check_tube(base, spec)
            raise DesignError(f"the reach tube fails its check: {base_check.reason}",
                              kind=base_check.kind, tried=base)
        first = (failures[min(failures)] if failures else final_failure[0])
        # a certified tube the gain cannot follow: that is what failed
        first = next((f for f in final_failure if f.kind is FailureKind.TRACKING), first)
        raise DesignError("no choice of circumvent dimension and side passes the tube "
                          f"check ({reasons() or 'the final check failed'})",
                          kind=first.kind, tried=best[1])
    return found
