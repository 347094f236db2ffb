"""What a named plant model implies about system (1) on a box of states.

A spec's ``[plant] model`` is the plant ``stt-codegen simulate`` runs and the plant
``verify`` judges. Its input matrix ``g(x)`` and drift ``f(x)`` are known, so the bounds of
``[assumptions]`` (:class:`~stt_codegen.spec.loader.Assumptions`) follow from it, over the
state space ``X`` for the spec and over a smaller box (the tube on one sampling interval)
for ``verify``'s sampled check:

* ``input_gain``: the range of the eigenvalues of the symmetric part
  ``g_s = (g + g^T) / 2`` (Assumption 2 asks its lower end positive);
* ``input_gain_skew``: the largest spectral norm of the skew part ``(g - g^T) / 2``;
* ``input_gain_coupling``: the largest Euclidean norm of the off-diagonal part of a row
  of ``g``;
* ``drift_bound``: the largest ``|f(x)|``;
* ``blocks``: a partition of the state indices in which ``g(x)`` is block diagonal for
  every ``x`` (an input of one block never moves a state of another);
* ``input_gain_lipschitz``, ``drift_lipschitz``: per state, how fast ``g`` and ``f`` may
  change with that state: ``|g(x) - g(y)|_2 <= sum_j L_j |x_j - y_j|`` (spectral norm)
  and ``|f(x) - f(y)| <= sum_j L_j |x_j - y_j|`` (Euclidean norm), units of ``g`` or
  ``f`` per state unit.

Every number is an outer bound: computed exactly where the model allows (the heading
range of eq. (14), the vertices of the box for a linear drift), then widened by a few
units in the last place (:data:`REL_PAD`) so that rounding cannot make it tighter than
the model. Plain Python (no numpy): the spec loader uses it.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

__all__ = ["BOX_BOUNDS", "ModelBounds", "declared_bounds", "differential_drive_bounds", "model_bounds", "row_coupling", "symmetric_eigen_range", "REL_PAD",
           "EXACT_DRIFT_DIMENSIONS"]

#: Relative outward widening of every computed bound (rounding of ``cos``, ``sin`` and of
#: the Jacobi eigenvalue iteration is far below it).
REL_PAD = 1e-12
#: Up to this many states, ``max |a x + c|`` over a box is evaluated at all its vertices
#: (exact: the norm is convex); beyond, an upper bound.
EXACT_DRIFT_DIMENSIONS = 10


@dataclass(frozen=True)
class ModelBounds:
    """Bounds a plant model implies on a box of states (see the module docstring).

    Attributes
    ----------
    model : str
        The ``plant.model`` name.
    input_gain : tuple of float, (g_min, g_max)
        Range of the eigenvalues of ``(g(x) + g(x)^T) / 2`` over the box (``g_min`` may
        be ``<= 0``: the model then violates Assumption 2 there).
    input_gain_skew : float
        Largest ``|(g(x) - g(x)^T) / 2|_2``.
    input_gain_coupling : float
        Largest Euclidean norm of the off-diagonal part of a row of ``g(x)``.
    drift_bound : float
        Largest ``|f(x)|``, state units per second.
    blocks : tuple of tuple of int
        Partition of ``0..n-1``: ``g(x)`` is block diagonal with these blocks for every
        ``x``, in increasing order.
    where : tuple of (str, str)
        For each key above, where the model attains it, in words (for messages).
    remedy : str
        What a spec whose ``[assumptions]`` contradict the model can change, in words.
    input_gain_lipschitz : tuple of float or None
        ``L_j`` per state with ``|g(x) - g(y)|_2 <= sum_j L_j |x_j - y_j|``; ``None``: not
        known (``g`` may jump).
    drift_lipschitz : tuple of float or None
        Likewise for ``|f(x) - f(y)|``.
    disturbance_bound : float or None
        Largest ``|w|`` the model's own parameters imply (the differential drive's slip),
        state units per second; ``None``: the spec's ``plant.disturbance_amplitude``
        decides.
    input_gain_turn : tuple of float or None
        How fast ``g`` turns while a held command acts
        (:attr:`~stt_codegen.spec.assumptions.Assumptions.input_gain_turn`); ``None``: it
        does not.
    """

    model: str
    input_gain: tuple[float, float]
    input_gain_skew: float
    input_gain_coupling: float
    drift_bound: float
    blocks: tuple[tuple[int, ...], ...]
    where: tuple[tuple[str, str], ...] = ()
    remedy: str = ""
    input_gain_lipschitz: tuple[float, ...] | None = None
    drift_lipschitz: tuple[float, ...] | None = None
    disturbance_bound: float | None = None
    input_gain_turn: tuple[float, float] | None = None

    def words(self, key: str) -> str:
        """Where the model attains ``key`` ("" if not recorded)."""
        return dict(self.where).get(key, "")


def _down(v: float) -> float:
    return v - REL_PAD * max(1.0, abs(v))


def _up(v: float) -> float:
    return v + REL_PAD * abs(v)


def _contains_point(lo: float, hi: float, phase: float, period: float) -> bool:
    """Whether ``[lo, hi]`` contains ``phase + m period`` for an integer ``m``."""
    m = math.ceil((lo - phase) / period)
    return phase + m * period <= hi


def cos_range(lo: float, hi: float) -> tuple[float, float]:
    """``(min, max)`` of ``cos`` on ``[lo, hi]`` (radians), exact up to rounding."""
    values = [math.cos(lo), math.cos(hi)]
    if _contains_point(lo, hi, 0.0, 2 * math.pi):
        values.append(1.0)
    if _contains_point(lo, hi, math.pi, 2 * math.pi):
        values.append(-1.0)
    return min(values), max(values)


def abs_sin_max(lo: float, hi: float) -> float:
    """``max |sin|`` on ``[lo, hi]`` (radians), exact up to rounding."""
    if _contains_point(lo, hi, math.pi / 2, math.pi):
        return 1.0
    return max(abs(math.sin(lo)), abs(math.sin(hi)))


def _omnidirectional(lower: Sequence[float], upper: Sequence[float]) -> ModelBounds:
    # eq. (14): g = R(x3), g_s = diag(cos x3, cos x3, 1), skew part sin x3 [[0, -1], [1, 0]]
    lo, hi = float(lower[2]), float(upper[2])
    c_min, c_max = cos_range(lo, hi)
    s_max = abs_sin_max(lo, hi)
    heading = f"x3 in [{lo:g}, {hi:g}]"
    return ModelBounds(
        # the eigenvalue 1 (of g_33) is exact and cos x3 <= 1: g_max = 1
        "omnidirectional", (_down(min(c_min, 1.0)), 1.0), _up(s_max),
        _up(s_max), 0.0, ((0, 1), (2,)),
        (("input_gain", f"eigenvalues cos x3 and 1 of (g + g^T)/2 for {heading}"),
         ("input_gain_skew", f"|sin x3| for {heading}"),
         ("input_gain_coupling", f"|sin x3| in rows 1 and 2 for {heading}"),
         ("drift_bound", "f = 0"), ("input_gain_lipschitz",
                                    "|R(a) - R(b)|_2 = 2 |sin((a - b)/2)| <= |a - b|"),
         ("drift_lipschitz", "f = 0")),
        "narrow state_space's heading range (x3)",
        # g = R(x3) depends on the heading only; f = 0
        (0.0, 0.0, 1.0), (0.0, 0.0, 0.0))


def _jacobi_eigenvalues(m: list[list[float]]) -> list[float]:
    """Eigenvalues of a symmetric matrix (cyclic Jacobi rotations), ascending."""
    a = [row[:] for row in m]
    n = len(a)
    scale = math.sqrt(sum(v * v for row in a for v in row)) or 1.0
    for _ in range(100):
        off = sum(a[i][j] ** 2 for i in range(n) for j in range(n) if i != j)
        if off <= (1e-17 * scale) ** 2:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if a[p][q] == 0.0:
                    continue
                theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q])
                t = math.copysign(1.0, theta) / (abs(theta) + math.hypot(theta, 1.0))
                c = 1.0 / math.hypot(t, 1.0)
                s = t * c
                for k in range(n):          # columns p, q
                    akp, akq = a[k][p], a[k][q]
                    a[k][p], a[k][q] = c * akp - s * akq, s * akp + c * akq
                for k in range(n):          # rows p, q
                    apk, aqk = a[p][k], a[q][k]
                    a[p][k], a[q][k] = c * apk - s * aqk, s * apk + c * aqk
    return sorted(a[i][i] for i in range(n))


def symmetric_eigen_range(g: Sequence[Sequence[float]]) -> tuple[float, float, float]:
    """``(lambda_min, lambda_max)`` of ``(g + g^T)/2`` and ``|(g - g^T)/2|_2``, widened
    outward by :data:`REL_PAD` times ``|g|_F`` (the Jacobi iteration's accuracy is far
    better); exact, not widened, for a diagonal ``(g + g^T)/2`` and a zero skew part.

    Parameters
    ----------
    g : sequence of sequence of float, shape (n, n)

    Returns
    -------
    lambda_min, lambda_max : float
        Smallest and largest eigenvalue of the symmetric part ``(g + g^T)/2``, widened
        outward.
    skew_norm : float
        Spectral norm of the skew part ``(g - g^T)/2``, rounded up (0 for a symmetric ``g``).
    """
    n = len(g)
    sym = [[(g[i][j] + g[j][i]) / 2 for j in range(n)] for i in range(n)]
    skew = [[(g[i][j] - g[j][i]) / 2 for j in range(n)] for i in range(n)]
    # |K|_2^2 = lambda_max(K^T K)
    ktk = [[sum(skew[k][i] * skew[k][j] for k in range(n)) for j in range(n)]
           for i in range(n)]
    eig = _jacobi_eigenvalues(sym)
    size = math.sqrt(sum(v * v for row in g for v in row))
    diagonal = all(sym[i][j] == 0.0 for i in range(n) for j in range(n) if i != j)
    pad = 0.0 if diagonal else REL_PAD * size
    skew_norm = math.sqrt(max(_jacobi_eigenvalues(ktk)[-1], 0.0))
    skew_pad = REL_PAD * size if skew_norm > 0 else 0.0
    return eig[0] - pad, eig[-1] + pad, skew_norm + skew_pad


def row_coupling(g: Sequence[Sequence[float]]) -> float:
    """The largest Euclidean norm of a row of ``g`` without its diagonal entry (how strongly
    the other inputs drive one state), rounded up.

    Parameters
    ----------
    g : sequence of sequence of float, shape (n, n)

    Returns
    -------
    float
        ``max_i sqrt(sum_{j != i} g_ij^2)``, rounded up; 0 for ``n = 1``.
    """
    n = len(g)
    return _up(max((math.sqrt(sum(g[i][j] ** 2 for j in range(n) if j != i))
                    for i in range(n)), default=0.0))


def _blocks(g: Sequence[Sequence[float]]) -> tuple[tuple[int, ...], ...]:
    """Connected components of the graph with an edge where ``g_ij != 0`` or ``g_ji != 0``."""
    n = len(g)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(n):
            if i != j and g[i][j] != 0.0:
                parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return tuple(sorted(tuple(v) for v in groups.values()))


def linear_drift_bound(a: Sequence[Sequence[float]], c: Sequence[float],
                       lower: Sequence[float], upper: Sequence[float]) -> float:
    """``max |a x + c|`` over the box ``[lower, upper]``: exact at the vertices up to
    :data:`EXACT_DRIFT_DIMENSIONS` states (the norm is convex), else
    ``|a m + c| + sum_j |a_j| r_j`` (centre ``m``, half-widths ``r``, columns ``a_j``)."""
    n = len(c)

    def norm_at(x: Sequence[float]) -> float:
        return math.sqrt(sum((sum(a[i][j] * x[j] for j in range(n)) + c[i]) ** 2
                             for i in range(n)))

    if n <= EXACT_DRIFT_DIMENSIONS:
        return _up(max(norm_at(v) for v in itertools.product(*zip(lower, upper))))
    mid = [(lo + hi) / 2 for lo, hi in zip(lower, upper)]
    half = [(hi - lo) / 2 for lo, hi in zip(lower, upper)]
    columns = [math.sqrt(sum(a[i][j] ** 2 for i in range(n))) for j in range(n)]
    return _up(norm_at(mid) + sum(cj * rj for cj, rj in zip(columns, half)))


def _linear(lower: Sequence[float], upper: Sequence[float], linear) -> ModelBounds:
    n = len(lower)
    if linear is None:
        a = [[0.0] * n for _ in range(n)]
        g = [[float(i == j) for j in range(n)] for i in range(n)]
        c = [0.0] * n
    else:
        a, g, c = linear.a, linear.g, linear.c
    g_min, g_max, skew = symmetric_eigen_range(g)
    return ModelBounds(
        "linear", (g_min, g_max), skew, row_coupling(g), linear_drift_bound(a, c, lower, upper),
        _blocks(g),
        (("input_gain", "eigenvalues of (g + g^T)/2 for the constant plant.g"),
         ("input_gain_skew", "|(g - g^T)/2| for plant.g"),
         ("input_gain_coupling", "the largest off-diagonal row of plant.g"),
         ("drift_bound", "max |a x + c| over the box"),
         ("input_gain_lipschitz", "plant.g is constant"),
         ("drift_lipschitz", "the Euclidean norms of plant.a's columns")),
        "correct plant.a, plant.g or plant.c",
        (0.0,) * n,
        tuple(_up(math.sqrt(sum(a[i][j] ** 2 for i in range(n)))) for j in range(n)))


def model_bounds(model: str, lower: Sequence[float], upper: Sequence[float],
                 linear=None) -> ModelBounds:
    """The bounds ``model`` implies for every state in the box ``[lower, upper]``.

    Parameters
    ----------
    model : str
        A ``plant.model`` name (:data:`~stt_codegen.spec.plants.PLANT_MODELS`):
        ``"omnidirectional"`` (eq. (14), ``g = R(x3)``, ``f = 0``; depends on the heading
        range ``[lower[2], upper[2]]``), ``"single-integrator"`` (``g = I``, ``f = 0``) or
        ``"linear"`` (``x_dot = a x + c + g u``).
    lower, upper : sequence of float, length n
        The box (the state space, or the tube on an interval), state units.
    linear : LinearPlant or DifferentialDrive, optional
        The model's own ``[plant]`` data: the ``linear`` model's matrices (default ``a =
        0``, ``g = I``, ``c = 0``), the ``differential-drive`` model's base (required).

    Returns
    -------
    ModelBounds

    Raises
    ------
    ValueError
        Unknown model.
    """
    if model not in BOX_BOUNDS:
        raise ValueError(f"unknown plant model {model!r}")
    return BOX_BOUNDS[model](lower, upper, linear)


def declared_bounds(model: str, declared: dict, n: int) -> ModelBounds:
    """The bounds of a model without equations (``declared_bounds`` in the plant
    registry): the declared ``[assumptions]`` themselves, so that nothing is derived or
    compared; one block of all states (the structure of ``g`` is unknown).

    Parameters
    ----------
    model : str
        The model's name.
    declared : dict
        The declared ``[assumptions]`` keys (``input_gain`` and ``drift_bound`` at least).
    n : int
        State dimension.

    Returns
    -------
    ModelBounds
    """
    g_min, g_max = (float(v) for v in declared["input_gain"])
    # a key not declared is not compared; combine_assumptions derives the coupling that
    # the declared input_gain and skew imply
    skew = float(declared.get("input_gain_skew", 0.0))
    coupling = float(declared.get("input_gain_coupling", 0.0))
    return ModelBounds(model, (g_min, g_max), skew, coupling,
                       float(declared["drift_bound"]), (tuple(range(n)),),
                       tuple((key, "declared") for key in ("input_gain", "input_gain_skew",
                                                           "input_gain_coupling",
                                                           "drift_bound",
                                                           "input_gain_lipschitz",
                                                           "drift_lipschitz")),
                       "declare the bounds your plant meets in [assumptions]",
                       _declared_vector(declared, "input_gain_lipschitz"),
                       _declared_vector(declared, "drift_lipschitz"))


def _declared_vector(declared: dict, key: str) -> tuple[float, ...] | None:
    return tuple(float(v) for v in declared[key]) if key in declared else None


def _single_integrator(lower: Sequence[float], upper: Sequence[float],
                       linear=None) -> ModelBounds:
    n = len(lower)
    return ModelBounds("single-integrator", (1.0, 1.0), 0.0, 0.0, 0.0,
                       tuple((i,) for i in range(n)),
                       (("input_gain", "g = I"), ("input_gain_skew", "g = I"),
                        ("input_gain_coupling", "g = I"), ("drift_bound", "f = 0"),
                        ("input_gain_lipschitz", "g = I"), ("drift_lipschitz", "f = 0")),
                       'describe your plant with [plant] model = "linear" and its g',
                       (0.0,) * n, (0.0,) * n)


def differential_drive_bounds(drive) -> ModelBounds:
    """What the base implies for the look-ahead point's system (1), for every heading.

    Parameters
    ----------
    drive : DifferentialDrive
        The base (:class:`~stt_codegen.spec.differential_drive.DifferentialDrive`): its
        axle offset, track width, wheel errors and slip.

    Returns
    -------
    ModelBounds
        ``input_gain`` ``(1 + m - |d| s, 1 + m + |d| s)``, ``input_gain_skew`` ``|d| |k|``,
        ``input_gain_coupling`` ``|d| (s + |k|)``, ``drift_bound`` 0, one block, the slip's
        ``disturbance_bound``, ``input_gain_turn`` ``((1 + m) / l + 2 |d| / b, s_omega)``;
        each widened outward by :data:`REL_PAD` (the formulas:
        :mod:`stt_codegen.spec.differential_drive`).
    """
    m, d = drive.mean_error, abs(drive.differential_error)
    beta = drive.track_width / (2.0 * drive.axle_offset)
    s, k = 0.5 * (beta + 1.0 / beta), abs(0.5 * (beta - 1.0 / beta))
    s_v, s_lat, s_w = drive.slip
    where = "wheel radius errors " + ", ".join(f"{e:g}" for e in drive.wheel_radius_error)
    return ModelBounds(
        "differential-drive", (_down(1.0 + m - d * s), _up(1.0 + m + d * s)), _up(d * k),
        _up(d * (s + k)), 0.0, ((0, 1),),
        (("input_gain", f"1 + m -+ |d| s for {where}, every heading"),
         ("input_gain_skew", f"|d| |k| for {where}"),
         ("input_gain_coupling", f"|d| (s + |k|) for {where}, heading 0"),
         ("drift_bound", "f = 0"), ("disturbance_bound", "the slip, plant.slip"),
         ("input_gain_lipschitz", "g depends on the heading, not on p"),
         ("drift_lipschitz", "f = 0")),
        "declare wider bounds in [assumptions], or smaller plant.wheel_radius_error",
        (0.0, 0.0) if d == 0.0 else None, (0.0, 0.0),
        disturbance_bound=_up(math.hypot(s_v, s_lat + drive.axle_offset * s_w)),
        # the heading's rate under a held command u: |omega_act| <= ((1 + m) / l + 2 |d| / b)
        # |u| + s_omega, since |v| <= |u| and |omega| <= |u| / l
        input_gain_turn=(_up((1.0 + m) / drive.axle_offset + 2.0 * d / drive.track_width),
                         _up(s_w)))


#: The bounds over a box of each first-order model, ``(lower, upper, linear) -> bounds``:
#: what ``[assumptions]`` defaults to.
BOX_BOUNDS = {
    "omnidirectional": lambda lower, upper, linear=None: _omnidirectional(lower, upper),
    "single-integrator": _single_integrator,
    "linear": _linear,
    "differential-drive": lambda lower, upper, drive: differential_drive_bounds(drive),
}
