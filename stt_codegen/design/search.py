"""Design of the spatiotemporal tube for a spec: windows (5), circumvent choices (6), gain.

The paper leaves several points open or, read literally, fails (see the README's
"Decisions" section). This module decides them deterministically:

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
  narrowest point (see :func:`default_gain`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..tube import reference
from .certificate import Certificate, certify_tube
from ..errors import DesignError
from ..spec.loader import Box, Spec
from ..tube.parameters import LOWER, UPPER, Circumvent, TubeDesign
from .samples import TubeSamples, sample_tube

#: Largest distance a tube bound may move in one sampling period, as a fraction of the
#: tube's width there: a sampled controller cannot follow a faster tube.
MAX_MOVE_PER_SAMPLE = 0.25
#: Largest ``|e_i|`` of ``x(0)`` in the tube at ``t = 0``: near the tube's edge law (13)
#: is so steep that the first sampled step overshoots (measured: at ``|e| ~ 1`` the
#: first input was 1e8 and the state left the arena in one period).
MAX_INITIAL_ERROR = 0.5
#: Obstacles are inflated by this fraction of ``delta_B`` to compute overlap windows.
WINDOW_INFLATION = 0.5


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
               samples: TubeSamples | None = None, final: bool = True) -> TubeCheck:
    """Check a designed tube: the continuous-time certificate and the sampling limit.

    Conditions, in order: no bound moves more than ``MAX_MOVE_PER_SAMPLE`` of the tube
    width in one sampling period; ``x(0)`` starts with ``|e_i| <= MAX_INITIAL_ERROR``
    (room for the first sampled steps); and every property of
    :func:`~stt_codegen.design.certificate.certify_tube` (non-empty, ``x(0)`` inside, inside the
    state space, missing each listed obstacle and, with ``final``, inside the target from
    ``t_c`` on) holds for all ``t``.

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
    obstacles : list of int, optional
        Indices of the obstacles to check against; default all.
    samples : TubeSamples, optional
        Precomputed :func:`~stt_codegen.design.samples.sample_tube` output.
    final : bool

    Returns
    -------
    TubeCheck
    """
    s = samples if samples is not None else sample_tube(design)
    certificate = certify_tube(design, spec, obstacles=obstacles, samples=s)
    dt = 1.0 / design.rate_hz
    width = s.gamma_upper - s.gamma_lower
    move = np.maximum(np.abs(s.gamma_lower_dot), np.abs(s.gamma_upper_dot)) * dt
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(width > 0, move / width, np.inf)
    max_ratio = float(ratio.max())
    margins = {m.name: m for m in certificate.margins}
    clearances = [m.margin for m in certificate.margins if m.name.startswith("avoids")]
    x0 = np.array(design.initial_state)
    with np.errstate(divide="ignore", invalid="ignore"):
        e0 = (2 * x0 - (s.gamma_upper[0] + s.gamma_lower[0])) / width[0]
    initial_error = float(np.max(np.abs(e0))) if np.all(width[0] > 0) else math.inf

    def result(reason: str) -> TubeCheck:
        return TubeCheck(not reason, reason, margins["non-empty"].margin,
                         min(clearances, default=math.inf), max_ratio, initial_error,
                         certificate)

    if not np.all(width > 0):  # empty at a sample: the rate ratio is meaningless
        return result(f"non-empty fails: {margins['non-empty'].detail}")
    if max_ratio > MAX_MOVE_PER_SAMPLE:  # next: a tube this fast also fails the rest
        k = int(np.argmax(ratio.max(axis=1)))
        return result(f"a tube bound moves {max_ratio:.2f} tube widths in one sampling "
                      f"period at t = {s.t[k]:.3f} s (limit {MAX_MOVE_PER_SAMPLE}; a larger "
                      "tube.circumvent_sharpness or controller.rate_hz helps)")
    if initial_error > MAX_INITIAL_ERROR and margins["initial state inside"].passed:
        return result(f"x(0) starts at |e| = {initial_error:.3g} of the tube's half-width "
                      f"at t = 0 (limit {MAX_INITIAL_ERROR}): the first sampled steps would "
                      "overshoot")
    for margin in certificate.margins:
        if margin.name == "inside target after t_c" and not final:
            continue
        if not margin.passed:
            return result(f"{margin.name} fails: {margin.detail}")
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
    k = design.circumvent_sharpness
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
            # widen [t1, t2] so that the bump is within delta_b / 2 of its peak there
            level = (height - 0.5 * delta_b) / height
            z = math.sqrt(-math.log(level) / (k - math.log(level)))
            radius = max(0.5 * (t2 - t1), 1e-9) / z
            center = 0.5 * (t1 + t2)
            result.append((-span, move, i, 0 if side == LOWER else 1,
                           Circumvent(j, i, side, center - radius, center + radius, height,
                                      base)))
    result.sort(key=lambda r: r[:4])
    return [r[-1] for r in result]


# --------------------------------------------------------------------------- the search


def base_design(spec: Spec, gain: float = 1.0) -> TubeDesign:
    """The design without circumvents, from the spec's boxes and parameters."""
    x0, d0 = spec.initial_state, spec.initial_half_width
    eta, d_t = spec.target_center, spec.target_half_width
    return TubeDesign(
        name=spec.name, prescribed_time=spec.prescribed_time,
        state_lower=spec.state_space.lower, state_upper=spec.state_space.upper,
        initial_lower=tuple(a - b for a, b in zip(x0, d0)),
        initial_upper=tuple(a + b for a, b in zip(x0, d0)),
        target_lower=tuple(a - b for a, b in zip(eta, d_t)),
        target_upper=tuple(a + b for a, b in zip(eta, d_t)),
        initial_state=x0, circumvents=(),
        circumvent_sharpness=spec.tube.circumvent_sharpness,
        smoothness=spec.tube.smoothness, theta0=spec.tube.theta0, kappa=spec.tube.kappa,
        mu=spec.tube.mu, gain=gain, rate_hz=spec.rate_hz)


