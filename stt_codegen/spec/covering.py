"""Cover a convex unsafe set by boxes (Remark 3.1: relaxing Assumption 3 by splitting).

:func:`cover` returns boxes whose union contains the shape, each missing the forbidden
boxes (the initial and target sets), and none reaching farther than ``tolerance`` from
the shape (the union's one-sided Hausdorff distance to the shape is at most
``tolerance``). Deterministic: a depth-first bisection, lower half first.

Why the bound holds: for a convex set the distance function is convex, so its maximum
over a box is attained at a corner; a box is accepted only when all its corners lie
within ``tolerance`` of the shape. Containment holds because every split keeps, for each
half, the smallest box that contains the shape's part in that half.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..errors import SpecError

#: At most this many boxes per shape.
MAX_BOXES = 256


def _corner_distance(shape, lo: np.ndarray, hi: np.ndarray) -> float:
    """Largest distance from a corner of ``[lo, hi]`` to the shape."""
    if hasattr(shape, "radius"):
        # the farthest corner from the centre, per axis the farther end: O(k), not 2^k
        # corners (a ball may live in all MAX_DIMENSION dimensions)
        c = np.array(shape.center)
        far = np.where(np.abs(lo - c) >= np.abs(hi - c), lo, hi)
        return float(shape.distance(far[None, :]).max())
    corners = np.array(list(itertools.product(*zip(lo, hi))))
    return max(shape.distance(c) for c in corners)


def cover(shape, tolerance: float, forbidden: list[tuple[np.ndarray, np.ndarray]],
          name: str = "obstacle") -> list[tuple[np.ndarray, np.ndarray]]:
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
        The obstacle's field name, for errors.

    Returns
    -------
    list of (lower, upper)
        ``k``-dimensional boxes, in a deterministic order.

    Raises
    ------
    SpecError
        More than :data:`MAX_BOXES` boxes would be needed (the shape comes too close to a
        forbidden box for the tolerance).
    """
    lower, upper = np.array(shape.lower, float), np.array(shape.upper, float)
    accepted: list[tuple[np.ndarray, np.ndarray]] = []
    stack = [(lower, upper)]
    while stack:
        lo, hi = stack.pop()
        hull = shape.box_hull(lo, hi)
        if hull is None:
            continue
        lo, hi = hull
        clear = not any(np.all(lo <= f_hi) and np.all(f_lo <= hi) for f_lo, f_hi in forbidden)
        if clear and _corner_distance(shape, lo, hi) <= tolerance:
            accepted.append((lo, hi))
            continue
        if len(accepted) + len(stack) + 2 > MAX_BOXES:
            raise SpecError(name, f"no covering by at most {MAX_BOXES} boxes within tolerance "
                                  f"{tolerance:g} misses the initial and target sets")
        axis = int(np.argmax(hi - lo))
        mid = 0.5 * (lo[axis] + hi[axis])
        upper_half_lo = lo.copy()
        upper_half_lo[axis] = mid
        lower_half_hi = hi.copy()
        lower_half_hi[axis] = mid
        stack.append((upper_half_lo, hi))       # popped second
        stack.append((lo, lower_half_hi))       # popped first: lower half first
    return accepted
