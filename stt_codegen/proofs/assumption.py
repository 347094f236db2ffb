"""Assumption 2: uniform positive definiteness of ``g_s(x) = (g(x) + g(x)^T)/2``.

The proof of Theorem 4.1 uses ``lambda_min(g_s(x)) >= g_lower > 0`` (Rayleigh-
Ritz). Since the controller keeps ``x`` inside the tube, it suffices that this
holds on the box the tube can visit; the caller supplies the range of each
state variable the eigenvalues depend on (e.g. the heading range
``[min gamma_L3, max gamma_U3]`` of the tube, or of the state space).
"""

from __future__ import annotations

import math
from fractions import Fraction

from typing import Callable, Mapping, Sequence

import sympy as sp

from ..codegen.emit import sympy_expressions
from ..errors import SpecError
from ..runtime.dynamics import input_matrix
from ..spec.loader import Spec
from ..spec.model_bounds import model_bounds
from .look_ahead import assumption2_differential_drive
from ..spec.plants import MissingPlantBehaviour, model_behaviour
from .check import Check

__all__ = [
    "plant_input_matrix",
    "symmetric_part",
    "check_assumption2",
    "assumption2_omnidirectional",
    "assumption2_single_integrator",
    "assumption2_declared",
    "assumption2_linear",
    "assumption2_check",
    "ASSUMPTION2_CHECKS",
]

#: A range endpoint closer than this to a zero of an eigenvalue counts as
#: reaching it (``np.pi/2`` is a double below pi/2, with ``cos`` = 6e-17).
TOUCH_TOL = 1e-12
#: Range ends are snapped outward to multiples of 1/SNAP.
SNAP = 10**15


def plant_input_matrix(model: str, n: int, x: Sequence[sp.Symbol]) -> sp.Matrix:
    """The deployed ``g(x)`` of a named plant as a SymPy matrix.

    :func:`stt_codegen.runtime.dynamics.input_matrix` (the one definition of the plant,
    also simulated and compiled into the embedded closed loop) printed by the SymPy
    printer, with the state entries ``x``.

    Parameters
    ----------
    model : str
        ``"omnidirectional"`` (eq. (14)) or ``"single-integrator"``.
    n : int
        State dimension.
    x : sequence of sympy.Symbol, length n
        The state's symbols.

    Returns
    -------
    sympy.Matrix, shape (n, n)
        ``g(x)`` of system (1).
    """
    (g,) = sympy_expressions(input_matrix(model, n), {"x": list(x)})
    # dense column-major -> (n, n); exact zeros and ones as SymPy integers
    entries = [sp.nsimplify(v) if v.is_Number else v for v in g]
    return sp.Matrix(n, n, lambda i, j: entries[j * n + i])


def symmetric_part(g: sp.Matrix) -> sp.Matrix:
    """``g_s = (g + g^T)/2``, simplified entrywise.

    Parameters
    ----------
    g : sympy.Matrix, shape (n, n)
        An input matrix ``g(x)``.

    Returns
    -------
    sympy.Matrix, shape (n, n)
        ``g_s``, whose least eigenvalue Assumption 2 bounds below.
    """
    return ((g + g.T) / 2).applyfunc(sp.simplify)


def _finite_points(s: sp.Set) -> list[sp.Expr] | None:
    if isinstance(s, sp.FiniteSet):
        return sorted(s, key=lambda p: float(p))
    if s is sp.S.EmptySet:
        return []
    return None


