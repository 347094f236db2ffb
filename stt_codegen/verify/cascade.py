"""SymPy proofs of the cascade's second stage on the deployed expressions
(docs/second-order.md, "The argument").

The pieces :func:`stt_codegen.tube.cascade.velocity_transform`,
:func:`~stt_codegen.tube.cascade.velocity_law` and
:func:`~stt_codegen.tube.cascade.velocity_tube` are printed by the emitter's SymPy printer
(the instruction stream the C and Python printers print) and reduced to the branch that
holds where the clamps are inactive (``rho2 >= GAMMA_D_MIN``, ``|e2| <= E_MAX``) by
:func:`stt_codegen.verify.deployed.on_domain`. On them:

* ``cascade.transform.n<n>``: ``e2 = (x2 - r)/rho2``, ``epsilon2 = ln((1+e2)/(1-e2))``,
  ``xi2 = 2/(rho2 (1 - e2^2))`` and ``u = -k2 xi2 epsilon2``;
* ``cascade.jacobian.n<n>``: ``d epsilon2/d x2 = xi2`` (diagonal), ``d epsilon2/d r = -xi2``;
* ``cascade.lyapunov_derivative.n<n>``: ``d/dt (epsilon2^T epsilon2 / 2) = epsilon2^T xi2
  (x2_dot - r_dot - rho2_dot e2)`` with ``x2``, ``r``, ``rho2`` functions of time;
* ``cascade.pushes_back``: ``xi2 > 0`` and ``u z <= 0`` for ``|e2| < 1``;
* ``cascade.velocity_tube``: ``rho2(0) = width_start``, ``rho2 >= rho2_inf`` for ``t >= 0``,
  ``|rho2_dot| <= l (rho2(0) - rho2_inf)``.

``cascade.sampled`` (:func:`sampled_cascade_check`) reports the sampled cascade's
certificate (:mod:`.cascade_sampled`), and, with ``[actuator]``, ``cascade.input_bound``
(:func:`cascade_input_bound_check`) its certified peak of each physical input against the
bound.
"""

from __future__ import annotations

import functools

import sympy as sp

from ..codegen.emit import sympy_expressions
from ..tube import cascade
from ..tube.parameters import E_MAX, GAMMA_D_MIN
from .check import Check
from .deployed import on_domain

__all__ = ["cascade_checks", "cascade_input_bound_check", "check_jacobian",
           "check_lyapunov_derivative", "check_pushes_back", "check_transform",
           "check_velocity_tube", "judged_stage", "plant_within_class_check",
           "sampled_cascade_check"]

_CLAMPS = {sp.Rational(GAMMA_D_MIN): 1, sp.Rational(E_MAX): -1, -sp.Rational(E_MAX): 1}


def _symbols(n: int):
    x2 = sp.Matrix(sp.symbols(f"x2_1:{n + 1}", real=True))
    r = sp.Matrix(sp.symbols(f"r1:{n + 1}", real=True))
    rho2 = sp.Matrix(sp.symbols(f"rho2_1:{n + 1}", positive=True))
    return x2, r, rho2


@functools.lru_cache(maxsize=None)
def deployed_transform(n: int) -> tuple:
    """``(e2, epsilon2, xi2, u, k2, x2, r, rho2)``: the deployed expressions (Matrices) on
    the domain where the clamps are inactive, and their symbols."""
    x2, r, rho2 = _symbols(n)
    values = {"x2": list(x2), "r": list(r), "rho2": list(rho2)}
    e, eps, xi = (sp.Matrix([on_domain(v, {}, _CLAMPS) for v in out])
                  for out in sympy_expressions(cascade.velocity_transform(n), values))
    k2 = sp.Symbol("k2", positive=True)
    u, _ = sympy_expressions(cascade.velocity_law(n), {**values, "gain": [k2]})
    u = sp.Matrix([on_domain(v, {}, _CLAMPS) for v in u])
    return e, eps, xi, u, k2, x2, r, rho2


def _zero(expr) -> bool:
    return sp.simplify(sp.together(expr)) == 0


