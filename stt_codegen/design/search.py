"""Design of the spatiotemporal tube for a spec: windows (5), circumvent choices (6), gain.

The paper leaves several points open or, read literally, fails (see
docs/decisions.md). This module decides them deterministically:

* **Windows, eq. (5)**, computed robustly: with ``s = tanh(t / (t_c - t))`` the reach
  tube is linear in ``s``, so the times at which its box overlaps an obstacle box form
  one interval of ``s`` per dimension; intersected over dimensions and mapped back with
  ``t = t_c a / (1 + a)``, ``a = atanh(s)``. No 0/0 on degenerate dimensions.
* **Dimension and side, eq. (6)**: every valid (dimension, side) of every obstacle is a
  candidate; candidates are tried in a fixed order (longest overlap first) and a design
  is accepted only if its tube passes :func:`check_tube`: the continuous-time
  certificate (:mod:`stt_codegen.design.certificate`) and the sampling-rate limit. The search
  is a depth-first search with backtracking over obstacles in the order of their
  windows (one choice per spec obstacle, shared by the boxes of a covering); it fails
  with a :class:`DesignError` naming the obstacle when no candidate passes.
* **Bump window**: the active window is widened around the overlap interval so that
  the bump, whose sharpness ``k^j`` the spec fixes, is within ``delta_B / 2`` of its peak
  where the reach tube first and last overlaps the obstacle.
* **Default gain** of law (13): half the sampled-loop stability limit at the tube's
  narrowest point, for the plants the spec's ``[assumptions]`` declare
  (:func:`~stt_codegen.design.gain.derived_gain`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..tube import reference
from .gain import derived_gain
from .certificate import MAX_INTERVALS, MAX_MOVE_PER_SAMPLE, Certificate, certify_tube
from .result import METHOD_PAPER, METHOD_VIA, Design
from .via import via_design
from ..errors import DesignError
from ..spec.loader import Box, Spec
from ..tube.parameters import LOWER, UPPER, Circumvent, TubeDesign, paper_segments

#: Largest ``|e_i|`` of ``x(0)`` in the tube at ``t = 0``: near the tube's edge law (13)
#: is so steep that the first sampled step overshoots (measured: at ``|e| ~ 1`` the
#: first input was 1e8 and the state left the arena in one period).
MAX_INITIAL_ERROR = 0.5
#: Obstacles are inflated by this fraction of ``delta_B`` to compute overlap windows.
WINDOW_INFLATION = 0.5
#: Circumvent sharpness values ``k^j`` the automatic choice picks from, sharpest first.
SHARPNESS_LADDER = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0)
#: Ladder values tried per circumvent, from the sharpest that passes the quick estimate.
AUTO_SHARPNESS_TRIES = 3
#: The quick estimate's tube width, as a fraction of the reach tube's (the adaptive
#: tube is narrower where it circumvents).
AUTO_WIDTH_FRACTION = 0.25
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


@dataclass(frozen=True)
class TubeCheck:
    """Outcome of :func:`check_tube` on a time grid.

    Attributes
    ----------
    passed : bool
    reason : str
        Empty when passed, else the first failed condition in words.
    min_width : float
        Certified lower bound of ``min_t min_i gamma_d_i(t)``, state units.
    min_clearance : float
        Certified smallest separation of the tube box from an obstacle it must avoid
        (positive: clear), state units; ``inf`` without obstacles.
    max_move_ratio : float
        Largest ``|gamma_dot| dt / gamma_d`` on the grid.
    initial_error : float
        ``max_i |e_i|`` of ``x(0)`` in the tube at ``t = 0``.
    certificate : Certificate
        The continuous-time certificate behind the verdict.
    """

    passed: bool
    reason: str
    min_width: float
    min_clearance: float
    max_move_ratio: float
    initial_error: float
    certificate: Certificate


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
    margins = {m.name: m for m in certificate.margins}
    clearances = [m.margin for m in certificate.margins if m.name.startswith("avoids")]
    initial_error = certificate.initial_error
    max_ratio = certificate.max_move_ratio

    def result(reason: str) -> TubeCheck:
        return TubeCheck(not reason, reason, certificate.min_width,
                         min(clearances, default=math.inf), max_ratio, initial_error,
                         certificate)

    if certificate.decisive:               # fails for certain at some instant
        failure = certificate.first_failure()
        return result(f"{failure.name} fails: {failure.detail}")
    if not margins["sampling rate"].passed:  # first: a tube this fast also fails the rest
        also = ("" if margins["non-empty"].passed else
                f"; non-empty fails too: {margins['non-empty'].detail}")
        return result(f"{margins['sampling rate'].detail}; a larger "
                      f"tube.circumvent_sharpness or controller.rate_hz helps{also}")
    if not margins["non-empty"].passed:
        return result(f"non-empty fails: {margins['non-empty'].detail}")
    if initial_error > MAX_INITIAL_ERROR and margins["initial state inside"].passed:
        return result(f"x(0) starts at |e| = {initial_error:.3g} of the tube's half-width "
                      f"at t = 0 (limit {MAX_INITIAL_ERROR}): the first sampled steps would "
                      "overshoot")
    failure = certificate.first_failure()
    if failure is not None:
        return result(f"{failure.name} fails: {failure.detail}")
    return result("")


# --------------------------------------------------------------------------- windows


def dimension_interval(design: TubeDesign, box: Box, i: int,
                       margin: float) -> tuple[float, float] | None:
    """Interval of ``s`` in ``[0, 1]`` where the reach tube's projection on ``i`` meets ``box``'s.

    ``rho_L_i(s) <= upper_i + margin`` and ``rho_U_i(s) >= lower_i - margin`` are linear
    in ``s`` (eq. (4)); ``None`` when they never hold together.
    """
    lo, hi = 0.0, 1.0
    x_l, x_u = design.initial_lower[i], design.initial_upper[i]
    for a, slope, bound, sign in ((x_l, design.target_lower[i] - x_l, box.upper[i] + margin, 1),
                                  (x_u, design.target_upper[i] - x_u, box.lower[i] - margin, -1)):
        a, slope, bound = sign * a, sign * slope, sign * bound  # a + slope s <= bound
        if slope == 0:
            if a > bound:
                return None
            continue
        limit = (bound - a) / slope
        if slope > 0:
            hi = min(hi, limit)
        else:
            lo = max(lo, limit)
    return (lo, hi) if lo <= hi else None


def overlap_interval(design: TubeDesign, box: Box, margin: float) -> tuple[float, float] | None:
    """Interval of ``s = tanh(t/(t_c - t))`` in ``[0, 1]`` where the reach tube box meets ``box``.

    The robust reading of eq. (5): the intersection over dimensions of
    :func:`dimension_interval`, with ``box`` inflated by ``margin``. ``None`` when the
    tube never meets the inflated box.
    """
    lo, hi = 0.0, 1.0
    for i in range(design.dimension):
        interval = dimension_interval(design, box, i, margin)
        if interval is None:
            return None
        lo, hi = max(lo, interval[0]), min(hi, interval[1])
    return (lo, hi) if lo <= hi else None


def progress_time(design: TubeDesign, s: float) -> float:
    """Inverse of ``s = tanh(t/(t_c - t))``: ``t = t_c a / (1 + a)``, ``a = atanh(s)``."""
    if s >= 1.0:
        return design.prescribed_time
    a = math.atanh(max(s, 0.0))
    return design.prescribed_time * a / (1.0 + a)


def candidates(design: TubeDesign, spec: Spec, j: int, delta_b: float) -> list[Circumvent]:
    """The circumvents that could avoid obstacle box ``j``, best first (deterministic order).

    Order: dimensions where the reach tube overlaps the obstacle's projection for the
    longest part of ``[0, 1]`` in ``s`` first, then the side that needs the bound to
    move least at the middle of the window, then dimension index.
    """
    box = spec.obstacle_boxes()[j]
    margin = WINDOW_INFLATION * delta_b
    interval = overlap_interval(design, box, margin)
    if interval is None:
        return []
    t1, t2 = (progress_time(design, s) for s in interval)
    mid = np.array([0.5 * (t1 + t2)])
    rho_l, rho_u, _, _ = reference.reach_tube(design, mid)
    result = []
    for i in range(design.dimension):
        lo_x, hi_x = spec.state_space.lower[i], spec.state_space.upper[i]
        if box.lower[i] <= lo_x and box.upper[i] >= hi_x:
            continue  # the obstacle spans this dimension
        interval_i = dimension_interval(design, box, i, margin)
        span = 0.0 if interval_i is None else interval_i[1] - interval_i[0]
        for side in (LOWER, UPPER):
            if side == LOWER:
                peak = box.upper[i] + delta_b
                if peak >= hi_x:
                    continue
                base, height = lo_x, peak - lo_x
                move = max(0.0, peak - float(rho_l[0, i]))
            else:
                peak = box.lower[i] - delta_b
                if peak <= lo_x:
                    continue
                base, height = hi_x, hi_x - peak
                move = max(0.0, float(rho_u[0, i]) - peak)
            width = float(np.min(rho_u[0] - rho_l[0]))
            for rank_k, k in enumerate(_sharpness_options(spec, height, delta_b, t1, t2,
                                                          width, design.rate_hz)):
                radius, center = _window(height, delta_b, k, t1, t2)
                result.append((-span, move, i, 0 if side == LOWER else 1, rank_k,
                               Circumvent(j, i, side, center - radius, center + radius,
                                          height, base, k)))
    result.sort(key=lambda r: r[:5])
    return [r[-1] for r in result]


def _window(height: float, delta_b: float, k: float, t1: float, t2: float):
    """Half-width and centre of the bump window: within ``delta_b / 2`` of the peak on [t1, t2]."""
    level = (height - 0.5 * delta_b) / height
    z = math.sqrt(-math.log(level) / (k - math.log(level)))
    return max(0.5 * (t2 - t1), 1e-9) / z, 0.5 * (t1 + t2)


def bump_rate_peak(k: float, radius: float) -> float:
    """``sup_t |b_dot|`` of the bump (7)-(8), 1/s (``verify.lemma.bump_rate_bound``)."""
    q = ((1.0 - k) + math.sqrt((1.0 - k) ** 2 + 3.0)) / 3.0
    return 2.0 * k / radius * math.sqrt(q) / (1.0 - q) ** 2 * math.exp(-k * q / (1.0 - q))


def _sharpness_options(spec: Spec, height: float, delta_b: float, t1: float, t2: float,
                       width: float, rate_hz: float) -> list[float]:
    """``k^j`` values to try, best first: the spec's, or the automatic ladder.

    Automatic: the sharpest value of :data:`SHARPNESS_LADDER` whose bump moves the bound
    by at most ``MAX_MOVE_PER_SAMPLE`` of :data:`AUTO_WIDTH_FRACTION` of the reach tube's
    width per sampling period (a quick necessary estimate), then the next
    :data:`AUTO_SHARPNESS_TRIES` - 1 smoother ones: the certificate's sampling-rate check
    decides among them.
    """
    if spec.tube.circumvent_sharpness is not None:
        return [spec.tube.circumvent_sharpness]
    limit = MAX_MOVE_PER_SAMPLE * AUTO_WIDTH_FRACTION * width * rate_hz
    first = len(SHARPNESS_LADDER) - 1
    for q, k in enumerate(SHARPNESS_LADDER):
        radius, _ = _window(height, delta_b, k, t1, t2)
        if height * bump_rate_peak(k, radius) <= limit:
            first = q
            break
    return list(SHARPNESS_LADDER[first:first + AUTO_SHARPNESS_TRIES])


# --------------------------------------------------------------------------- the search


def base_design(spec: Spec, gain: float = 1.0) -> TubeDesign:
    """The design without circumvents, from the spec's boxes and parameters."""
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


