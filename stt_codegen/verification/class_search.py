"""Members of a plant class that leave the tube: plants no sound sampled check may accept.

The sampled-data check (:func:`~stt_codegen.design.certificate.sampled.check_sampled`) proves a whole
class of plants, the bounds of :class:`~stt_codegen.spec.assumptions.Assumptions`: every
``x_dot = f(x) + g(x) u + w`` whose ``g`` has the symmetric part's eigenvalues in
``[g_min, g_max]``, a skew part of norm at most ``input_gain_skew``, off-diagonal rows of
norm at most ``input_gain_coupling``, and ``|f| <= drift_bound``, ``|w| <=
disturbance_bound``. A check that accepts a class has to be right for *every* member,
not only for the plant the bounds were read from. This module searches a class for a
member that leaves the tube under the sampled law (13): when it finds one, no sound check
can accept that class, whatever its argument.

The search is an adversary on the sampled loop, exact in its arithmetic:

* ``g`` is piecewise constant along the path: on each sampling interval, one matrix
  ``G_m`` of a finite set of members of the class (:func:`class_matrices`: the extreme
  eigenvalues in every arrangement, rotated and not, with the largest skew part, each
  kept only if its rows obey the coupling bound);
* ``f + w`` is constant on each interval, of norm ``drift_bound + disturbance_bound``, in
  one of a finite set of directions (the axes, the normalized error, the gradient of law
  (13)'s Lyapunov function, both signs);
* with ``u_k`` held, the step is exact: ``x_{k+1} = x_k + dt (G_m u_k + d_k)``.

When the class bounds how fast ``g`` and ``f`` change with the state
(``input_gain_lipschitz``, ``drift_lipschitz``: :class:`Assumptions`), the search is of
that class (the Lipschitz mode): the adversary no longer jumps between members; on each
interval ``g`` moves from its value on the previous interval towards the member it
chooses by at most ``sum_j L_j |x_{k,j} - x_{k-1,j}|`` (in the Frobenius norm, which
bounds the spectral norm the bound is stated in), and ``f`` towards
``drift_bound`` times the direction it chooses by at most its own such budget, while ``w``
(of norm ``disturbance_bound``) stays free in time. A step between two members of the
class is a convex combination of them, so it stays in the class (its bounds are convex
sets). Without a Lipschitz bound, ``g`` (or ``f``) moves freely, as before.

Three strategies choose ``(G_m, d_k)`` at each sample: greedily the largest next
``max_i |e_i|``, greedily the largest next ``sum_i atanh(e_i)^2``, and, for each of the
first :data:`HELD_RUNS` members held for the whole run (side by side, one path each), the
direction of the largest next ``max_i |e_i|``. A run is a counterexample when
``|e_i(t_k)| >= 1`` at a sample (the state is outside the deployed tube there). The path is
the trajectory of a member of the class as long as it does not pass one point twice with two
different choices: then ``g(x)`` and ``f(x)`` are defined on the path and extended off it
within the bounds (which are convex sets), and ``w`` is defined along time. A polyline in
3-D generically never meets itself, and the exits go beyond the edge by a margin
(:attr:`Counterexample.depth`), so smoothing the switches between samples keeps them. In
the Lipschitz mode the path is that of a plant whose ``g`` and ``f`` are held on each
interval and change between consecutive samples by at most the declared rate times the
state's move: the rates hold between consecutive samples of the path (not between any two
of its points, and ``g`` is not varied within an interval), the sense in which a
counterexample is "a member of the class the spec declares". The search is not exhaustive:
finding none proves nothing.

The time-invariant adversary (:func:`search_time_invariant`) holds ``g`` and ``f`` for
the whole run, at the class's extremes (each member of :func:`class_matrices` with ``f``
of norm ``drift_bound`` in each of :func:`fixed_directions`), and chooses only ``w`` per
interval, greedily. Its members are constant plants, which obey any Lipschitz bound: a
class it breaks is out of reach of a sound check with or without them.

``verify`` runs the greedy strategies when its sampled check fails on bounds that hold on
every interval alike, and reports a member it finds, confirmed on the numpy reference of
the deployed controller (:func:`replay`): the failure is then not the check's caution.
The wide study runs the search on each plant's class
(``python -m stt_codegen_bench.plants_study --classes``; docs/sampled-data.md, "The wide
study, and how much a sound check can accept").
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from ..design.samples import TubeSamples
from ..spec.assumptions import Assumptions
from ..spec.model_bounds import row_coupling, symmetric_eigen_range
from ..tube import reference
from ..tube.parameters import TubeDesign

__all__ = ["Counterexample", "class_matrices", "fixed_directions", "replay", "search_class",
           "search_time_invariant", "unit_skew", "within_class"]

#: Random rotations of the extreme eigenvalues tried per class (besides the axis-aligned
#: arrangements).
ROTATIONS = 16
#: Members held for a whole run (the first of :func:`class_matrices`), after the greedy runs.
HELD_RUNS = 24


@dataclass(frozen=True)
class Counterexample:
    """A member of the class whose sampled loop leaves the tube.

    Attributes
    ----------
    strategy : str
        How the adversary chose ``(G, d)`` on each interval.
    time : float
        The sample at which ``|e_i| >= 1``, seconds.
    dimension : int
        The dimension ``i`` (0-based).
    depth : float
        ``|e_i|`` there (``>= 1``; how far outside the tube, in half-widths from its centre).
    max_abs_e : float
        The largest ``|e|`` at the samples before the exit.
    gains : ndarray, shape (K, n, n)
        ``g`` on each sampling interval up to the exit (a member of the class).
    pushes : ndarray, shape (K, n)
        ``f + w`` on each interval, state units per second.
    drifts : ndarray, shape (K, n)
        The ``f`` part of ``pushes`` (``pushes - drifts`` is ``w``), state units per second.
    gain_rates : bool
        ``g`` moved only within the class's ``input_gain_lipschitz`` (else it jumped).
    drift_rates : bool
        ``f`` moved only within the class's ``drift_lipschitz``, ``w`` apart within
        ``disturbance_bound`` (else ``f + w`` jumped within their sum).
    """

    strategy: str
    time: float
    dimension: int
    depth: float
    max_abs_e: float
    gains: np.ndarray = field(compare=False, repr=False, default=None)
    pushes: np.ndarray = field(compare=False, repr=False, default=None)
    drifts: np.ndarray = field(compare=False, repr=False, default=None)
    gain_rates: bool = False
    drift_rates: bool = False

    def to_json(self) -> dict:
        """The figures, without the path (JSON-ready)."""
        return {"strategy": self.strategy, "time": self.time, "dimension": self.dimension,
                "depth": self.depth, "max_abs_e": self.max_abs_e}

    @property
    def lipschitz(self) -> bool:
        """Whether the search respected a Lipschitz bound of the class (``g``'s or ``f``'s)."""
        return self.gain_rates or self.drift_rates


def unit_skew(axis: np.ndarray) -> np.ndarray:
    """The skew matrix of the cross product with ``axis`` (3-D), or the rotation generator
    (2-D); spectral norm ``|axis|``.

    Parameters
    ----------
    axis : ndarray, shape (2,) or (3,)
        A unit vector (its direction is ignored in 2-D).

    Returns
    -------
    ndarray, shape (2, 2) or (3, 3)
        The skew-symmetric matrix ``K``.
    """
    if len(axis) == 2:
        return np.array([[0.0, -1.0], [1.0, 0.0]])
    return np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                     [-axis[1], axis[0], 0.0]])


def within_class(g: np.ndarray, bounds: Assumptions, tol: float = 1e-9) -> bool:
    """``g`` obeys the class's bounds on ``g``: eigenvalues of its symmetric part, norm of
    its skew part, norm of each row's off-diagonal part (up to ``tol`` relative), and zero
    entries between the class's blocks (:meth:`Assumptions.coupled_blocks`).

    Parameters
    ----------
    g : ndarray, shape (n, n)
        A constant input matrix.
    bounds : Assumptions
        The declared class (``[assumptions]``).
    tol : float, optional
        Relative (and, for the norms, absolute) tolerance.

    Returns
    -------
    bool
        Whether ``g`` is a member of the class.
    """
    n = len(g)
    g_min, g_max = bounds.input_gain
    block_of = {i: b for b in bounds.coupled_blocks(n) for i in b}
    if any(g[i, j] != 0.0 for i in range(n) for j in range(n) if j not in block_of[i]):
        return False
    rows = g.tolist()
    low, high, skew = symmetric_eigen_range(rows)     # what the constant g implies (the
    slack = 1.0 + tol                                  # linear model's bounds)
    return bool(low >= g_min / slack and high <= g_max * slack
                and skew <= bounds.input_gain_skew * slack + tol
                and row_coupling(rows) <= bounds.input_gain_coupling * slack + tol)


def _block_matrices(bounds: Assumptions, m: int, rng: np.random.Generator
                    ) -> list[np.ndarray]:
    """Candidate ``m x m`` blocks: extreme eigenvalues (on the axes, and rotated) plus the
    largest skew part the coupling bound allows (about each axis and random axes, both
    signs)."""
    g_min, g_max = bounds.input_gain
    skew = bounds.input_gain_skew
    syms = [np.diag(e) for e in itertools.product((g_min, g_max), repeat=m)]
    if m > 1:
        for _ in range(ROTATIONS):
            q, _ = np.linalg.qr(rng.normal(size=(m, m)))
            syms.append(q @ np.diag(rng.choice((g_min, g_max), m)) @ q.T)
    if m == 1 or skew == 0.0:
        skews = [np.zeros((m, m))]
    elif m == 2:
        skews = [sign * skew * unit_skew(np.zeros(2)) for sign in (1.0, -1.0)]
    else:
        axes = list(np.eye(m)) + [v / np.linalg.norm(v) for v in rng.normal(size=(4, m))]
        skews = [sign * skew * unit_skew(a) for a in axes for sign in (1.0, -1.0)]
    return [s + k for s, k in itertools.product(syms, skews)]


def class_matrices(bounds: Assumptions, n: int, seed: int = 0) -> list[np.ndarray]:
    """Constant input gains ``g`` of the class, at its extremes.

    Block by block (:meth:`Assumptions.coupled_blocks`; ``g`` is zero between blocks), the
    symmetric part has eigenvalues ``g_min`` and ``g_max`` (every arrangement on the axes,
    and :data:`ROTATIONS` random rotations), the skew part the largest norm the coupling
    bound allows (scaled by 1, 0.75, 0.5 or 0), about each axis and random axes, both
    signs. Only matrices :func:`within_class` are returned, without repeats, in a fixed
    order.

    Parameters
    ----------
    bounds : Assumptions
        The class.
    n : int
        States (``g`` is ``n x n``); blocks of at most 3 states.
    seed : int
        Seeds the random rotations and axes.

    Returns
    -------
    list of ndarray, each (n, n)
        The members of the class tried, in a fixed order.
    """
    rng = np.random.default_rng([seed, n, 11])
    blocks = bounds.coupled_blocks(n)
    choices = [_block_matrices(bounds, len(b), rng) for b in blocks]
    unique: dict[bytes, np.ndarray] = {}
    for parts in itertools.product(*choices):
        full = np.zeros((n, n))
        for b, part in zip(blocks, parts):
            full[np.ix_(b, b)] = part
        sym = 0.5 * (full + full.T)
        for scale in (1.0, 0.75, 0.5, 0.0):      # the largest skew the coupling allows
            g = sym + scale * (full - sym)
            if within_class(g, bounds):
                unique.setdefault(np.round(g, 12).tobytes(), g)
                break
    return list(unique.values())


def _directions(e: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Unit directions of ``f + w`` tried at a sample, per path: the axes, the normalized
    error and ``z``, the gradient of ``W`` (law (13)'s Lyapunov function, along ``-u``),
    both signs; (P, 2n + 4, n) for ``e`` and ``z`` of shape (P, n). A zero ``e`` or ``z``
    gives the first axis in its place (a repeat, which the greedy choice, taking the first
    of equal values, never prefers)."""
    p, n = e.shape
    axes = np.broadcast_to(np.concatenate([np.eye(n), -np.eye(n)]), (p, 2 * n, n))
    rows = [axes]
    for v in (e, z):
        norm = np.linalg.norm(v, axis=1, keepdims=True)
        unit = np.where(norm > 0.0, v / np.where(norm > 0.0, norm, 1.0), np.eye(n)[0])
        rows.append(np.stack([unit, -unit], axis=1))
    return np.concatenate(rows, axis=1)


