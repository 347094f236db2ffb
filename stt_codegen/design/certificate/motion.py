"""The certificate's property for moving obstacles: the tube misses each one at every ``t``.

For a moving obstacle (:class:`~stt_codegen.spec.motion.MovingObstacle`) the property is
space-time disjointness: for every ``t`` in its ``active`` interval, the tube box
``[gamma_L(t), gamma_U(t)]`` and the obstacle's box at ``t`` do not meet. On an interval
``[t_a, t_b]`` of the certificate's partition the tube lies in the enclosure
``[lower_min, upper_max]`` (:class:`~.report.Enclosure`) and the obstacle lies in the hull
of its positions over ``[t_a, t_b]`` met with ``active``
(:meth:`~stt_codegen.spec.motion.MovingObstacle.hull`: the centre is piecewise linear, so
its range is attained at the interval's ends and at the knots inside); if the two boxes are
separated along some dimension of the obstacle, the property holds on the whole interval.
The margin is that separation. Where it is not positive, the interval is cut (as
:mod:`.refine` does, in sample indices) and ``alpha``'s bounds are followed again on the
cuts only (:func:`~.repropagate.repropagate`); the loop stops when every moving obstacle is
proven, at single-sample intervals, at :data:`MOTION_INTERVALS`, or as soon as the tube
certainly meets an obstacle at an instant (:func:`_surely_meets`).

Argument and limits: docs/moving-obstacles.md.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...spec.loader import Spec
from ...tube import reference
from ...tube.parameters import TubeDesign
from .enclosures import enclose, partition
from .report import ROUNDING_MARGIN, Certificate, CertificateState, Enclosure, Margin
from .repropagate import repropagate
from .tasks import reach_certified_by

__all__ = ["MOTION_INTERVALS", "MOTION_SPLIT", "MOVING_PROPERTY", "certify_motion",
           "cut_enclosure", "until_ended"]

#: Most intervals the refinement for moving obstacles may create (its own budget, on top
#: of the partition the rest of the certificate proved).
MOTION_INTERVALS = 50_000
#: A thin interval is cut into this many pieces.
MOTION_SPLIT = 4
#: Name of the property, followed by the spec's obstacle index.
MOVING_PROPERTY = "avoids moving obstacle"


def moving_separation(spec: Spec, enc: Enclosure) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Separation of the tube's enclosure from each moving obstacle, per interval.

    Returns
    -------
    list of (int, ndarray (K,), ndarray (K,) of int)
        Per moving obstacle (spec order): its spec index ``j``, the separation on each
        interval of ``enc`` (state units; ``inf`` where the obstacle is not active), and
        the state dimension along which it is largest.
    """
    out = []
    for obstacle in spec.moving_obstacles:
        lo, hi, present = obstacle.hull(enc.t_start, enc.t_end)
        dims = list(obstacle.dims)
        gaps = np.maximum(lo - enc.upper_max[:, dims], enc.lower_min[:, dims] - hi)
        best = np.argmax(gaps, axis=1)
        sep = np.where(present, gaps.max(axis=1), np.inf)
        out.append((obstacle.source, sep, np.array(dims)[best]))
    return out


def until_ended(design: TubeDesign, spec: Spec, enc: Enclosure) -> tuple[Spec, dict[int, str]]:
    """``spec`` with each obstacle until a task (``MovingObstacle.until``) ended where the
    tube is certified to have met the task (:func:`~.tasks.reach_certified_by`): every run
    inside the tube has met it by then, so the box no longer exists for it. An obstacle
    whose task is not certified met keeps its ``active`` (the end of the task's window).

    Parameters
    ----------
    design : TubeDesign
    spec : Spec
        Its ``moving_obstacles`` and ``tasks``.
    enc : Enclosure
        The certificate's enclosure.

    Returns
    -------
    spec : Spec
        The same spec, each such obstacle's ``active`` ending at its task's time.
    notes : dict of int to str
        Per obstacle index, the words its margin's detail ends with.
    """
    if all(ob.until is None for ob in spec.moving_obstacles):
        return spec, {}
    notes, kept = {}, []
    for ob in spec.moving_obstacles:
        if ob.until is not None:
            task = spec.tasks[ob.until]
            met = reach_certified_by(design, task, enc)
            if met is not None:
                ob = ob.ended_at(met)
                notes[ob.source] = (f"; it exists until {task.label} is met, which the tube "
                                    f"certifies by t = {met:.4f} s")
            else:
                notes[ob.source] = (f"; it exists until {task.label} is met, at the latest "
                                    f"at the end of its window, {ob.active[1]:g} s")
        kept.append(ob)
    return replace(spec, moving_obstacles=tuple(kept)), notes