def check_assumption2(
    g: sp.Matrix,
    ranges: Mapping[sp.Symbol, tuple[float, float]],
    name: str = "assumption2",
) -> Check:
    """Prove ``lambda_min(g_s(x)) >= g_lower > 0`` on a box of states.

    The eigenvalues of ``g_s`` are computed symbolically. Each must be constant
    or depend on a single state variable ``v`` with a given range
    ``[lo, hi]``; its minimum there is taken over the endpoints and the
    stationary points (``solveset`` of ``d lambda/dv = 0`` in the interval).
    PASS with ``g_lower`` = the least of these minima when it is positive;
    otherwise FAIL naming the points of ``[lo, hi]`` where the eigenvalue
    vanishes (within :data:`TOUCH_TOL`), i.e. where the guarantee is lost.

    Parameters
    ----------
    g : sympy.Matrix
        Input matrix ``g(x)`` of the control-affine system (1), square.
    ranges : mapping
        ``{state_symbol: (lo, hi)}`` for every variable the eigenvalues use.
    name : str
        Name of the returned check.

    Returns
    -------
    Check
        Named ``name``; ``data`` holds ``g_s``, its eigenvalues and, on PASS, ``g_lower``
        and where it is attained; on FAIL by a vanishing eigenvalue, where (``lost_at``).
    """
    gs = symmetric_part(g)
    eig = gs.eigenvals()
    data: dict[str, object] = {"g_s": str(gs.tolist()),
                               "eigenvalues": {str(k): int(v) for k, v in eig.items()}}
    lower = sp.oo
    where: dict[str, object] = {}
    for lam in eig:
        free = sorted(lam.free_symbols, key=str)
        if not free:
            val = sp.nsimplify(lam)
            if val < lower:
                lower, where = val, {"eigenvalue": str(lam), "at": "everywhere"}
            continue
        if len(free) > 1:
            return Check(name, False,
                         f"eigenvalue {lam} of g_s depends on {free}: only single-variable "
                         "eigenvalues are handled, no bound derived", data)
        v = free[0]
        if v not in ranges:
            return Check(name, False,
                         f"eigenvalue {lam} of g_s depends on {v}, for which no range was "
                         "given: not uniformly positive over all reals", data)
        raw_lo, raw_hi = (float(b) for b in ranges[v])
        if raw_lo > raw_hi:
            return Check(name, False, f"empty range [{raw_lo}, {raw_hi}] for {v}", data)
        # snap outward, exactly, to a 1e-15 grid of rationals: a superset of the range (so
        # the bound stays sound) whose comparisons with pi SymPy can decide (a subnormal
        # width such as [0, 2.2e-309] made it give up)
        lo = sp.Rational(math.floor(Fraction(raw_lo) * SNAP), SNAP)
        hi = sp.Rational(math.ceil(Fraction(raw_hi) * SNAP), SNAP)
        try:
            zeros = _finite_points(sp.solveset(lam, v, sp.Interval(lo - TOUCH_TOL,
                                                                    hi + TOUCH_TOL)))
            crit = [] if lo == hi else _finite_points(
                sp.solveset(sp.diff(lam, v), v, sp.Interval(lo, hi)))
        except TypeError as exc:
            return Check(name, False, f"could not decide the sign of {lam} on "
                                      f"[{raw_lo}, {raw_hi}]: {exc}", data)
        if crit is None or zeros is None:
            return Check(name, False,
                         f"could not enumerate the critical points or zeros of {lam} on "
                         f"[{float(lo)}, {float(hi)}]", data)
        cands = [lo, hi, *crit]
        vals = [(sp.N(lam.subs(v, c), 30), c) for c in cands]
        m, arg = min(vals, key=lambda p: p[0])
        if zeros or m <= 0:
            lost = [float(z) for z in zeros] or [float(arg)]
            data.update({"lost_at": lost, "lost_at_exact": [str(z) for z in zeros],
                         "variable": str(v), "range": [float(lo), float(hi)],
                         "min_value": float(m), "argmin": float(arg)})
            if zeros:
                pts = ", ".join(f"{v} = {z} ({float(z):.12g})" for z in zeros)
                how = f"reaches 0 at {pts}"
            else:
                how = "is <= 0 on the whole range (no zero inside)"
            return Check(name, False,
                         f"g_s is not uniformly positive definite: eigenvalue {lam} "
                         f"{how} within [{float(lo):.12g}, {float(hi):.12g}]"
                         f"; min {lam} = {float(m):.6g} at {v} = {float(arg):.12g}",
                         data)
        if m < lower:
            lower, where = m, {"eigenvalue": str(lam), "at": f"{v} = {float(arg):.12g}"}
    data.update({"g_lower": float(lower), "where": where})
    return Check(name, True,
                 f"g_s = {gs.tolist()} has eigenvalues {list(map(str, eig))}; "
                 f"lambda_min(g_s) >= g_lower = {float(lower):.12g} (eigenvalue "
                 f"{where.get('eigenvalue')} at {where.get('at')}) on the given ranges",
                 data)


