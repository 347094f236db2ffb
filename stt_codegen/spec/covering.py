"""Cover a convex unsafe set by boxes (Remark 3.1: relaxing Assumption 3 by splitting).

:func:`cover` returns boxes whose union contains the shape, each missing the forbidden
boxes (the initial and target sets), and none reaching farther than ``tolerance`` from
the shape (the union's one-sided Hausdorff distance to the shape is at most
``tolerance``). Deterministic: a depth-first bisection of the longest side, lower half
first; at most :data:`MAX_BOXES` boxes per shape.

Why the bound holds: for a convex set the distance function is convex, so its maximum
over a box is attained at a corner; a box is accepted only when all its corners lie
within ``tolerance`` of the shape. Containment holds because every split keeps, for each
half, the smallest box that contains the shape's part in that half (``shape.box_hull``:
closed form for a ball; exact for a polygon, from its edges' crossings of the box's
sides, widened by a rounding margin; linear programs for polytopes in three or four
dimensions).

Then the accepted boxes are merged (:func:`_merge`): each absorbs one of the last
:data:`MERGE_WINDOW` kept boxes it touches when the hull of the shape's part in their
bounding box is again acceptable (within ``tolerance`` at its corners, missing the
forbidden boxes); about a third fewer boxes for polygons, hence fewer obstacles for the
design.

Cost: one box hull and one corner-distance evaluation per visited box, at most
``2 MAX_BOXES + 1`` visits per shape, and at most ``MERGE_WINDOW`` per box and merge when
merging; for a polygon both are a few numpy operations on its edges. A refusal costs one
more covering, without the forbidden boxes, to tell its reason: a tolerance too fine for
the shape's size, or a shape too close to the initial or target set.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from ..errors import SpecError

__all__ = ["MAX_BOXES", "MERGE_WINDOW", "cover"]

#: At most this many boxes per shape (counted before merging).
MAX_BOXES = 256
#: A box may merge with one of this many boxes accepted just before it.
MERGE_WINDOW = 8


def _corner_distance(shape, lo: np.ndarray, hi: np.ndarray) -> float:
    """Largest distance from a corner of ``[lo, hi]`` to the shape."""
    if hasattr(shape, "radius"):
        # the farthest corner from the centre, per axis the farther end: O(k), not 2^k
        # corners (a ball may live in all MAX_DIMENSION dimensions)
        c = np.array(shape.center)
        far = np.where(np.abs(lo - c) >= np.abs(hi - c), lo, hi)
        return float(shape.distance(far[None, :]).max())
    # a polytope has k <= MAX_POLYTOPE_DIMENSION coordinates: its 2^k corners, at once
    return float(shape.distance(np.array(list(itertools.product(*zip(lo, hi))))).max())


class _OverBudget(Exception):
    """More than :data:`MAX_BOXES` boxes; ``met`` the forbidden boxes that forced splits."""

    def __init__(self, met: set[int]) -> None:
        super().__init__()
        self.met = met


def _bisect(shape, tolerance: float,
            forbidden: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The covering: depth-first bisection of the longest side, lower half first."""
    lower, upper = np.array(shape.lower, float), np.array(shape.upper, float)
    accepted: list[tuple[np.ndarray, np.ndarray]] = []
    met: set[int] = set()
    stack = [(lower, upper)]
    while stack:
        lo, hi = stack.pop()
        hull = shape.box_hull(lo, hi)
        if hull is None:
            continue
        lo, hi = hull
        meets = [j for j, (f_lo, f_hi) in enumerate(forbidden)
                 if np.all(lo <= f_hi) and np.all(f_lo <= hi)]
        met.update(meets)
        if not meets and _corner_distance(shape, lo, hi) <= tolerance:
            accepted.append((lo, hi))
            continue
        if len(accepted) + len(stack) + 2 > MAX_BOXES:
            raise _OverBudget(met)
        axis = int(np.argmax(hi - lo))
        mid = 0.5 * (lo[axis] + hi[axis])
        upper_half_lo = lo.copy()
        upper_half_lo[axis] = mid
        lower_half_hi = hi.copy()
        lower_half_hi[axis] = mid
        stack.append((upper_half_lo, hi))       # popped second
        stack.append((lo, lower_half_hi))       # popped first: lower half first
    return accepted