def _ordered(circumvents) -> tuple[Circumvent, ...]:
    return tuple(sorted(circumvents, key=lambda c: (c.dimension, c.side, c.obstacle)))


def default_gain(design: TubeDesign, samples: TubeSamples) -> float:
    """Default ``k`` of law (13): half the sampled-loop stability limit at the narrowest tube.

    Linearizing the sampled loop of ``x_dot = u`` under law (13) at ``e = 0`` gives
    ``e+ = (1 - 16 k dt / gamma_d^2) e``: stable for ``k < gamma_d^2 / (8 dt)``. The default
    is ``gamma_d,min^2 / (16 dt)``, where ``gamma_d,min`` is the tube's smallest width.
    """
    dt = 1.0 / design.rate_hz
    width = float((samples.gamma_upper - samples.gamma_lower).min())
    return width**2 / (16.0 * dt)


def design_tube(spec: Spec) -> tuple[TubeDesign, TubeCheck]:
    """Design the spatiotemporal tube of a spec.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    design : TubeDesign
        With the circumvents chosen and the gain set (the spec's, or :func:`default_gain`).
    check : TubeCheck
        The accepted design's check.

    Raises
    ------
    DesignError
        No choice of circumvents gives a tube that passes :func:`check_tube`.
    """
    base = base_design(spec)
    boxes = spec.obstacle_boxes()
    delta_b = spec.tube.delta_b
    # one choice of (dimension, side) per spec obstacle: a ball or polytope covered by
    # several boxes (Remark 3.1) is passed on one side by all of them
    groups: dict[int, list[int]] = {}
    starts: dict[int, float] = {}
    per_box: dict[int, dict[tuple[int, str], Circumvent]] = {}
    rank: dict[int, list[tuple[int, str]]] = {}
    for b, box in enumerate(boxes):
        j = spec.obstacles[b].source
        interval = overlap_interval(base, box, WINDOW_INFLATION * delta_b)
        if interval is None:
            continue
        if interval[1] >= 1.0:
            raise DesignError(f"obstacle {j} comes within {WINDOW_INFLATION * delta_b:g} of "
                              "the target box eta +- d_T: shrink target.half_width")
        found_here = candidates(base, spec, b, delta_b)
        per_box[b] = {(c.dimension, c.side): c for c in found_here}
        groups.setdefault(j, []).append(b)
        rank.setdefault(j, [(c.dimension, c.side) for c in found_here])
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

    def search(level: int, chosen: tuple[Circumvent, ...]) -> tuple[TubeDesign, TubeCheck] | None:
        if level == len(order):
            design = replace(base, circumvents=_ordered(chosen))
            check = check_tube(design, spec)
            return (design, check) if check.passed else None
        j = order[level]
        done = [b for k in order[:level + 1] for b in groups[k]]
        for option in options[j]:
            design = replace(base, circumvents=_ordered(chosen + option))
            check = check_tube(design, spec, obstacles=done, final=False)
            if not check.passed:
                failures.setdefault(j, check.reason)
                continue
            found = search(level + 1, chosen + option)
            if found is not None:
                return found
        return None

    found = search(0, ())
    if found is None:
        if not order:
            check = check_tube(base, spec)
            raise DesignError(f"the reach tube fails its check: {check.reason}")
        detail = "; ".join(f"obstacle {j}: {r}" for j, r in sorted(failures.items()))
        raise DesignError("no choice of circumvent dimension and side passes the tube "
                          f"check ({detail or 'the final check failed'})")
    design, check = found
    if spec.gain is not None:
        return replace(design, gain=spec.gain), check
    samples = sample_tube(design)
    from .gain import derived_gain  # the gain follows from the spec's [assumptions]
    return replace(design, gain=derived_gain(samples, design.rate_hz, spec.assumptions)), check
