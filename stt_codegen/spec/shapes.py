"""Convex unsafe sets that are not boxes: balls and convex polytopes (Remark 3.1).

Each shape lives in the subspace of the dimensions it is given on (``k`` of them) and
spans the state space in the others. All geometry here is in those ``k`` coordinates.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import SpecError

__all__ = ["Ball", "MAX_POLYTOPE_DIMENSION", "Polytope", "make_polytope"]

#: Largest number of coordinates (``dims``) a polytope obstacle may be given on.
MAX_POLYTOPE_DIMENSION = 4
#: Relative widening of an exact box hull (one and two dimensions), against rounding.
ROUNDING = 1e-12


@dataclass(frozen=True)
class Ball:
    """The closed ball ``{y : |y - center| <= radius}``.

    Attributes
    ----------
    center : tuple of float, length k
    radius : float
        Positive, state units.
    """

    center: tuple[float, ...]
    radius: float

    @property
    def lower(self) -> tuple[float, ...]:
        return tuple(c - self.radius for c in self.center)

    @property
    def upper(self) -> tuple[float, ...]:
        return tuple(c + self.radius for c in self.center)

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Euclidean distance from each point (N, k) to the ball; 0 inside."""
        d = np.linalg.norm(np.atleast_2d(points) - np.array(self.center), axis=1)
        return np.maximum(d - self.radius, 0.0)

    def signed_clearance(self, points: np.ndarray) -> np.ndarray:
        """Distance outside, minus the depth inside, shape (N,)."""
        return np.linalg.norm(np.atleast_2d(points) - np.array(self.center), axis=1) - self.radius

    def box_hull(self, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The smallest box containing ``ball ∩ [lower, upper]``, or ``None`` if empty."""
        c = np.array(self.center)
        gap = np.maximum(np.maximum(lower - c, c - upper), 0.0)
        if np.sum(gap**2) > self.radius**2:
            return None
        lo, hi = np.empty_like(c), np.empty_like(c)
        for i in range(c.size):
            others = np.sum(gap**2) - gap[i] ** 2
            reach = math.sqrt(max(self.radius**2 - others, 0.0))
            lo[i] = max(lower[i], c[i] - reach)
            hi[i] = min(upper[i], c[i] + reach)
        return lo, hi

    def meets_box(self, lower: np.ndarray, upper: np.ndarray) -> bool:
        return self.box_hull(np.asarray(lower, float), np.asarray(upper, float)) is not None


@dataclass(frozen=True)
class Polytope:
    """The convex hull of a list of vertices, with its facets ``A y <= b``.

    Attributes
    ----------
    vertices : tuple of tuple of float
        At least ``k + 1`` affinely independent points in ``k`` dimensions.
    """

    vertices: tuple[tuple[float, ...], ...]
    _a: np.ndarray = field(init=False, repr=False, compare=False)
    _b: np.ndarray = field(init=False, repr=False, compare=False)
    _ring: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        points = np.array(self.vertices, dtype=float)
        k = points.shape[1]
        if k == 1:
            a = np.array([[1.0], [-1.0]])
            b = np.array([points.max(), -points.min()])
            ring = points[[points.argmin(), points.argmax()]]
        else:
            from scipy.spatial import ConvexHull   # scipy on first use: box specs never load it
            hull = ConvexHull(points)
            a, b = hull.equations[:, :-1], -hull.equations[:, -1]
            norms = np.linalg.norm(a, axis=1)
            a, b = a / norms[:, None], b / norms
            # in the plane, the hull's vertices in counter-clockwise order (its edges)
            ring = points[hull.vertices] if k == 2 else points
        object.__setattr__(self, "_a", a)
        object.__setattr__(self, "_b", b)
        object.__setattr__(self, "_ring", ring)

    @property
    def halfspaces(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A, b)`` with unit-norm rows: the polytope is ``{y : A y <= b}``."""
        return self._a.copy(), self._b.copy()

    @property
    def lower(self) -> tuple[float, ...]:
        return tuple(np.array(self.vertices).min(axis=0).tolist())

    @property
    def upper(self) -> tuple[float, ...]:
        return tuple(np.array(self.vertices).max(axis=0).tolist())

    def signed_clearance(self, points: np.ndarray) -> np.ndarray:
        """A lower bound of the distance outside (exact off the facets' edges), minus the depth inside.

        ``max_i (a_i . y - b_i)`` with unit normals: the distance to the nearest facet's
        plane, which never exceeds the true distance to the polytope.
        """
        return np.max(np.atleast_2d(points) @ self._a.T - self._b, axis=1)

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Euclidean distance from each point (N, k) (or one point (k,)) to the polytope, (N,).

        Closed form in one and two dimensions (the distance to the nearest edge, all points
        at once); a small convex QP (SLSQP) per point outside in more.
        """
        p = np.atleast_2d(np.asarray(points, dtype=float))
        inside = np.all(p @ self._a.T <= self._b + 1e-12, axis=1)
        k = p.shape[1]
        if k == 1:
            lo, hi = self._ring[0, 0], self._ring[1, 0]
            return np.maximum(np.maximum(lo - p[:, 0], p[:, 0] - hi), 0.0)
        if k == 2:
            a = self._ring
            ab = np.roll(a, -1, axis=0) - a                         # edges (m, 2)
            ap = p[:, None, :] - a[None, :, :]                      # (N, m, 2)
            s = np.clip(np.einsum("nmj,mj->nm", ap, ab) / np.einsum("mj,mj->m", ab, ab),
                        0.0, 1.0)
            gap = ap - s[:, :, None] * ab
            far = np.sqrt(np.min(np.einsum("nmj,nmj->nm", gap, gap), axis=1))
            return np.where(inside, 0.0, far)
        return np.array([0.0 if ok else self._qp_distance(q) for q, ok in zip(p, inside)])

    def _qp_distance(self, p: np.ndarray) -> float:
        from scipy.optimize import minimize
        start = np.array(self.vertices, dtype=float).mean(axis=0)
        res = minimize(lambda y: 0.5 * np.sum((y - p) ** 2), start, jac=lambda y: y - p,
                       constraints=[{"type": "ineq", "fun": lambda y: self._b - self._a @ y,
                                     "jac": lambda y: -self._a}],
                       method="SLSQP", options={"ftol": 1e-14, "maxiter": 200})
        y = res.x
        # project residual infeasibility away conservatively: report the larger of the QP
        # value and the facet lower bound
        return float(max(np.linalg.norm(y - p), self.signed_clearance(p)[0]))

    def box_hull(self, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The smallest box containing ``polytope ∩ [lower, upper]``, or ``None`` if empty.

        Exact in one and two dimensions (from the vertices inside the box, the edges'
        crossings of the box's sides and the box's corners inside the polygon, widened by
        :data:`ROUNDING` and clipped to the box, so that rounding never loses a point);
        ``2k`` linear programs in more.
        """
        lower, upper = np.asarray(lower, float), np.asarray(upper, float)
        k = lower.size
        if k > 2:
            return self._box_hull_lp(lower, upper)
        scale = ROUNDING * (1.0 + float(np.max(np.abs(np.concatenate([lower, upper])))))
        points = [self._ring]
        if k == 2:
            a = self._ring
            b = np.roll(a, -1, axis=0)
            for axis in (0, 1):
                other = 1 - axis
                for side in (lower[axis], upper[axis]):
                    da = a[:, axis] - side
                    db = b[:, axis] - side
                    cross = (da * db <= 0) & (da != db)
                    t = da[cross] / (da[cross] - db[cross])
                    hit = np.empty((t.size, 2))
                    hit[:, axis] = side
                    hit[:, other] = a[cross, other] + t * (b[cross, other] - a[cross, other])
                    points.append(hit)
        corners = np.array(list(itertools.product(*zip(lower, upper))))
        points.append(corners[np.all(corners @ self._a.T <= self._b + scale, axis=1)])
        points = np.concatenate(points)
        points = points[np.all((points >= lower - scale) & (points <= upper + scale), axis=1)]
        if points.shape[0] == 0:
            return None
        lo = np.maximum(points.min(axis=0) - scale, lower)
        hi = np.minimum(points.max(axis=0) + scale, upper)
        return lo, hi

    def _box_hull_lp(self, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        from scipy.optimize import linprog
        k = len(lower)
        bounds = list(zip(lower, upper))
        lo, hi = np.empty(k), np.empty(k)
        for i in range(k):
            for sign, out in ((1.0, lo), (-1.0, hi)):
                c = np.zeros(k)
                c[i] = sign
                res = linprog(c, A_ub=self._a, b_ub=self._b, bounds=bounds, method="highs")
                if res.status == 2:
                    return None
                if res.status != 0:
                    raise SpecError("obstacles", f"linear program failed: {res.message}")
                out[i] = res.x[i]
        return lo, hi

    def meets_box(self, lower: np.ndarray, upper: np.ndarray) -> bool:
        return self.box_hull(np.asarray(lower, float), np.asarray(upper, float)) is not None


def make_polytope(vertices: list, name: str) -> Polytope:
    """Validate a vertex list and build the polytope.

    Parameters
    ----------
    vertices : list of list of float, shape (v, k)
        The vertices, state units, ``k <= MAX_POLYTOPE_DIMENSION``.
    name : str
        The obstacle's field name in errors (``obstacles[i]``).

    Returns
    -------
    Polytope
        The convex hull of the vertices.

    Raises
    ------
    SpecError
        Too few vertices, or vertices that do not span the ``k``-dimensional space.
    """
    points = np.array(vertices, dtype=float)
    k = points.shape[1]
    if k > MAX_POLYTOPE_DIMENSION:
        # the hull of up to 1024 vertices has O(v^(k/2)) facets and the covering checks
        # 2^k corners per box: bounded work needs a small k
        raise SpecError(f"{name}.vertices", f"{k} coordinates; a polytope may be given on "
                                            f"at most {MAX_POLYTOPE_DIMENSION} dimensions")
    if points.shape[0] < k + 1:
        raise SpecError(f"{name}.vertices", f"needs at least {k + 1} vertices in {k} dimensions")
    if np.linalg.matrix_rank(points[1:] - points[0], tol=1e-9) < k:
        raise SpecError(f"{name}.vertices", "the vertices are degenerate (their hull has no "
                                            "interior)")
    from scipy.spatial import QhullError
    try:
        return Polytope(tuple(tuple(float(v) for v in p) for p in vertices))
    except QhullError as exc:  # pragma: no cover - rank check above catches these
        raise SpecError(f"{name}.vertices", f"no convex hull: {exc}") from None