def check_transform(n: int) -> Check:
    """The deployed ``e2``, ``epsilon2``, ``xi2``, ``u`` equal the formulas of
    docs/second-order.md.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).

    Returns
    -------
    Check
        ``cascade.transform.n<n>``.
    """
    e, eps, xi, u, k2, x2, r, rho2 = deployed_transform(n)
    ok = True
    for i in range(n):
        paper_e = (x2[i] - r[i]) / rho2[i]
        paper_eps = sp.log((1 + paper_e) / (1 - paper_e))
        paper_xi = 2 / (rho2[i] * (1 - paper_e**2))
        ok = ok and _zero(e[i] - paper_e) and _zero(xi[i] - paper_xi)
        ok = ok and _zero(sp.expand_log(eps[i] - paper_eps, force=True))
        ok = ok and _zero(u[i] + k2 * xi[i] * eps[i])
    return Check(f"cascade.transform.n{n}", bool(ok),
                 "deployed e2 = (x2 - r)/rho2, epsilon2 = ln((1+e2)/(1-e2)), xi2 = 2/(rho2 "
                 "(1 - e2^2)), u = -k2 xi2 epsilon2 where the clamps are inactive"
                 if ok else "the deployed second stage differs from its formulas", {"n": n})


def check_jacobian(n: int) -> Check:
    """``d epsilon2 / d x2 = diag(xi2)`` and ``d epsilon2 / d r = -diag(xi2)``.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).

    Returns
    -------
    Check
        ``cascade.jacobian.n<n>``.
    """
    _, eps, xi, _, _, x2, r, rho2 = deployed_transform(n)
    jx = (eps.jacobian(x2) - sp.diag(*xi)).applyfunc(lambda v: sp.simplify(sp.together(v)))
    jr = (eps.jacobian(r) + sp.diag(*xi)).applyfunc(lambda v: sp.simplify(sp.together(v)))
    ok = jx.is_zero_matrix and jr.is_zero_matrix
    return Check(f"cascade.jacobian.n{n}", bool(ok),
                 "d epsilon2/d x2 = xi2 and d epsilon2/d r = -xi2 (diagonal), symbolic x2, r, "
                 "rho2 > 0" if ok else f"differences {jx.tolist()}, {jr.tolist()}", {"n": n})


def check_lyapunov_derivative(n: int, tube_rate: bool = True) -> Check:
    """``V2_dot = epsilon2^T xi2 (x2_dot - r_dot - rho2_dot e2)`` with time-dependent
    ``x2``, ``r``, ``rho2``.

    Parameters
    ----------
    n : int
        Number of positions (= velocities).
    tube_rate : bool, optional
        ``False`` drops the term ``rho2_dot e2`` from the claim (a wrong identity, which
        the check must refuse: the tests use it).

    Returns
    -------
    Check
        ``cascade.lyapunov_derivative.n<n>``: passed when the difference simplifies to 0.
    """
    e, eps, xi, _, _, x2, r, rho2 = deployed_transform(n)
    t = sp.Symbol("t", real=True)
    fx = [sp.Function(f"X{i + 1}", real=True)(t) for i in range(n)]
    fr = [sp.Function(f"R{i + 1}", real=True)(t) for i in range(n)]
    fp = [sp.Function(f"P{i + 1}", positive=True)(t) for i in range(n)]
    timed = {**dict(zip(x2, fx)), **dict(zip(r, fr)), **dict(zip(rho2, fp))}
    e_t, eps_t, xi_t = (m.xreplace(timed) for m in (e, eps, xi))
    v_dot = sp.diff((eps_t.T * eps_t)[0] / 2, t)
    claim = sum(eps_t[i] * xi_t[i] * (fx[i].diff(t) - fr[i].diff(t) - fp[i].diff(t) * e_t[i] * int(tube_rate))
                for i in range(n))
    diff = sp.expand(v_dot - claim)
    logs = {eps_t[i]: sp.Symbol(f"L{i + 1}") for i in range(n)}
    diff = sp.simplify(sp.together(diff.xreplace(logs)))
    ok = diff == 0
    return Check(f"cascade.lyapunov_derivative.n{n}", bool(ok),
                 "d/dt (eps2^T eps2/2) = eps2^T xi2 (x2_dot - r_dot - rho2_dot e2) identically "
                 "(time-dependent x2, r, rho2 > 0)" if ok else f"difference {diff}", {"n": n})