def fixed_directions(n: int, seed: int = 0) -> np.ndarray:
    """The directions a time-invariant drift is held in (:func:`search_time_invariant`):
    the axes and two seeded random unit directions, both signs.

    Parameters
    ----------
    n : int
        States.
    seed : int
        Seeds the two random directions.

    Returns
    -------
    ndarray, shape (2 n + 4, n)
        Unit vectors, in a fixed order (10 in 3-D).
    """
    rng = np.random.default_rng([seed, n, 13])
    extra = rng.normal(size=(2, n))
    extra /= np.linalg.norm(extra, axis=1, keepdims=True)
    return np.concatenate([np.eye(n), -np.eye(n), extra, -extra])


def _towards(current: np.ndarray, targets: np.ndarray, budget: np.ndarray) -> np.ndarray:
    """Each path's ``current`` (P, ...) moved towards each of ``targets`` (P or 1, M, ...)
    by at most its ``budget`` (P,) (Euclidean norm; for matrices the Frobenius norm, which
    bounds the spectral norm the Lipschitz bounds are stated in); all of ``targets`` where
    ``budget`` is infinite. Shape (P, M, ...)."""
    step = targets - current[:, None]
    size = np.sqrt(np.sum(step.reshape(step.shape[:2] + (-1,)) ** 2, axis=2))
    scale = np.minimum(1.0, budget[:, None] / np.maximum(size, 1e-300))
    return current[:, None] + scale.reshape(scale.shape + (1,) * (step.ndim - 2)) * step


