"""Test vectors: inputs and expected outputs from the numpy reference, with tolerances.

The inputs are float32 numbers (exact in both precisions), drawn with a fixed seed:
:data:`INSIDE` points with ``|e_i| <= 0.99`` in tubes at least 1e-2 wide, and
:data:`OUTSIDE` points with ``1.1 <= |e_i| <= 2`` in one dimension (status OUTSIDE_TUBE,
``u`` clamped); every point's status is certain in the generated precision (see
:func:`~stt_codegen.codegen.tolerance.status_certain`). For a design with an actuator
bound the inside points' status is ``OK`` or ``INPUT_CLAMPED`` as the reference clamps
``u``, and only points whose clamp decision is certain in the precision are kept
(every ``|u_i|`` of law (13) farther from ``input_bound_i`` than its error bound). Times cover ``[0, 1.2 t_c]``, so
after ``t_c`` too; ``dt`` is drawn from 1e-4, 1e-3 and 1e-2 s (the adaptive law over its
``dt`` domain), and :func:`period_copies` appends copies of a few points so that the law's
statuses ``OK`` and ``INPUT_CLAMPED`` each have a vector at ``dt = PERIOD`` (the step's
status is the law's) and one off it (``OFF_PERIOD``). Expected values are the reference's
(:mod:`stt_codegen.tube.reference`) at those inputs; tolerances are :mod:`~stt_codegen.codegen.tolerance`'s bounds for the
chosen precision (double: with the floor ``1e-12 max(1, |ref|)``).

The search is bounded (:data:`ROUNDS` rounds of :data:`BATCH` candidates). A precision
whose error bound on the tube's bounds is not small against the tube's width at the
spec's coordinates (about ``4 * 64 * unit`` times the largest coordinate; single
precision on an arena at 1e6 m, or a narrow tube in a 20 km arena) has no point whose
status is certain: that is a :class:`~stt_codegen.errors.SpecError` naming ``precision``
(see docs/codegen.md, "Large coordinates").
"""

from __future__ import annotations

import numpy as np

from ..errors import SpecError
from ..rounding import round_up_array
from ..tube import reference as R
from ..tube.parameters import Status, TubeDesign, off_period
from . import tolerance as T
from .errors import CodegenError

__all__ = ["BATCH", "INSIDE", "OFF_PERIOD_FACTOR", "OUTSIDE", "ROUNDS", "period_copies",
           "sample_inputs", "test_vectors", "vector_document", "with_copies"]

INSIDE = 48
OUTSIDE = 8
SEED = 20240531
#: Candidates per round of the search.
BATCH = 64
#: Rounds before the search gives up (the bundled cases need 2; about 1 s of work).
ROUNDS = 200
#: Width, in error bounds of the tube's bounds, below which no OUTSIDE point
#: (``1.1 <= |e| <= 2``) has a certain status: ``status_certain`` needs
#: ``|e| - 1 > 4 (1 + |e|) dg / w``, so ``w > 12 dg`` at ``|e| = 2``; 16 leaves a third
#: of the OUTSIDE draws.
RESOLUTION = 16.0
#: ``dt`` of the off-period copies of :func:`period_copies`, in periods.
OFF_PERIOD_FACTOR = 1.5