def check_pushes_back() -> Check:
    """``xi2 > 0`` and ``u (x2 - r) <= 0`` for ``|e2| < 1`` (n = 1; the stage is entry-wise).

    With ``e2 = (w - 1)/(w + 1)``, ``w > 0`` (a bijection onto ``(-1, 1)``),
    ``epsilon2 = ln(w)`` and ``1 - e2^2 = 4 w / (w + 1)^2``, so ``xi2 > 0``; ``epsilon2``
    has the sign of ``w - 1``, which is the sign of ``e2``, so ``u z = -k2 xi2 epsilon2
    rho2 e2 <= 0``.

    Returns
    -------
    Check
        ``cascade.pushes_back``; ``data`` holds ``xi2`` and ``epsilon2`` in ``w``.
    """
    e, eps, xi, u, k2, x2, r, rho2 = deployed_transform(1)
    w = sp.Symbol("w", positive=True)
    on = {x2[0]: r[0] + rho2[0] * (w - 1) / (w + 1)}
    xi_w = sp.factor(sp.simplify(xi[0].xreplace(on)))
    eps_w = sp.simplify(sp.expand_log(eps[0].xreplace(on), force=True))
    e_w = sp.simplify(e[0].xreplace(on))
    xi_positive = bool(xi_w.is_positive)
    eps_is_log_w = _zero(eps_w - sp.log(w))
    e_sign = _zero(e_w - (w - 1) / (w + 1))
    u_is = _zero(u[0].xreplace(on) + k2 * xi_w * eps_w)
    ok = xi_positive and eps_is_log_w and e_sign and u_is
    return Check("cascade.pushes_back", ok,
                 f"on |e2| < 1 (e2 = (w-1)/(w+1), w > 0): xi2 = {xi_w} > 0, epsilon2 = log(w) "
                 "has the sign of e2, so u (x2 - r) = -k2 xi2 epsilon2 rho2 e2 <= 0"
                 if ok else f"not shown: xi2 = {xi_w}, epsilon2 = {eps_w}, e2 = {e_w}",
                 {"xi2": str(xi_w), "epsilon2": str(eps_w)})


def check_velocity_tube() -> Check:
    """``rho2(0) = width_start``, ``rho2(t) >= width_floor`` and ``|rho2_dot| <= l
    (width_start - width_floor)`` for ``t >= 0``, on the deployed expression (the exponent
    clamp at -80 inactive: ``l t <= 80``; beyond, ``rho2`` is the floor plus
    ``(width_start - width_floor) e^-80``, also above the floor).

    Returns
    -------
    Check
        ``cascade.velocity_tube``; ``data`` holds the reduced ``rho2``.
    """
    t = sp.Symbol("t", nonnegative=True)
    floor, gap, decay = (sp.Symbol(s, positive=True) for s in ("rho2_inf", "g", "l"))
    (rho2,) = sympy_expressions(cascade.velocity_tube(1), {
        "t": [t], "width_start": [floor + gap], "width_floor": [floor], "decay": [decay]})
    s = sp.Symbol("s", nonnegative=True)       # s = l t <= 80: the clamp inactive
    expr = on_domain(rho2[0], {t: s / decay}, {-sp.Integer(80): 1})
    expr = sp.simplify(expr.xreplace({t: s / decay}))
    at_zero = sp.simplify(expr.xreplace({s: 0}) - (floor + gap)) == 0
    above = bool(sp.simplify(expr - floor).is_positive)
    rate = sp.simplify(sp.diff(expr, s) * decay)       # d rho2 / dt = l d rho2 / ds
    # exp(-s) = 1/(1 + v), v >= 0, is a bijection of s >= 0 onto (0, 1]
    v = sp.Symbol("v", nonnegative=True)
    rate_v = sp.factor(sp.simplify(rate.xreplace({sp.exp(-s): 1 / (1 + v)})))
    rate_bound = bool(sp.factor(decay * gap + rate_v).is_nonnegative) and bool(
        (-rate_v).is_nonnegative) and rate_v.has(v)
    ok = at_zero and above and rate_bound
    return Check("cascade.velocity_tube", ok,
                 f"rho2 = {expr} (s = l t): rho2(0) = width_start, rho2 > rho2_inf, "
                 "-l (rho2(0) - rho2_inf) <= rho2_dot <= 0" if ok
                 else f"not shown for rho2 = {expr}", {"rho2": str(expr)})