def _budget(rates: tuple[float, ...] | None, move: np.ndarray | None, paths: int
            ) -> np.ndarray:
    """How far ``g`` or ``f`` may change on each path after the state moved by ``move``
    (P, n): ``sum_j L_j |move_j|``; infinite without rates (the class's member may jump)
    or before the first interval. Shape (P,)."""
    if rates is None or move is None:
        return np.full(paths, np.inf)
    return np.abs(move) @ np.asarray(rates, dtype=float)


def _run(design: TubeDesign, samples: TubeSamples, members: np.ndarray, bounds: Assumptions,
         score: str, strategy: str, drifts: np.ndarray | None = None, record: bool = True
         ) -> tuple[int, Counterexample] | None:
    """The adversary on the sampled loop, greedy on ``score`` (``"max"`` or
    ``"lyapunov"``), on P paths side by side.

    Path ``p`` chooses its ``g`` on each interval among ``members[p]`` (shape (P, M, n,
    n); moved towards them within ``input_gain_lipschitz`` when the class has it; one
    member, ``M = 1``, is held for the whole run) and ``f + w`` in the directions of
    :func:`_directions` (``f`` moved within ``drift_lipschitz`` when the class has it).
    With ``drifts`` (P, n), path ``p`` holds ``f = drifts[p]`` and only ``w``, of norm
    ``disturbance_bound``, is chosen. Returns the path that exits first (at the earliest
    sample; the lowest index among those exiting there) and its counterexample
    (``strategy`` formatted with the path's index), or ``None``; without ``record``, the
    counterexample has no path (``gains``, ``pushes``, ``drifts`` ``None``: many paths
    side by side would not fit in memory)."""
    lower, upper = samples.gamma_lower, samples.gamma_upper
    centre, half = 0.5 * (upper + lower), 0.5 * (upper - lower)
    dt = 1.0 / design.rate_hz
    gain = design.gain
    x0 = np.array(design.initial_state, dtype=float)
    n = len(x0)
    steps = len(samples.t) - 1
    paths = len(members)
    x = np.repeat(x0[None, :], paths, axis=0)                   # (P, n)
    separate = drifts is not None or bounds.drift_lipschitz is not None  # f apart from w
    drift = bounds.drift_bound if separate else bounds.drift_bound + bounds.disturbance_bound
    free = bounds.disturbance_bound if separate else 0.0
    g_now, f_now = None, (np.zeros((paths, n)) if drifts is None else
                          np.asarray(drifts, dtype=float))
    gains = np.empty((paths, steps, n, n)) if record else None
    pushes = np.empty((paths, steps, n)) if record else None
    f_path = np.empty((paths, steps, n)) if record else None
    move = None
    top = np.zeros(paths)
    every = np.arange(paths)

    def found(k: int, e: np.ndarray) -> tuple[int, Counterexample]:
        p = int(np.flatnonzero(np.max(np.abs(e), axis=1) >= 1.0)[0])
        i = int(np.argmax(np.abs(e[p])))
        path = ((gains[p, :k].copy(), pushes[p, :k].copy(), f_path[p, :k].copy())
                if record else (None, None, None))
        return p, Counterexample(
            strategy.format(p), float(samples.t[k]), i, float(abs(e[p, i])), float(top[p]),
            *path, drifts is not None or bounds.input_gain_lipschitz is not None, separate)

    for k in range(steps):
        e = (x - centre[k]) / half[k]
        worst = np.max(np.abs(e), axis=1)
        if np.any(worst >= 1.0):
            return found(k, e)
        top = np.maximum(top, worst)
        u = reference.law(gain, x, np.broadcast_to(lower[k], x.shape),
                          np.broadcast_to(upper[k], x.shape))[0]      # (P, n)
        units = _directions(e, -u)                                      # (P, D, n)
        g_next = (members if g_now is None else
                  _towards(g_now, members, _budget(bounds.input_gain_lipschitz, move, paths)))
        if drifts is not None:
            f_next = np.broadcast_to(f_now[:, None], units.shape)
        elif move is None:
            f_next = drift * units
        else:
            f_next = _towards(f_now, drift * units, _budget(bounds.drift_lipschitz, move, paths))
        dirs = f_next + free * units                                    # f + w, (P, D, n)
        moves = (g_next @ u[:, None, :, None])[..., 0]                  # (P, M, n)
        e_moved = (x[:, None, :] + dt * moves - centre[k + 1]) / half[k + 1]
        e_next = e_moved[:, :, None, :] + dirs[:, None, :, :] * (dt / half[k + 1])
        if score == "max":
            value = np.abs(e_next[..., 0])        # max over the axis, without a reduction
            for i in range(1, n):                 # over a short axis (slow in numpy)
                np.maximum(value, np.abs(e_next[..., i]), out=value)
        else:
            value = np.sum(np.arctanh(np.clip(np.abs(e_next), 0.0, 1.0 - 1e-15)) ** 2,
                           axis=-1)
        best = np.argmax(value.reshape(paths, -1), axis=1)
        m, d = np.divmod(best, value.shape[2])
        g_now, f_now = g_next[every, m], f_next[every, d]
        new_x = x + dt * (moves[every, m] + dirs[every, d])
        move = new_x - x
        x = new_x
        if record:
            gains[:, k] = g_now
            pushes[:, k] = dirs[every, d]
            f_path[:, k] = f_now
    e = (x - centre[-1]) / half[-1]
    return found(steps, e) if float(np.max(np.abs(e))) >= 1.0 else None