def design_tube(spec: Spec) -> Design:
    """Design the spatiotemporal tube of a spec and certify it.

    ``spec.tube.method`` picks the reach tube: ``"paper"`` (one ``tanh`` segment, eq. (4),
    with circumvents (7)-(9), :func:`paper_design`), ``"via"`` (via-point segments,
    :mod:`stt_codegen.design.via`) or ``"auto"`` (the paper's, else via points).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    Design
        The tube with its gain (the spec's ``controller.gain``, or
        :func:`~stt_codegen.design.gain.derived_gain` at the certified narrowest width),
        the method used, its check and certificate (every ``t >= 0``) and the design's
        wall time in seconds.

    Raises
    ------
    DesignError
        No tube of the allowed methods passes :func:`check_tube`; the message gives the
        reason (for via points: where the free passage is too narrow).
    """
    started = time.perf_counter()
    base = base_design(spec)
    method = spec.tube.method
    # "auto": the paper's search on a short budget, then via points, then the paper's
    # search on its full budget (a hard arena rarely needs it)
    full = (METHOD_PAPER, MAX_CANDIDATE_CHECKS, None)
    stages = {"paper": [full], "via": [(METHOD_VIA, 0, None)],
              "auto": [(METHOD_PAPER, AUTO_CANDIDATE_CHECKS, AUTO_CANDIDATE_INTERVALS),
                       (METHOD_VIA, 0, None), full]}[method]
    errors: dict[str, str] = {}
    for used, budget, work in stages:
        if used in errors and "candidate tubes" not in errors[used]:
            continue          # the paper's search ended for another reason than its budget
        try:
            tube, check = (_via(spec, base) if used == METHOD_VIA
                           else paper_design(spec, base, budget, work))
            break
        except DesignError as exc:
            errors[used] = str(exc)
    else:
        if len(errors) == 1:
            raise DesignError(next(iter(errors.values())))
        raise DesignError(f"{errors[METHOD_PAPER]}; with via points: {errors[METHOD_VIA]}")
    gain = (spec.gain if spec.gain is not None
            else derived_gain(check.min_width, tube.rate_hz, spec.assumptions))
    return Design(replace(tube, gain=gain), used, check, time.perf_counter() - started,
                  spec=spec)