def sampled_cascade_check(spec, tube, min_width: float) -> Check:
    """``cascade.sampled``: the sampled cascade's certificate
    (:func:`~stt_codegen.verify.cascade_sampled.check_cascade_sampled`) for the deployed
    second stage and the spec's declared plants, with its margins and the lowest certified
    rate (:func:`~stt_codegen.design.cascade_gain.lowest_certified_rate`).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.
    tube : TubeDesign
        The position tube; the second stage is :func:`judged_stage`'s.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    Check
        PASS when the certificate holds at the spec's rate; FAIL with its figures otherwise.
    """
    from ..design.cascade_gain import lowest_certified_rate
    from .cascade_sampled import cascade_check_of
    stage, derivation = judged_stage(spec, tube, min_width)
    result = cascade_check_of(tube, spec, stage)
    rate = lowest_certified_rate(tube, spec, passes_at_rate=result.passed)
    lowest = (f"lowest certified rate {rate:g} Hz (on the two-digit grid, a second stage "
              "derived there)" if rate is not None else
              f"no rate up to {tube.rate_hz * 16:g} Hz is certified")
    words = result.data["class"]
    if result.passed:
        detail = (f"proved: every plant with {words} keeps |e1| < 1 and |e2| < 1 at and "
                  f"between samples at {tube.rate_hz:g} Hz over [0, "
                  f"{result.data['horizon']:.4g}] s, with k1 = {stage.position_gain:.4g}, "
                  f"k2 = {stage.velocity_gain:.4g}, rho2 from {max(stage.width_start):.4g} "
                  f"to {min(stage.width_floor):.4g} (l = {stage.decay:.4g}): |e1| <= "
                  f"{result.max_abs_e1:.3g}, |e2| <= {result.max_abs_e2:.3g} at the "
                  f"samples; room >= {result.position_margin:.3g} of the position tube's "
                  f"half-width and {result.velocity_margin:.3g} of rho2 between samples "
                  f"(least at t = {result.time:.4f} s, dimension {result.dimension}); "
                  f"|u_i| <= {[round(v, 4) for v in result.peak_input]}, |x2_i| <= "
                  f"{[round(v, 4) for v in result.peak_velocity]}; {lowest}")
    else:
        detail = (f"not proved at {tube.rate_hz:g} Hz for plants with {words}: "
                  f"{result.reason}; {lowest}")
    data = {**result.data, "passed": result.passed, "reason": result.reason,
            "time": result.time, "dimension": result.dimension, "lowest_rate_hz": rate,
            "gains": derivation}
    return Check("cascade.sampled", result.passed, detail, data)


def judged_stage(spec, tube, min_width: float) -> tuple:
    """The second stage ``verify`` judges: the one the design deploys
    (:func:`~stt_codegen.design.cascade_gain.certified_stage` within ``spec.input_bound``);
    when no certified shape keeps the bound, the first certified one (its peak input is
    then reported beyond the bound); when none is certified, the first shape's (to report
    its figures).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.
    tube : TubeDesign
        The position tube.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    stage : SecondStage
    derivation : dict
        As :func:`~stt_codegen.design.cascade_gain.derived_second_stage`.
    """
    from ..design.cascade_gain import certified_stage, derived_second_stage
    for bound in ((spec.input_bound, None) if spec.input_bound is not None else (None,)):
        certified, derivation = certified_stage(tube, spec, min_width, bound)
        if certified is not None:      # a shape is certified (None: none is)
            return certified, derivation
    order = spec.second_order
    return derived_second_stage(tube, min_width, order.input_gain,
                                order.drift_bound + spec.disturbance_amplitude,
                                order.initial_velocity)