def search_class(design: TubeDesign, samples: TubeSamples, bounds: Assumptions,
                 seed: int = 0, held_runs: int = HELD_RUNS) -> Counterexample | None:
    """Search the class ``bounds`` for a member whose sampled loop leaves the tube.

    Parameters
    ----------
    design : TubeDesign
        The designed tube: its gain ``k`` of law (13), rate and ``x(0)``.
    samples : TubeSamples
        The deployed tube at every sample (:func:`~stt_codegen.design.samples.sample_tube`).
    bounds : Assumptions
        The class (its ``g`` bounds, ``drift_bound + disturbance_bound``, and its
        ``input_gain_lipschitz`` and ``drift_lipschitz`` when known: then the search is of
        the Lipschitz-respecting members, see the module's text).
    seed : int
        Seeds :func:`class_matrices`.
    held_runs : int
        How many members to also hold for a whole run, after the greedy runs (default
        :data:`HELD_RUNS`; ``verify`` asks for 0).

    Returns
    -------
    Counterexample or None
        The first counterexample found (see the module's text for the strategies), or
        ``None`` when none is found (which proves nothing).
    """
    members = class_matrices(bounds, design.dimension, seed)
    if not members:
        return None
    rated = [name for name, rates in (("g", bounds.input_gain_lipschitz),
                                      ("f", bounds.drift_lipschitz)) if rates is not None]
    mode = f", {' and '.join(rated)} Lipschitz" if rated else ""
    every = np.stack(members)[None]                             # one path, (1, M, n, n)
    for score in ("max", "lyapunov"):
        found = _run(design, samples, every, bounds, score, f"greedy {score}{mode}")
        if found is not None:
            return found[1]
    if held_runs > 0:                      # each member held on its own path, side by side
        found = _run(design, samples, every[0, :held_runs, None], bounds, "max",
                     f"member {{}} held{mode}")
        if found is not None:
            return found[1]
    return None