def _via(spec: Spec, base: TubeDesign) -> tuple[TubeDesign, TubeCheck]:
    tube = via_design(spec, base)
    check = check_tube(tube, spec)
    if not check.passed:
        raise DesignError(f"the via-point tube fails its check: {check.reason}")
    return tube, check


def paper_design(spec: Spec, base: TubeDesign, max_checks: int = MAX_CANDIDATE_CHECKS,
                 max_work: int | None = None) -> tuple[TubeDesign, TubeCheck]:
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

    Returns
    -------
    tube : TubeDesign
        ``base`` with the circumvents chosen (gain not yet set).
    check : TubeCheck

    Raises
    ------
    DesignError
        No choice of circumvents passes :func:`check_tube` (or ``max_checks`` candidates
        or ``max_work`` intervals were used up).
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
                              "the target box eta +- d_T: shrink target.half_width")
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
                              f"room of delta_b = {delta_b:g} beside it")
        options[j] = [tuple(per_box[b][key] for b in members) for key in keys]
    order = sorted(options, key=lambda j: (starts[j], j))
    failures: dict[int, str] = {}
    budget: list[float] = [max_checks, math.inf if max_work is None else max_work]

    def check(design: TubeDesign, **kwargs) -> TubeCheck:
        if budget[0] <= 0 or budget[1] <= 0:
            raise DesignError(f"no certified circumvents within {max_checks} candidate tubes"
                              + ("" if max_work is None else f" and {max_work} intervals of "
                                 "certificate work") + " (" + "; ".join(
                                  f"obstacle {j}: {r}" for j, r in sorted(failures.items()))
                              + ")")
        budget[0] -= 1
        found = check_tube(design, spec,
                           max_intervals=int(min(CANDIDATE_INTERVALS, budget[1])), **kwargs)
        budget[1] -= found.certificate.work
        return found

    def search(level: int, chosen: tuple[Circumvent, ...],
               parent: TubeCheck | None) -> tuple[TubeDesign, TubeCheck] | None:
        if level == len(order):
            design = replace(base, circumvents=_ordered(chosen))
            # the same tube as the last partial check: resume all of it
            accepted = check(design, resume=None if parent is None
                             else (parent.certificate, math.inf))
            return (design, accepted) if accepted.passed else None
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
                failures.setdefault(j, partial.reason)
                if not partial.reason.startswith("a tube bound moves"):
                    hopeless.add(side)   # a smoother bump only helps the sampling rate
                continue
            found = search(level + 1, chosen + option, partial)
            if found is not None:
                return found
        return None

    found = search(0, (), None)
    if found is None:
        if not order:
            raise DesignError(f"the reach tube fails its check: {check_tube(base, spec).reason}")
        detail = "; ".join(f"obstacle {j}: {r}" for j, r in sorted(failures.items()))
        raise DesignError("no choice of circumvent dimension and side passes the tube "
                          f"check ({detail or 'the final check failed'})")
    return found