def _acceptable(shape, lo: np.ndarray, hi: np.ndarray, tolerance: float,
                forbidden: Sequence[tuple[np.ndarray, np.ndarray]]) -> bool:
    return (not any(np.all(lo <= f_hi) and np.all(f_lo <= hi) for f_lo, f_hi in forbidden)
            and _corner_distance(shape, lo, hi) <= tolerance)


def _merge(shape, boxes: list[tuple[np.ndarray, np.ndarray]], tolerance: float,
           forbidden: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Fewer boxes: each box, in order, absorbs one of the last :data:`MERGE_WINDOW` kept
    boxes it touches while the hull of the shape's part in their bounding box is
    acceptable.

    Sound: that hull contains the shape's part in both boxes, and the accepted boxes'
    union contains the shape.
    """
    kept: list[tuple[np.ndarray, np.ndarray]] = []
    for box in boxes:
        merged = True
        while merged and kept:
            merged = False
            for k in range(1, min(MERGE_WINDOW, len(kept)) + 1):
                if not (np.all(kept[-k][0] <= box[1]) and np.all(box[0] <= kept[-k][1])):
                    continue                    # apart: their bounding box spans a gap
                hull = shape.box_hull(np.minimum(kept[-k][0], box[0]),
                                      np.maximum(kept[-k][1], box[1]))
                if hull is not None and _acceptable(shape, *hull, tolerance, forbidden):
                    del kept[-k]
                    box, merged = hull, True
                    break
        kept.append(box)
    return kept


def _fits(shape, tolerance: float, forbidden) -> bool:
    try:
        _bisect(shape, tolerance, forbidden)
    except _OverBudget:
        return False
    return True


def cover(shape, tolerance: float, forbidden: Sequence[tuple[np.ndarray, np.ndarray]],
          name: str = "obstacle",
          forbidden_names: Sequence[str] = ("the initial set", "the target set"),
          ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Boxes covering ``shape``, each within ``tolerance`` of it and missing ``forbidden``.

    Parameters
    ----------
    shape : Ball or Polytope
        In ``k`` dimensions.
    tolerance : float
        Largest distance from a point of the union to the shape, state units, positive.
    forbidden : list of (lower, upper)
        ``k``-dimensional boxes no covering box may meet (touching counts).
    name : str
        The obstacle's field name, for errors (``"obstacles[3]"``).
    forbidden_names : list of str
        What each forbidden box is, for errors.

    Returns
    -------
    list of (lower, upper)
        ``k``-dimensional boxes, in a deterministic order.

    Raises
    ------
    SpecError
        Field ``name``: more than :data:`MAX_BOXES` boxes would be needed, either because
        the tolerance is too fine for the shape's size (the message gives a tolerance that
        fits) or because the shape comes too close to a forbidden box (the message names
        it).
    """
    try:
        return _merge(shape, _bisect(shape, tolerance, forbidden), tolerance, forbidden)
    except _OverBudget as over:
        met = over.met
    what = "ball" if hasattr(shape, "radius") else "polytope"
    # the reason: without the forbidden boxes, does the covering fit? (one more covering)
    if not met or not _fits(shape, tolerance, []):
        raise SpecError(name, f"no covering by at most {MAX_BOXES} boxes stays within "
                              f"tolerance {tolerance:g} of the {what}: the tolerance is too "
                              f"fine for its size (raise {name}.tolerance)")
    near = " and ".join(forbidden_names[j] if j < len(forbidden_names) else
                        f"forbidden box {j}" for j in sorted(met))
    raise SpecError(name, f"no covering by at most {MAX_BOXES} boxes within tolerance "
                          f"{tolerance:g} misses {near}: the {what} comes too close to "
                          f"it for that tolerance")