def search_time_invariant(design: TubeDesign, samples: TubeSamples, bounds: Assumptions,
                          seed: int = 0) -> Counterexample | None:
    """Search the class ``bounds`` for a member with ``g`` and ``f`` constant, only ``w``
    chosen along time, whose sampled loop leaves the tube (the time-invariant adversary).

    Every pair of a member ``g`` of :func:`class_matrices` and a drift ``f`` of norm
    ``drift_bound`` in one of :func:`fixed_directions` is held for the whole run; on each
    interval ``w``, of norm ``disturbance_bound``, takes the direction of
    :func:`_directions` that makes the next ``max_i |e_i|`` largest (greedy). Such a plant
    has ``g(x) = G`` and ``f(x) = F`` everywhere: it is a member of the class with any
    Lipschitz bounds (its rates are 0), so a class it breaks is out of reach of every sound
    check, Lipschitz bounds declared or not. The pairs run side by side (members first);
    the first to exit (at the earliest sample, the lowest index among those exiting there;
    with numpy's ``log``, a screen) is run again alone, with the reference's own
    arithmetic, to record its path, and returned. Not exhaustive: finding none
    proves nothing.

    Parameters
    ----------
    design : TubeDesign
        The designed tube: its gain ``k`` of law (13), rate and ``x(0)``.
    samples : TubeSamples
        The deployed tube at every sample (:func:`~stt_codegen.design.samples.sample_tube`).
    bounds : Assumptions
        The class: its ``g`` bounds, ``drift_bound`` and ``disturbance_bound`` (its
        Lipschitz bounds, if any, are not needed: a constant member obeys them).
    seed : int
        Seeds :func:`class_matrices` and :func:`fixed_directions`.

    Returns
    -------
    Counterexample or None
        The member found (``strategy`` ``"time-invariant pair P"``, ``P`` its index in the
        order above; ``gains`` and ``drifts`` the same on every interval), or ``None``.
    """
    n = design.dimension
    members = class_matrices(bounds, n, seed)
    if not members:
        return None
    units = fixed_directions(n, seed)
    gains = np.repeat(np.stack(members), len(units), axis=0)[:, None]     # (M D, 1, n, n)
    drifts = np.tile(bounds.drift_bound * units, (len(members), 1))       # (M D, n)
    start = 0
    while start < len(gains):
        with reference.numpy_math():          # a screen: the path found is run again
            first = _run(design, samples, gains[start:], bounds, "max", "", drifts[start:],
                         record=False)
        if first is None:
            return None
        index = start + first[0]
        alone = _run(design, samples, gains[index:index + 1], bounds, "max",
                     f"time-invariant pair {index}", drifts[index:index + 1])
        if alone is not None:
            return alone[1]
        start = index + 1        # rounding made the path differ alone: search on past it
    return None