def _f32(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def sample_inputs(design: TubeDesign, precision: str = "single") -> dict[str, np.ndarray]:
    """The vectors' inputs: ``x`` (N, n), ``t`` (N,), ``dt`` (N,), ``alpha`` (N, 2n).

    Parameters
    ----------
    design : TubeDesign
    precision : {"single", "double"}
        Every point's status is certain in this precision.

    Returns
    -------
    dict of str to ndarray
        ``x`` (N, n), ``t`` (N,) s, ``dt`` (N,) s, ``alpha`` (N, 2n), float32-exact values,
        :data:`INSIDE` points inside the tube and :data:`OUTSIDE` outside, in the order drawn.

    Raises
    ------
    SpecError
        ``precision``: after :data:`ROUNDS` rounds too few points have a certain status
        because the precision cannot resolve the tube at the spec's coordinates.
    CodegenError
        Too few points for another reason (an internal limit).
    """
    rng = np.random.default_rng(SEED)
    n = design.dimension
    t_c = design.prescribed_time
    unit = T.unit_roundoff(precision)
    chosen = {k: [] for k in ("x", "t", "dt", "alpha")}
    want = {False: INSIDE, True: OUTSIDE}
    have = {False: 0, True: 0}
    widest = 0.0  # widest narrowest-dimension width of a usable candidate
    resolvable = 0  # usable candidates whose tube the precision resolves
    for _ in range(ROUNDS):
        if have[False] >= INSIDE and have[True] >= OUTSIDE:
            break
        m = BATCH
        t = _f32(rng.uniform(0.0, 1.2 * t_c, m))
        psi = R.conflict_distance(design, t)
        alpha = _f32(np.maximum(0.0, -psi + 1e-2)
                     + rng.exponential(0.05, psi.shape) * (rng.random(psi.shape) < 0.7))
        dt = _f32(rng.choice([1e-4, 1e-3, 1e-2], m))
        outside = rng.random(m) < 0.3
        e = rng.uniform(-0.99, 0.99, (m, n))
        k = rng.integers(0, n, m)
        far = rng.uniform(1.1, 2.0, m) * rng.choice([-1.0, 1.0], m)
        e[outside, k[outside]] = far[outside]
        g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
        x = _f32(((g_u - g_l) * e + (g_u + g_l)) / 2)
        usable = np.all(g_u - g_l >= 1e-2, axis=1) & np.all(psi + alpha > 0, axis=1)
        narrowest = np.min(g_u - g_l, axis=1)
        if usable.any():
            widest = max(widest, float(np.max(narrowest[usable])))
        dg = T.gamma_bound(design, alpha, unit)[:, 0]
        resolvable += int(np.sum(usable & (narrowest > RESOLUTION * dg)))
        ok = usable & T.status_certain(design, x, alpha, g_l, g_u, unit)
        _, _, inside = R.controller_step(design, x, t, dt, alpha)
        if design.input_bound is not None:
            ok &= _clamp_certain(design, x, t, alpha, g_l, g_u, unit)
        for i in np.flatnonzero(ok):
            kind = bool(inside[i] == 0.0)
            if kind != bool(outside[i]) or have[kind] >= want[kind]:
                continue
            have[kind] += 1
            for key, value in (("x", x), ("t", t), ("dt", dt), ("alpha", alpha)):
                chosen[key].append(value[i])
    if have[False] < INSIDE or have[True] < OUTSIDE:
        magnitude = max(max(abs(v) for v in design.state_lower),
                        max(abs(v) for v in design.state_upper))
        if resolvable == 0:
            hint = "; use precision double" if precision == "single" else (
                "; shift the spec's coordinates nearer 0")
            bound = T.GAMMA_FACTOR * unit * (1.0 + magnitude)
            raise SpecError("precision", (
                f"{precision} precision cannot resolve a tube of width {widest:.3g} at "
                f"coordinates of magnitude {magnitude:.3g}: the error bound of its bounds "
                f"there is {bound:.3g} and the test points need a width above "
                f"{RESOLUTION * bound:.3g}{hint}"))
        raise CodegenError(
            f"test vectors: {have[False]} of {INSIDE} inside and {have[True]} of {OUTSIDE} "
            f"outside points with a certain {precision}-precision status after "
            f"{ROUNDS * BATCH} candidates")
    return {k: np.array(v) for k, v in chosen.items()}


def _clamp_certain(design: TubeDesign, x, t, alpha, g_l, g_u, unit: float) -> np.ndarray:
    """Whether the actuator clamp's decision cannot depend on rounding, shape (N,): every
    ``|u_i|`` of law (13) is farther from ``input_bound_i`` than its error bound plus the
    rounding of the bound itself."""
    u, _, _ = R.law_step(design, x, t, np.full(t.shape, 1e-3), alpha)
    bound = np.array(design.input_bound)
    tol = T.u_bound(design, x, alpha, g_l, g_u, u, unit) + unit * bound
    return np.all(np.abs(np.abs(u) - bound) > tol, axis=1)


def period_copies(dt, status, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """The vectors to append so that the step's period check is tested: for each of the
    law's statuses ``OK`` and ``INPUT_CLAMPED`` among the vectors, a copy of its first
    vector at ``dt = PERIOD`` where none of that status is at the period, and one at
    ``dt =`` :data:`OFF_PERIOD_FACTOR` ``PERIOD`` where none is off it (the step's status
    ``OFF_PERIOD``). ``dt`` does not enter ``u`` or the law's status: a copy differs in
    ``alpha_next`` and the step's status only.

    Parameters
    ----------
    dt : ndarray, shape (N,)
        The vectors' ``dt``, s.
    status : ndarray of int, shape (N,)
        The law's status of each vector (:func:`stt_codegen.tube.reference.law_status`).
    rate_hz : float
        The design's rate: ``PERIOD = 1 / rate_hz``.

    Returns
    -------
    rows : ndarray of int
        The vectors copied, in the order appended.
    dt : ndarray
        Each copy's ``dt``: ``PERIOD`` or ``OFF_PERIOD_FACTOR PERIOD`` rounded to float32
        (exact in both precisions; float32's rounding of ``PERIOD`` is within the check's
        relative ``2^-20``).
    """
    period = 1.0 / rate_hz
    off = np.asarray(off_period(dt, rate_hz))
    rows, steps = [], []
    for law in (Status.OK, Status.INPUT_CLAMPED):
        mine = np.flatnonzero(np.asarray(status) == law)
        if mine.size == 0:
            continue
        if np.all(off[mine]):
            rows.append(int(mine[0]))
            steps.append(period)
        if not np.any(off[mine]):
            rows.append(int(mine[0]))
            steps.append(OFF_PERIOD_FACTOR * period)
    return np.array(rows, dtype=int), _f32(np.array(steps, dtype=float))


def with_copies(arrays: dict, rows: np.ndarray, dt: np.ndarray) -> dict:
    """``arrays`` (each with a leading vector axis, ``dt`` among them) with the rows
    ``rows`` appended, their ``dt`` replaced by ``dt`` (:func:`period_copies`).

    Parameters
    ----------
    arrays : dict of str to ndarray
    rows : ndarray of int
    dt : ndarray, shape of ``rows``

    Returns
    -------
    dict of str to ndarray
    """
    out = {k: np.concatenate([v, np.asarray(v)[rows]]) for k, v in arrays.items()}
    out["dt"][len(arrays["dt"]):] = dt
    return out


def test_vectors(design: TubeDesign, precision: str) -> dict:
    """Inputs, expected outputs and tolerances of every vector, as JSON-ready lists.

    Parameters
    ----------
    design : TubeDesign
        The tube.
    precision : str
        ``"double"`` or ``"single"``: the tolerances are for that precision.

    Returns
    -------
    dict
        Keys ``x``, ``t``, ``dt``, ``alpha`` (inputs); ``u``, ``alpha_next``, ``status``
        (the step's), ``control_status`` (``P_control``'s: the law's, without the
        period check), ``gamma_L``, ``gamma_U`` (reference); ``tol_u``,
        ``tol_alpha_next``, ``tol_gamma`` (absolute tolerances, same shapes);
        ``unit_roundoff``.
    """
    p = sample_inputs(design, precision)
    law = R.law_status(design, p["x"], p["t"], p["dt"], p["alpha"])[2]
    p = with_copies(p, *period_copies(p["dt"], law, design.rate_hz))
    x, t, dt, alpha = p["x"], p["t"], p["dt"], p["alpha"]
    u, alpha_next, status = R.controller_status(design, x, t, dt, alpha)
    control_status = R.law_status(design, x, t, dt, alpha)[2]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    unit = T.unit_roundoff(precision)
    # the bound of law (13)'s u bounds the clamped u too (the clamp is 1-Lipschitz, and an
    # entry clamped at a certain decision is off by the rounding of the bound only, far
    # below the term |u| 2 dg / w of the bound)
    u_law = R.law_step(design, x, t, dt, alpha)[0]
    tol_u = T.u_bound(design, x, alpha, g_l, g_u, u_law, unit)
    return vector_document(design, precision, x, t, dt, alpha, u, alpha_next, status, tol_u,
                           control_status)


def vector_document(design: TubeDesign, precision: str, x, t, dt, alpha, u, alpha_next,
                    status, tol_u, control_status=None) -> dict:
    """The vectors' document of any variant: the inputs, the oracle's outputs, the tube at
    ``t`` and every tolerance (``tol_u`` given, the others derived; a double floor in
    double precision; rounded up to a few digits, so still bounds and the same on every
    CPU, docs/codegen.md).

    Parameters
    ----------
    design : TubeDesign
    precision : str
        ``"double"`` or ``"single"``.
    x, t, dt, alpha : ndarray
        The inputs, shapes (N, m), (N,), (N,), (N, 2 n).
    u, alpha_next, status : ndarray
        The oracle's outputs (``status`` the step's).
    tol_u : ndarray
        The bound on ``u``'s rounding, shape of ``u``.
    control_status : ndarray, optional
        The status of the variant's ``P_control`` (the law's, no period check); ``None``:
        a variant without ``P_control``, no key ``control_status``.

    Returns
    -------
    dict
        As :func:`test_vectors`.
    """
    unit = T.unit_roundoff(precision)
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    tol_a = T.alpha_bound(design, alpha, alpha_next, unit)
    tol_g = np.broadcast_to(T.gamma_bound(design, alpha, unit), g_l.shape)
    if precision == "double":
        tol_u = T.with_double_floor(tol_u, u)
        tol_a = T.with_double_floor(tol_a, alpha_next)
        tol_g = T.with_double_floor(tol_g, np.maximum(np.abs(g_l), np.abs(g_u)))
    tol_u, tol_a, tol_g = (round_up_array(tol) for tol in (tol_u, tol_a, tol_g))

    def rows(a):
        return [[float(v) for v in row] for row in np.asarray(a)]

    document = {
        "x": rows(x), "t": [float(v) for v in t], "dt": [float(v) for v in dt],
        "alpha": rows(alpha), "u": rows(u), "alpha_next": rows(alpha_next),
        "status": [int(s) for s in status], "gamma_L": rows(g_l), "gamma_U": rows(g_u),
        "tol_u": rows(tol_u), "tol_alpha_next": rows(tol_a), "tol_gamma": rows(tol_g),
        "unit_roundoff": unit,
    }
    if control_status is not None:
        document["control_status"] = [int(s) for s in control_status]
    return document


test_vectors.__test__ = False  # not a pytest test
