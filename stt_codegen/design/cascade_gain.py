"""The cascade's second stage from declared bounds, chosen so that the sampled cascade is
certified (docs/second-order.md).

Linearized at ``e1 = e2 = 0`` the cascade is two first-order loops: the velocity error
``z = x2 - r`` obeys ``z_dot = -(4 k2 lambda / rho2^2) z + (f + w - r_dot)`` for each
eigenvalue ``lambda`` of the symmetric part of ``g``, and the position error
``x1_dot = -(16 k1 / gamma_d^2) (x1 - gamma_s / 2) + z + ...``. A *shape* (:data:`SHAPES`)
puts

* the inner bandwidth ``omega2 = 4 k2 lambda / rho2_floor^2`` at ``step / dt`` for
  ``lambda = g_max``;
* the outer bandwidth at the narrowest tube, ``omega1 = 16 k1 / gamma_d,min^2``, at
  ``omega2,min / separation`` (time-scale separation);
* the floor ``rho2_floor = margin (F + omega1 V) / omega2,min``: ``margin`` times the linear
  loop's steady velocity error under the declared bound ``F`` on ``|f + w|`` and the
  estimate ``omega1 V`` of ``|r_dot|`` (``V``: the fastest bound of the designed tube);
* ``rho2(0) = |x2(0) - r(x1(0), 0)| + rho2_floor`` (contains the initial error), shrinking
  at ``l = omega1``.

The linearization only proposes numbers. :func:`certified_stage` keeps the first shape
whose stage the sampled cascade's certificate
(:func:`.certificate.cascade_sampled.check_cascade_sampled`, through
:func:`~.certificate.cascade_sampled.certify_stage`) accepts at the
spec's rate, and :func:`second_stage_for` refuses the design when none is, naming the
lowest certified rate (:func:`lowest_certified_rate`). With ``[actuator] input_bound`` (the
physical input: force or torque) a shape is kept only when the certificate's peak input is
within the bound too; :func:`cascade_input_proof` gives the design that peak, so that it
slows the tube or refuses as for law (13) (:mod:`.actuator`).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from ..progress import report as report_progress, reporting
from ..rounding import round_up
from ..spec.variants import require_variant, variant_of
from ..tube import reference
from ..tube.parameters import TubeDesign
from ..tube.second_stage import SecondStage
from .certificate.cascade_sampled import certify_stage
from .certificate.sampled import largest_passing
from .failures import advice_wanted
from .input_bound import InputProof

__all__ = ["RATE_SEARCH_FACTOR", "SHAPES", "cascade_design_proof", "cascade_input_proof", "certified_stage",
           "derived_second_stage", "fastest_searched_rate", "lowest_certified_rate",
           "second_stage_for", "tube_speed", "upward_search"]


#: The shapes of the second stage the design tries, in order, until the sampled cascade's
#: certificate holds: ``(omega2 dt at lambda = g_max, omega2,min / omega1, rho2_floor over
#: the linear loop's steady velocity error)``. A larger inner step pulls the velocity
#: error back harder per period (the certificate's contraction); a larger separation
#: slows the virtual velocity ``r`` (less change of ``r`` per period); a larger floor
#: widens the velocity tube. The last three, a slower outer loop on a fast inner one, ask
#: less force of a tube timed for it (stlpy's ReachAvoid at 14 s: 0.99 of its bound with
#: the separation 40, where the first five ask 1.23 or more; DoorPuzzle at 37.5 s without
#: disturbance is certified with the separation 15 alone), so they come last: a spec the
#: first five certify keeps its stage. Every shape costs a certificate run on every tube
#: a refusal's search tries, cut short where it cannot beat the shape before
#: (:func:`certified_stage`): the hovercraft at 1 kHz names its time in 12.3 s of CPU.
SHAPES = ((0.3, 10.0, 4.0), (1.0, 5.0, 4.0), (0.5, 10.0, 4.0), (1.4, 10.0, 4.0),
          (0.3, 10.0, 16.0), (1.0, 20.0, 4.0), (1.0, 40.0, 8.0), (1.0, 15.0, 4.0))

#: Samples of the tube's speed over ``[0, t_c]``.
SPEED_SAMPLES = 4001


def tube_speed(design: TubeDesign, samples: int = SPEED_SAMPLES) -> float:
    """``V``: the largest ``|rho_dot|`` and ``|beta_dot|`` of the designed tube on a grid of
    ``[0, t_c]``, state units per second (sampled: an estimate, not a bound), rounded up
    to :data:`~stt_codegen.rounding.DIGITS` significant digits so that the gains derived
    from it are the same on every CPU.

    Parameters
    ----------
    design : TubeDesign
        The position tube.
    samples : int, optional
        Grid points on ``[0, t_c]``.

    Returns
    -------
    float
        State units per second.
    """
    t = np.linspace(0.0, design.prescribed_time, samples)
    with reference.numpy_math():
        _, _, rho_l_dot, rho_u_dot = reference.reach_tube(design, t)
        _, _, beta_l_dot, beta_u_dot = reference.circumvent(design, t)
    rates = np.concatenate([np.abs(v).ravel() for v in (rho_l_dot, rho_u_dot, beta_l_dot,
                                                         beta_u_dot)])
    return round_up(float(np.max(rates[np.isfinite(rates)])))


def derived_second_stage(design: TubeDesign, min_width: float, input_gain: tuple,
                         drift_bound: float, initial_velocity,
                         shape: tuple[float, float, float] | None = None
                         ) -> tuple[SecondStage, dict]:
    """``k1``, ``k2`` and ``rho2`` of one shape (module docstring) and their derivation.

    Parameters
    ----------
    design : TubeDesign
        The position tube (its ``rate_hz``, ``initial_state``).
    min_width : float
        ``gamma_d,min``, the certified narrowest width of the tube, state units.
    input_gain : (float, float)
        ``(g_min, g_max)``: bounds of the eigenvalues of the symmetric part of ``g`` over
        the declared plants (e.g. ``1 / m`` for mass ``m``), > 0.
    drift_bound : float
        ``F >= sup |f + w|`` over the declared plants and the state space (gravity, drag
        at the velocity bound, disturbance), velocity units per second.
    initial_velocity : sequence of float, length n
        ``x2(0)``.
    shape : (float, float, float), optional
        ``(omega2(g_max) dt, omega2,min / omega1, rho2_inf over the steady error)``;
        default the first of :data:`SHAPES`.

    Returns
    -------
    stage : SecondStage
    derivation : dict
        The numbers above (``omega1``, ``omega2_min``, ``tube_speed``, ...), JSON-ready.

    Raises
    ------
    ValueError
        Non-positive gains or width, a negative drift bound, or a wrong length.
    """
    g_min, g_max = (float(v) for v in input_gain)
    if not 0 < g_min <= g_max or min_width <= 0 or drift_bound < 0:
        raise ValueError("need 0 < g_min <= g_max, min_width > 0 and drift_bound >= 0")
    n = design.dimension
    x2 = np.asarray(initial_velocity, dtype=float)
    if x2.shape != (n,):
        raise ValueError(f"initial_velocity needs {n} entries")
    step, separation, margin = SHAPES[0] if shape is None else shape
    dt = 1.0 / design.rate_hz
    omega2_min = step * g_min / (g_max * dt)
    omega1 = omega2_min / separation
    k1 = omega1 * min_width**2 / 16.0
    speed = float(tube_speed(design))
    floor = float(margin * (drift_bound + omega1 * speed) / omega2_min)
    k2 = step * floor**2 / (4.0 * dt * g_max)
    first = dataclasses.replace(design, gain=k1, input_bound=None)
    x1 = np.array(design.initial_state, dtype=float)
    r0, _, _ = reference.law_step(first, x1[None], 0.0, dt, np.zeros((1, 2 * n)))
    z0 = np.abs(x2 - r0[0])
    stage = SecondStage(k1, k2, tuple(float(v) for v in z0 + floor), (floor,) * n, omega1)
    return stage, {"shape": [step, separation, margin], "dt": dt, "input_gain": [g_min, g_max], "min_width": float(min_width),
                   "drift_bound": float(drift_bound), "tube_speed": speed,
                   "omega1": omega1, "omega2_min": omega2_min, "position_gain": k1,
                   "velocity_gain": k2, "width_floor": floor,
                   "width_start": list(stage.width_start), "decay": omega1,
                   "initial_velocity_error": z0.tolist()}


def certified_stage(tube: TubeDesign, spec, min_width: float,
                    bound: tuple[float, ...] | None = None) -> tuple[SecondStage | None, dict]:
    """The first shape of :data:`SHAPES` whose second stage the sampled cascade's
    certificate accepts for ``spec``'s declared plants at ``tube.rate_hz`` and, given a
    ``bound``, whose certified peak input is within it.

    Parameters
    ----------
    tube : TubeDesign
        The position tube at the rate judged.
    spec : Spec
        With a second-order ``plant.model``.
    min_width : float
        ``gamma_d,min`` of ``tube``'s certificate.
    bound : tuple of float, optional
        ``[actuator] input_bound``, one per physical input (force or torque units): the
        certificate's ``peak_input[i] <= bound[i]`` is required too. ``None``: the tubes
        only.

    Returns
    -------
    stage : SecondStage or None
        ``None`` when no shape is accepted.
    derivation : dict
        The accepted stage's derivation with its ``certificate``; when none: the last
        shape's, with the reports of every shape tried (``tried``: ``shape``, ``passed``
        (the tubes kept), ``reason``, ``peak_input``, ``peak_input_time``, ``horizon``).
        Within :func:`~.failures.without_advice` (a search asking the verdict only), a
        shape's check stops where its input passes ``bound``: the stage kept is the same,
        but such a shape is reported as not passed, with the peak found until then.
        Otherwise, given a ``bound`` (every entry positive), a shape tried after one that
        keeps the tubes stops where its input passes the lowest peak-to-bound ratio found
        so far times the bound (it cannot have a lower ratio), and is reported so too: the
        stage kept and the tubes-kept shape of lowest ratio (:func:`cascade_input_proof`)
        are the same.
    """
    order = spec.second_order
    # the certificate reads neither bound: one certificate per tube and stage, bound or not
    tube, spec = dataclasses.replace(tube, input_bound=None), spec.without_actuator()
    # a search that asks the verdict only (no advice) needs no shape's whole peak: its
    # check stops where the input passes the bound (the shape kept is the same)
    limit = None if bound is None or advice_wanted() else tuple(bound)
    # with advice, the lowest peak-to-bound ratio of the shapes that keep the tubes: a
    # shape whose input passes it times the bound cannot be lower, so its check stops there
    # (a bound with a zero entry has no ratio: every shape runs whole)
    cut = limit is None and bound is not None and all(b > 0.0 for b in bound)
    lowest = math.inf
    tried = []
    for k, shape in enumerate(SHAPES):
        report_progress("cascade stage", k / len(SHAPES),
                        f"the cascade's second stage: shape {k + 1} of at most {len(SHAPES)}")
        stage, derivation = derived_second_stage(
            tube, min_width, order.input_gain, order.drift_bound + spec.disturbance_amplitude,
            order.initial_velocity, shape)
        with reporting(None, (k / len(SHAPES), (k + 1) / len(SHAPES))):
            passed, report = certify_stage(tube, spec, stage, limit if lowest == math.inf
                                           else tuple(lowest * b for b in bound))
        within = bound is None or all(p <= b for p, b in zip(report["peak_input"], bound))
        if passed and within:
            return stage, {**derivation, "certificate": report}
        if passed and cut:
            lowest = min(lowest, max(p / b for p, b in zip(report["peak_input"], bound)))
        reason = report.get("reason", "") if not passed else (
            "the certified peak input " + ", ".join(f"{p:.4g}" for p in report["peak_input"])
            + " exceeds the bound " + ", ".join(f"{b:g}" for b in bound))
        tried.append({"shape": list(shape), "passed": passed, "reason": reason,
                      "peak_input": list(report["peak_input"]),
                      "peak_input_time": list(report.get("peak_input_time", [])),
                      "horizon": report.get("horizon", 0.0)})
    return None, {**derivation, "tried": tried}


def cascade_design_proof(design, spec, initial_error=None) -> InputProof:
    """The cascade's certified peak of each physical input along ``design`` for ``spec``
    (the cascade's role ``input_proof``): :func:`cascade_input_proof` on its tube and its
    certified narrowest width.

    Parameters
    ----------
    design : Design
    spec : Spec
        With a second-order ``plant.model`` and ``input_bound``.
    initial_error : None
        The cascade does not replan (its certificate starts from ``x(0)``).

    Returns
    -------
    InputProof

    Raises
    ------
    ValueError
        ``initial_error`` given.
    """
    if initial_error is not None:
        raise ValueError("the cascade's certificate starts from x(0): no initial_error")
    return cascade_input_proof(design.tube, spec, design.check.min_width)


def cascade_input_proof(tube: TubeDesign, spec, min_width: float) -> InputProof:
    """The certified peak of each physical input ``|u_i|`` of the cascade along ``tube``:
    that of the second stage :func:`certified_stage` deploys under ``spec.input_bound``,
    or, when no certified shape keeps the bound, of the certified shape with the lowest
    peak-to-bound ratio (the design slows the tube or refuses from it,
    :mod:`.actuator`).

    Parameters
    ----------
    tube : TubeDesign
        The position tube.
    spec : Spec
        With a second-order ``plant.model`` and ``input_bound``.
    min_width : float
        ``gamma_d,min`` of ``tube``'s certificate.

    Returns
    -------
    InputProof
        ``peak``: the certificate's ``peak_input`` (force or torque units), a bound of
        ``|u_k,i|`` at every sample of ``[0, 1.1 t_c]``, hence of the held input; not
        proved when no shape is certified at ``tube.rate_hz`` (the first shape's reason).
    """
    bound = spec.input_bound
    certified, derivation = certified_stage(tube, spec, min_width, bound)
    if certified is not None:      # a shape is certified (None: none is)
        report = derivation["certificate"]
        return InputProof(True, tuple(report["peak_input"]), tuple(report["peak_input_time"]),
                          float(report["horizon"]), max_abs_e=float(report["max_abs_e2"]))
    certified = [t for t in derivation["tried"] if t["passed"]]
    if not certified:
        n = tube.dimension
        return InputProof(False, (math.inf,) * n, (0.0,) * n, 0.0,
                          "the sampled cascade is not certified at controller.rate_hz = "
                          f"{tube.rate_hz:g} Hz with any shape (the first: "
                          f"{derivation['tried'][0]['reason']})")
    best = min(certified, key=lambda t: max(p / b for p, b in zip(t["peak_input"], bound)))
    return InputProof(True, tuple(best["peak_input"]), tuple(best["peak_input_time"]),
                      float(best["horizon"]))


def _largest_stage_delay(tube: TubeDesign, spec, min_width: float) -> float | None:
    """The largest ``[controller] delay`` below the spec's (by bisection, to ``delay /
    2^DELAY_HALVINGS``) with which some shape is certified on ``tube`` at its rate, with the
    spec's jitter and bound; ``None`` when none is, or only 0 (the position tube does not
    depend on the delay, so the design is then certified whole)."""
    def passes(delay: float) -> bool:
        trial = dataclasses.replace(spec, delay=delay)
        return certified_stage(tube, trial, min_width, spec.input_bound)[0] is not None

    with reporting(None, (0.0, 0.0)):              # no progress events of its own
        found = largest_passing(passes, spec.delay)
    return found if found else None


def _compensated_stage(tube: TubeDesign, spec, min_width: float) -> bool:
    """Whether ``[controller] compensate_delay`` would make some shape certified on
    ``tube`` at its rate with the spec's delay, bound and no jitter (False when the spec
    compensates already or its timing cannot be compensated)."""
    if (spec.compensate_delay or spec.delay <= 0.0 or spec.jitter != 0.0
            or spec.delay * tube.rate_hz > 1.0 or not variant_of(spec).predicts_delay):
        return False
    trial = dataclasses.replace(spec, compensate_delay=True)
    with reporting(None, (0.0, 0.0)):              # no progress events of its own
        return certified_stage(tube, trial, min_width, spec.input_bound)[0] is not None


def _one_period_rate(tube: TubeDesign, spec) -> float | None:
    """With a compensated delay of one whole period (the command computed during one period
    and applied at the next tick): the lowest rate on the two-digit grid, up to
    ``RATE_SEARCH_FACTOR`` times the spec's, at which some shape is certified with a delay
    of one period of that rate (bisection, as :func:`lowest_certified_rate`); ``None`` when
    even the fastest fails."""
    from .grid import grid_value

    def passes(index: int) -> bool:
        rate = grid_value(index)
        trial = dataclasses.replace(spec, rate_hz=rate, delay=1.0 / rate)
        return _rate_certified(tube, trial, rate)

    found = upward_search(passes, tube.rate_hz, tube.rate_hz * RATE_SEARCH_FACTOR)
    return None if found is None else grid_value(found)


def _rate_certified(tube: TubeDesign, spec, rate_hz: float) -> bool:
    """Whether some shape is certified at ``rate_hz`` (the tube certified again there);
    not where the period is shorter than ``[controller] delay + 2 jitter``."""
    from .certificate import certify_tube
    if spec.delay + 2.0 * spec.jitter > 1.0 / rate_hz:
        return False                   # the delay (s) and jitter must fit the period
    trial = dataclasses.replace(tube, rate_hz=rate_hz)     # the tubes kept, not the bound
    certificate = certify_tube(trial, spec)
    return bool(certificate.passed) and certified_stage(
        trial, spec, certificate.min_width)[0] is not None


#: The search for a certified rate goes up to this multiple of the spec's rate.
RATE_SEARCH_FACTOR = 16.0


def fastest_searched_rate(rate_hz: float, spec) -> float:
    """The fastest rate :func:`lowest_certified_rate` tries upwards: ``RATE_SEARCH_FACTOR``
    times ``rate_hz``, and no faster than ``1 / (delay + 2 jitter)`` (``[controller]``: a
    shorter period cannot hold the delay).

    Parameters
    ----------
    rate_hz : float
        The rate searched from, Hz.
    spec : Spec
        Its ``delay`` and ``jitter``.

    Returns
    -------
    float
        Hz.
    """
    timing = spec.delay + 2.0 * spec.jitter
    fastest = rate_hz * RATE_SEARCH_FACTOR
    return min(fastest, 1.0 / timing) if timing > 0.0 else fastest


def lowest_certified_rate(tube: TubeDesign, spec, passes_at_rate: bool) -> float | None:
    """The smallest rate on the two-digit grid (:mod:`.grid`) at which a shape of
    :data:`SHAPES` is certified, between ``rate / RATE_SEARCH_FACTOR`` and ``rate *
    RATE_SEARCH_FACTOR`` (bisection, upwards after doubling the rate until it is
    certified, :func:`upward_search`: a faster rate is assumed not to break the
    certificate; every rate reported was certified). With ``[controller] delay`` or
    ``jitter`` the search stops at the fastest rate whose period holds ``delay + 2
    jitter`` (:func:`fastest_searched_rate`). ``None`` when even the fastest fails; the
    lowest end when it passes there.

    Parameters
    ----------
    tube : TubeDesign
        The certified position tube (its ``rate_hz``).
    spec : Spec
        Its spec, with a second-order ``plant.model``.
    passes_at_rate : bool
        Whether a shape is certified at ``tube.rate_hz`` (search downwards) or not (upwards).

    Returns
    -------
    float or None
        Hz.
    """
    from .grid import grid_index, grid_value, smallest_passing
    rate = tube.rate_hz
    if passes_at_rate:
        low, high = grid_index(rate / RATE_SEARCH_FACTOR), grid_index(rate)
        if grid_value(high) > rate:
            high -= 1
        if high <= low or _rate_certified(tube, spec, grid_value(low)):
            return grid_value(low) if high > low else rate
        best = smallest_passing(lambda j: _rate_certified(tube, spec, grid_value(j)), low, high)
        return grid_value(best) if _rate_certified(tube, spec, grid_value(best)) else rate
    found = upward_search(lambda j: _rate_certified(tube, spec, grid_value(j)), rate,
                          fastest_searched_rate(rate, spec))
    return None if found is None else grid_value(found)


def upward_search(passes, rate_hz: float, fastest: float) -> int | None:
    """The smallest grid index above ``rate_hz`` (:mod:`.grid`), up to ``fastest``, at which
    ``passes`` holds: tried at twice ``rate_hz``, four times, ... (the last try at
    ``fastest``) until it holds, then a bisection between the last rate that failed and
    that one (a faster rate is assumed not to break the certificate, as in
    :func:`lowest_certified_rate`; the index returned passed).

    A certificate at a faster rate checks more samples, so the slow rates are tried first:
    the fastest one only when every slower doubling fails.

    Parameters
    ----------
    passes : callable
        ``passes(index) -> bool`` on grid indices.
    rate_hz : float
        The rate that fails, Hz.
    fastest : float
        The fastest rate tried, Hz.

    Returns
    -------
    int or None
        A grid index; ``None`` when no rate up to ``fastest`` passes.

    Examples
    --------
    >>> from stt_codegen.design.grid import grid_index, grid_value
    >>> tried = []
    >>> def passes(index):
    ...     tried.append(grid_value(index))
    ...     return grid_value(index) >= 650
    >>> grid_value(upward_search(passes, 500.0, 8000.0)), tried
    (650.0, [1000.0, 750.0, 620.0, 680.0, 650.0, 630.0, 640.0])
    """
    from .grid import grid_index, grid_value, smallest_passing
    low, top = grid_index(rate_hz), grid_index(fastest)
    if grid_value(top) > fastest:
        top -= 1                       # the grid's last rate whose period holds the timing
    factor = 2.0
    while top > low:
        index = max(min(grid_index(factor * rate_hz), top), low + 1)
        if passes(index):
            return smallest_passing(passes, low, index)
        low, factor = index, 2.0 * factor
    return None


def second_stage_for(tube: TubeDesign, spec, min_width: float) -> tuple[SecondStage, dict]:
    """The certified second stage of a tube whose spec has a second-order ``plant.model``
    (:func:`certified_stage`, within ``spec.input_bound`` when given; computed once per
    tube; :attr:`Design.second_stage <stt_codegen.design.result.Design.second_stage>` is
    the way to ask for it).

    Parameters
    ----------
    tube : TubeDesign
        The certified position tube.
    spec : Spec
        Its spec.
    min_width : float
        The certificate's narrowest width (state units).

    Returns
    -------
    stage : SecondStage
    derivation : dict
        As :func:`derived_second_stage`, with the ``certificate``.

    Raises
    ------
    SpecError
        The spec's ``plant.model`` is first order (field ``plant.model``).
    DesignError
        No shape is certified at the design's rate (kind ``SAMPLING_RATE``, naming the
        rate that is); or, with ``[actuator]``, shapes are certified but none within
        ``input_bound`` (kind ``INPUT_BOUND``; :func:`~stt_codegen.design_tube` slows the
        tube or names the ``prescribed_time`` that works instead). Its ``tried`` is
        ``tube``, the position tube designed (for the figure of ``design --plot``).
    """
    require_variant(spec, "cascade", "the cascade's second stage")
    return _second_stage(tube, spec, min_width)


@functools.lru_cache(maxsize=16)
def _second_stage(tube: TubeDesign, spec, min_width: float) -> tuple[SecondStage, dict]:
    certified, derivation = certified_stage(tube, spec, min_width, spec.input_bound)
    if certified is not None:      # a shape is certified (None: none is)
        return certified, derivation
    from ..errors import DesignError
    from .failures import FailureKind, advice_wanted
    proof = (cascade_input_proof(tube, spec, min_width) if spec.input_bound is not None
             else None)
    if proof is not None and proof.proved:      # the tubes are kept, the bound is not
        unit = f" {spec.input_unit}"
        raise DesignError(
            f"no second stage tried ({len(SHAPES)} shapes) keeps the cascade's input within "
            "actuator.input_bound = [" + ", ".join(f"{b:g}{unit}" for b in spec.input_bound)
            + "] on this tube: the certified stage with the lowest peak-to-bound ratio asks "
            + ", ".join(f"|{name}| <= {p:.4g}{unit}"
                        for name, p in zip(spec.input_names, proof.peak))
            + "; design_tube slows the tube or names the prescribed_time that works "
            "(docs/second-order.md, 'Force limits')", kind=FailureKind.INPUT_BOUND,
            tried=tube)
    compensated = _compensated_stage(tube, spec, min_width) if advice_wanted() else False
    rate = (lowest_certified_rate(tube, spec, passes_at_rate=False)
            if advice_wanted() and not compensated else None)
    delay = (_largest_stage_delay(tube, spec, min_width)
             if spec.delay > 0.0 and advice_wanted() and not compensated else None)
    fastest = fastest_searched_rate(tube.rate_hz, spec)
    capped = (f" (a shorter period cannot hold controller.delay + 2 jitter = "
              f"{spec.delay + 2.0 * spec.jitter:g} s)"
              if fastest < tube.rate_hz * RATE_SEARCH_FACTOR else "")
    knobs = "a longer prescribed_time (a slower tube)" + (
        ", a shorter controller.delay" if spec.delay > 0.0 else "")
    need = (f"controller.compensate_delay = true is certified with controller.delay = "
            f"{spec.delay:g} s at {tube.rate_hz:g} Hz" if compensated else
            f"controller.rate_hz = {rate:g} is certified" if rate is not None else
            f"no rate up to {fastest:g} Hz is certified{capped}; {knobs} or a narrower "
            "assumptions.input_gain may be")
    if delay is not None:
        need += (f"; controller.delay = {delay:.3g} s is certified at {tube.rate_hz:g} Hz "
                 f"(of {spec.delay:.3g} s)")
    whole = (spec.compensate_delay and advice_wanted()
             and abs(spec.delay * tube.rate_hz - 1.0) < 1e-9)
    period_rate = _one_period_rate(tube, spec) if whole else None
    if period_rate is not None:
        need += (f"; if the delay is one period (computed during a period, applied at the "
                 f"next tick), controller.rate_hz = {period_rate:g} with controller.delay = "
                 f"{1.0 / period_rate:.3g} s is certified")
    first = derivation["tried"][0]["reason"]
    raise DesignError(f"the sampled cascade is not certified at controller.rate_hz = "
                      f"{tube.rate_hz:g} Hz for the declared plants with any second stage "
                      f"tried ({len(SHAPES)} shapes; with the first: {first}); {need} "
                      "(docs/second-order.md, 'The sampled cascade')",
                      kind=FailureKind.SAMPLING_RATE, tried=tube,
                      advice={**({"controller.compensate_delay": True} if compensated
                                 else {}),
                              **({} if rate is None else {"controller.rate_hz": rate}),
                              **({} if delay is None else {"controller.delay": delay})})