def replay(design: TubeDesign, found: Counterexample, backend: str = "c") -> bool:
    """Replay a counterexample on a deployed controller: ``True`` when the controller of
    ``backend`` (the generated C by default, see
    :func:`~stt_codegen.runtime.backends.make_controller`) reports ``STATUS_OUTSIDE_TUBE``
    at a sample up to the counterexample's exit, and ``STATUS_OK`` at every sample before.

    The plant is the counterexample's: ``g = G_k`` and ``f + w = d_k`` on interval ``k``,
    stepped exactly, ``x_{k+1} = x_k + dt (G_k u_k + d_k)``, with ``u_k`` and the tube now
    computed by the deployed controller itself (its own ``alpha`` iteration, law (13) with
    its clamps), so a counterexample does not rest on the numpy reference alone.
    The replayed path may leave before the search's: the adversary drives the loop into
    the law's over-correction, where the rounding of two implementations grows from step
    to step; an earlier exit of the same plant confirms it all the same.

    Parameters
    ----------
    design : TubeDesign
        The design the counterexample was found for.
    found : Counterexample
        From :func:`search_class`.
    backend : str
        ``"c"`` (needs a C compiler), ``"python"``, ``"casadi"`` or ``"reference"``.

    Returns
    -------
    bool
        Whether the deployed controller confirms the exit.
    """
    from ..runtime.backends import STATUS_OK, STATUS_OUTSIDE_TUBE, make_controller
    controller = make_controller(backend, design)
    dt = 1.0 / design.rate_hz
    x = np.array(design.initial_state, dtype=float)
    alpha = np.zeros(2 * design.dimension)
    for k, (g, d) in enumerate(zip(found.gains, found.pushes)):
        u, alpha, status = controller.step(x, k * dt, dt, alpha)
        if status != STATUS_OK:
            return status == STATUS_OUTSIDE_TUBE
        x = x + dt * (g @ u + d)
    return controller.step(x, len(found.gains) * dt, dt, alpha)[2] == STATUS_OUTSIDE_TUBE