def cascade_input_bound_check(spec, tube, min_width: float) -> Check:
    """``cascade.input_bound``: the sampled cascade's certified peak of every physical
    input ``|u_i|`` (force or torque) within ``[actuator] input_bound``.

    The certificate (:mod:`.cascade_sampled`) bounds ``|u_k,i| <= (2 k2 / rho2(t_k))
    phi(E2_k,i)`` at every sample for every plant of the class; the deployed input is held
    between samples, so the bound holds at every instant of ``[0, 1.1 t_c]``
    (docs/second-order.md, "Force limits").

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model`` and ``input_bound``.
    tube : TubeDesign
        The position tube; the second stage is :func:`judged_stage`'s.
    min_width : float
        ``gamma_d,min`` of the tube's certificate.

    Returns
    -------
    Check
        PASS when the certificate holds and every peak is within its bound. Data:
        ``input_bound``, ``peak``, ``time`` (per input), ``margin`` (the smallest
        ``(bound - peak) / bound``), ``inputs``, ``unit``, ``horizon``.
    """
    from ..rounding import distinct
    from .cascade_sampled import cascade_check_of
    bound, names, unit = spec.input_bound, spec.input_names, spec.input_unit
    stage, _ = judged_stage(spec, tube, min_width)
    result = cascade_check_of(tube, spec, stage)
    margin = min((b - p) / b for p, b in zip(result.peak_input, bound))
    data = {"input_bound": list(bound), "peak": list(result.peak_input),
            "time": list(result.peak_input_time), "margin": margin if result.passed else
            -float("inf"), "inputs": list(names), "unit": unit,
            "horizon": result.data.get("horizon", 0.0)}
    if not result.passed:
        return Check("cascade.input_bound", False, "no bound on the cascade's input is "
                     f"proved: the sampled cascade is not certified ({result.reason})", data)
    each = ", ".join(f"|{name}| <= {distinct(p, b, 4)} {unit} (bound {b:g} {unit}, at t = "
                     f"{t:.3f} s)" for name, p, b, t in zip(names, result.peak_input, bound,
                                                            result.peak_input_time))
    ok = all(p <= b for p, b in zip(result.peak_input, bound))
    detail = (f"the cascade asks at most {each} at every sample on [0, "
              f"{data['horizon']:.4g}] s, held between samples, for every plant of the "
              f"certified class (k2 = {stage.velocity_gain:.4g}): margin {margin:.3g} of the "
              "bound")
    if not ok:
        over = [name for name, p, b in zip(names, result.peak_input, bound) if p > b]
        detail += (f"; beyond the bound in {', '.join(over)} (no certified second stage "
                   "keeps it on this tube: a longer prescribed_time may)")
    return Check("cascade.input_bound", ok, detail, data)


def plant_within_class_check(spec) -> Check:
    """``cascade.plant_within_assumptions``: the spec's simulated second-order plant lies in
    the class ``cascade.sampled`` certifies
    (:func:`~stt_codegen.verify.cascade_sampled.model_within_class`).

    Parameters
    ----------
    spec : Spec
        With a second-order ``plant.model``.

    Returns
    -------
    Check
        PASS when the model with its parameters is in the class, with the figures.
    """
    from .plant_within import plant_within_assumptions
    return plant_within_assumptions(spec)


def cascade_checks(max_n: int = 2) -> list[Check]:
    """Every check of this module (``n = 1..max_n`` where the dimension matters).

    Parameters
    ----------
    max_n : int, optional
        Largest number of positions proved.

    Returns
    -------
    list of Check
        The transform, Jacobian and Lyapunov derivative for each ``n``, then
        ``cascade.pushes_back`` and ``cascade.velocity_tube`` (not ``cascade.sampled`` nor
        ``cascade.rate``, which need a design).
    """
    out = []
    for n in range(1, max_n + 1):
        out += [check_transform(n), check_jacobian(n), check_lyapunov_derivative(n)]
    return out + [check_pushes_back(), check_velocity_tube()]