def cut_enclosure(design: TubeDesign, points: list[int], state: CertificateState
                  ) -> tuple[Enclosure, CertificateState]:
    """The enclosure on a cut partition, ``alpha`` followed from ``state`` on the cuts only.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    points : list of int
        The cut partition's sample indices (every point of ``state`` among them).
    state : CertificateState
        A proven partition's ``alpha`` bounds.

    Returns
    -------
    enc : Enclosure
        The tube on the cut partition.
    state : CertificateState
        Its ``alpha`` bounds (to cut again).
    """
    part = partition(design, points)
    state, _ = repropagate(design, part.pieces, points, part.steps, state)
    a_min = np.maximum(np.array(state.alpha_lo), 0.0)
    enc = enclose(design, part.pieces, a_min, np.array(state.alpha_hi), part.t0, part.t1)
    return enc, state


def _surely_meets(design: TubeDesign, spec: Spec, enc: Enclosure, state: CertificateState,
                  bad: np.ndarray) -> bool:
    """Whether the tube certainly meets a moving obstacle at the start of a ``bad`` interval.

    With ``alpha >= alpha_lo`` there, the tube box contains the box for ``alpha_lo``
    (``gamma_L`` falls and ``gamma_U`` rises with ``alpha``); if that box meets the
    obstacle's box at that instant, no refinement can prove the property.
    """
    k = np.flatnonzero(bad & np.isfinite(enc.t_start))
    t = enc.t_start[k]
    a_min = np.maximum(np.array(state.alpha_lo)[k], 0.0)
    g_l, g_u, _, _ = reference.adaptive_tube(design, t, a_min)
    for ob in spec.moving_obstacles:
        d = list(ob.dims)
        centre, half = ob.centre(t), np.array(ob.half_size)
        meets = ob.is_active(t) & np.all((g_l[:, d] < centre + half)
                                         & (g_u[:, d] > centre - half), axis=1)
        if meets.any():
            return True
    return False


def certify_motion(design: TubeDesign, spec: Spec, certificate: Certificate,
                   max_intervals: int = MOTION_INTERVALS) -> Certificate:
    """``certificate`` with one property per moving obstacle of ``spec``, proven for every ``t``.

    Parameters
    ----------
    design : TubeDesign
        The tube the certificate is of.
    spec : Spec
        Its ``moving_obstacles`` (none: ``certificate`` is returned unchanged).
    certificate : Certificate
        From :func:`~.refine.certify_tube` on ``design``: its partition and ``alpha``
        bounds are the start of the refinement.
    max_intervals : int
        Refinement budget; past it the obstacles not yet proven fail.

    Returns
    -------
    Certificate
        The same, with ``avoids moving obstacle j`` margins (state units: the smallest
        separation of the tube from the obstacle's hull over an interval; positive means
        proven) inserted after the static obstacles'.
    """
    if not spec.moving_obstacles:
        return certificate
    spec, until = until_ended(design, spec, certificate.enclosure)
    with reference.numpy_math():
        enc, state = certificate.enclosure, certificate.state
        points = list(state.points)
        budget_hit = False
        while True:
            seps = moving_separation(spec, enc)
            bad = np.zeros(enc.t_start.size, dtype=bool)
            for _, sep, _ in seps:
                bad |= sep <= ROUNDING_MARGIN
            if not bad.any() or _surely_meets(design, spec, enc, state, bad):
                break
            i0 = np.array(points)
            length = np.append(i0[1:] - i0[:-1], 0)
            split = bad & (length >= 2)
            if not split.any():
                break
            if len(points) + (MOTION_SPLIT - 1) * int(split.sum()) > max_intervals:
                budget_hit = True
                break
            cuts = {int(a + (b * q) // MOTION_SPLIT) for a, b in zip(i0[split], length[split])
                    for q in range(1, MOTION_SPLIT)}
            points = sorted(set(points) | cuts)
            enc, state = cut_enclosure(design, points, state)
    note = (f" (the refinement budget of {max_intervals} intervals was exhausted)"
            if budget_hit else "")
    margins = []
    for j, sep, along in seps:
        k = int(np.argmin(sep))
        m, t = float(sep[k]), float(enc.t_start[k])
        if np.isinf(m):
            detail = f"moving obstacle {j} is never active while the tube exists"
        elif m > ROUNDING_MARGIN:
            detail = (f"separation from moving obstacle {j} (its hull over each interval) "
                      f">= {m:.6g} along dimension {int(along[k])} (interval at t = {t:.4f} s; "
                      f"{enc.t_start.size} intervals)")
        else:
            detail = (f"the tube may meet moving obstacle {j} on [{t:.4f}, "
                      f"{float(enc.t_end[k]):.4f}] s (separation {m:.3g})" + note)
        margins.append(Margin(f"{MOVING_PROPERTY} {j}", m > ROUNDING_MARGIN, m, t,
                              detail + until.get(j, "")))
    old = list(certificate.margins)
    at = max((q + 1 for q, mg in enumerate(old) if mg.name.startswith("avoids")),
             default=next(q + 1 for q, mg in enumerate(old) if mg.name == "inside state space"))
    return replace(certificate, margins=tuple(old[:at] + margins + old[at:]))