def assumption2_omnidirectional(heading_range: Sequence[float]) -> Check:
    """Assumption 2 for the omnidirectional robot (14) on a heading range.

    ``g = R(x3)`` gives ``g_s = diag(cos x3, cos x3, 1)`` (the ``sin`` terms
    cancel), eigenvalues ``{cos x3 (double), 1}``. PASS with
    ``g_lower = min(1, min_{x3 in [lo, hi]} cos x3)`` when positive; FAIL with
    the point (e.g. ``x3 = pi/2``) where the range reaches a zero of ``cos``.

    Parameters
    ----------
    heading_range : (lo, hi)
        Range of ``x3`` the tube (or the state space) allows, in radians.

    Returns
    -------
    Check
        ``assumption2.omnidirectional`` (:func:`check_assumption2`).
    """
    x = sp.symbols("x1:4", real=True)
    return check_assumption2(plant_input_matrix("omnidirectional", 3, x),
                             {x[2]: tuple(heading_range)}, name="assumption2.omnidirectional")


def assumption2_single_integrator(n: int) -> Check:
    """Assumption 2 for ``x_dot = u + w``: ``g_s = I``, ``g_lower = 1``.

    Parameters
    ----------
    n : int
        State dimension.

    Returns
    -------
    Check
        ``assumption2.single_integrator`` (:func:`check_assumption2`).
    """
    x = sp.symbols(f"x1:{n + 1}", real=True)
    return check_assumption2(plant_input_matrix("single-integrator", n, x), {},
                             name="assumption2.single_integrator")


def assumption2_linear(spec: Spec) -> Check:
    """Assumption 2 for the ``linear`` model: ``lambda_min((g + g^T)/2) > 0`` for the
    constant ``plant.g`` (its bounds over the state space,
    :func:`~stt_codegen.spec.model_bounds.model_bounds`).

    Parameters
    ----------
    spec : Spec
        A spec of the ``linear`` model (its ``plant.g``; default ``g = I``).

    Returns
    -------
    Check
        ``assumption2.linear``, with ``lambda_min``.
    """
    b = model_bounds("linear", spec.state_space.lower, spec.state_space.upper,
                     spec.linear_plant)
    lam = b.input_gain[0]
    return Check("assumption2.linear", bool(lam > 0),
                 f"lambda_min((g + g^T)/2) >= {lam:.6g} for the linear plant's g"
                 + ("" if lam > 0 else ": Assumption 2 fails, law (13) cannot "
                    "hold this plant"), {"lambda_min": lam})


def assumption2_declared(spec: Spec) -> Check:
    """Assumption 2 for a plant without equations (``plant.model = "mujoco"``): what can be
    proved is that the declared ``[assumptions] input_gain`` satisfies it (``g_min > 0``);
    that the plant meets the declared bounds is assumed, not proved, and the check says so.

    Parameters
    ----------
    spec : Spec
        A spec whose plant model has ``declared_bounds`` in the plant registry.

    Returns
    -------
    Check
        ``assumption2.declared``, with ``g_min``.
    """
    g_min = spec.assumptions.input_gain[0]
    return Check("assumption2.declared", bool(g_min > 0),
                 f"the declared input_gain has g_min = {g_min:.6g} > 0; not proved: that the "
                 f"{spec.plant_model} plant meets the declared [assumptions] (the toolkit "
                 "has no equations of it; every guarantee of verify holds for plants that "
                 "do)", {"g_min": g_min})


#: The Assumption-2 check of each first-order model, ``spec -> Check``: the proof on the
#: deployed ``g(x)`` over the state space (the omnidirectional robot's heading range).
ASSUMPTION2_CHECKS: dict[str, Callable[[Spec], Check]] = {
    "omnidirectional": lambda spec: assumption2_omnidirectional(
        (spec.state_space.lower[2], spec.state_space.upper[2])),
    "single-integrator": lambda spec: assumption2_single_integrator(spec.dimension),
    "linear": assumption2_linear,
    "mujoco": assumption2_declared,
    "differential-drive": lambda spec: assumption2_differential_drive(spec),
}


def assumption2_check(spec: Spec, model: str) -> Check:
    """Assumption 2 for ``model`` over the spec's state space (:data:`ASSUMPTION2_CHECKS`).

    Parameters
    ----------
    spec : Spec
        The spec (its state space and, for ``linear``, its matrices).
    model : str
        The first-order ``plant.model`` to check.

    Returns
    -------
    Check
        The model's ``assumption2.*`` check.

    Raises
    ------
    SpecError
        ``model`` has no Assumption-2 check (field ``plant.model``): a model is never
        checked as another.
    """
    try:
        check = model_behaviour(ASSUMPTION2_CHECKS, model, "Assumption-2 check")
    except MissingPlantBehaviour as err:
        raise SpecError("plant.model", str(err)) from None
    return check(spec)
