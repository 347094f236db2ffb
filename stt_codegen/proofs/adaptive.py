"""Adaptive law (11): non-negativity, an explicit tight bound, and the singularity.

``alpha_dot = theta/(psi + alpha)^2 - kappa alpha``, ``alpha(0) = 0``,
``theta = theta0 (1 - tanh(psi - mu))`` (``sign`` replaced by ``tanh``), one
scalar law per (dimension, side), with ``psi_L = beta_U - rho_L`` and
``psi_U = rho_U - beta_L``; ``psi`` is a function of time only.

Results (proved in :func:`adaptive_law_checks`, tested in
:func:`check_adaptive_law_numeric`):

* ``alpha >= 0`` for all ``t`` (``theta >= 0``, so ``alpha_dot >= -kappa alpha``).
* With ``psi(t) >= psi_min`` for all ``t`` and ``psi + alpha > 0``:
  ``alpha(t) <= alpha_max``, the unique root ``a > max(0, -psi_min)`` of
  ``kappa a (psi_min + a)^2 = theta_sup``, ``theta_sup = theta0 (1 - tanh(psi_min
  - mu))``. The bound is tight: it is the equilibrium of (11) for
  ``psi == psi_min``.
* ``psi + alpha`` stays positive iff it starts positive: if ``psi(0) > 0`` and
  ``|psi_dot| <= L``, then ``psi + alpha >= y_min = min(psi(0), mu,
  sqrt(theta0/(L + kappa alpha_max)))`` and ``|alpha_dot| <= max(theta_sup/y_min^2,
  kappa alpha_max)``. If ``psi(0) < 0``, ``alpha`` reaches ``-psi`` in finite time
  with infinite slope (``alpha_dot -> +oo``): ``gamma`` is then not C^1 and
  Lemma 3.3 fails. ``kappa = 0`` makes ``alpha`` unbounded (``alpha^3`` grows
  linearly), ``theta0 = 0`` switches the adaptation off.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Callable, Mapping

import mpmath
import numpy as np
import sympy as sp

from .check import Check
from .deployed import trigger, trigger_clamped

__all__ = [
    "theta",
    "theta_zero_threshold",
    "alpha_upper_bound",
    "alpha_rate_bound",
    "adaptive_law_form",
    "adaptive_law_checks",
    "simulate_alpha",
    "adversarial_psi_signals",
    "check_adaptive_law_numeric",
]

PsiFn = Callable[[float], float]


def theta(psi: float | np.ndarray, theta0: float, mu: float) -> float | np.ndarray:
    """Trigger of (11): ``theta0 (1 - tanh(psi - mu))``, in ``[0, 2 theta0)``.

    Parameters
    ----------
    psi : float or ndarray
        The conflict distance ``psi_i^lambda`` of (11), state units, any shape.
    theta0 : float
        The trigger's gain ``theta_o > 0``.
    mu : float
        The conflict tolerance ``mu > 0``, state units.

    Returns
    -------
    float or ndarray
        ``theta_i^lambda``, the shape of ``psi``.
    """
    return theta0 * (1.0 - np.tanh(psi - mu))


def theta_zero_threshold() -> float:
    """Smallest double ``y`` with ``1 - tanh(y) == 0`` in numpy (about 19.06).

    For ``psi - mu`` beyond it ``theta`` is exactly 0 in floating point, so
    (11) reduces to ``alpha_dot = -kappa alpha``: still ``alpha >= 0``.

    Returns
    -------
    float
        The threshold (state units, as ``psi - mu``).
    """
    lo, hi = 1.0, 40.0
    while np.nextafter(lo, hi) < hi:
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if 1.0 - np.tanh(mid) == 0.0:
            hi = mid
        else:
            lo = mid
    return hi


def _theta_sup_upper(psi_min: float, theta0: float, mu: float) -> Fraction:
    """Rigorous upper bound of ``theta0 (1 - tanh(psi_min - mu))`` as a Fraction."""
    iv = mpmath.iv
    old = iv.dps
    iv.dps = 40
    try:
        y = iv.mpf(psi_min) - iv.mpf(mu)
        # 1 - tanh(y) = 2/(1 + e^{2y})
        val = iv.mpf(theta0) * 2 / (1 + iv.exp(2 * y))
        up = val.b
    finally:
        iv.dps = old
    return Fraction(str(mpmath.nstr(mpmath.mpf(up) * (1 + mpmath.mpf(10) ** -30), 45)))


def alpha_upper_bound(psi_min: float, theta0: float, kappa: float, mu: float) -> float:
    """Certified ``alpha_max``: ``alpha(t) <= alpha_max`` for all ``t``.

    ``alpha_max`` is the root ``a > c = max(0, -psi_min)`` of
    ``f(a) = kappa a (psi_min + a)^2 = theta_sup``; ``f(c) = 0`` and
    ``f'(a) = kappa (psi_min + a)(psi_min + 3 a) > 0`` on ``a > c``, so the root
    is unique. It is bracketed by bisection in exact rational arithmetic against
    an interval-arithmetic upper bound of ``theta_sup``; the returned double
    satisfies ``f(alpha_max) >= theta_sup`` exactly.

    Parameters
    ----------
    psi_min : float
        Lower bound of ``psi(t)`` over all time (may be negative).
    theta0, kappa, mu : float
        Parameters of (11), all > 0.

    Returns
    -------
    float
        ``alpha_max``, state units, rounded up.

    Raises
    ------
    ValueError
        ``theta0``, ``kappa`` or ``mu`` is not positive.
    """
    if not (theta0 > 0 and kappa > 0 and mu > 0):
        raise ValueError("theta0, kappa and mu must be > 0")
    ts = _theta_sup_upper(psi_min, theta0, mu)
    p, k = Fraction(psi_min), Fraction(kappa)
    c = max(Fraction(0), -p)

    def f(a: Fraction) -> Fraction:
        return k * a * (p + a) ** 2

    step = Fraction(1)
    while f(c + step) < ts:
        step *= 2
    lo, hi = c, c + step
    for _ in range(200):
        mid = Fraction((float(lo) + float(hi)) / 2)
        if mid <= lo or mid >= hi:
            break
        if f(mid) >= ts:
            hi = mid
        else:
            lo = mid
    out = float(hi)
    if Fraction(out) < hi:  # float(hi) rounded down: step up one ulp
        out = float(np.nextafter(out, np.inf))
    return out


def alpha_rate_bound(
    psi0: float, psi_min: float, psi_dot_max: float, theta0: float, kappa: float, mu: float
) -> tuple[float, float]:
    """Lower bound of ``psi + alpha`` and bound of ``|alpha_dot|``.

    Returns ``(y_min, alpha_dot_max)`` with
    ``y_min = min(psi0, mu, sqrt(theta0/(psi_dot_max + kappa alpha_max)))``:
    below ``min(mu, .)``, ``psi = y - alpha < mu`` so ``theta > theta0`` and
    ``y_dot >= -psi_dot_max + theta0/y^2 - kappa alpha_max > 0``. Then
    ``-kappa alpha_max <= alpha_dot <= theta_sup/y_min^2``.
    Requires ``psi0 > 0``.

    Parameters
    ----------
    psi0 : float
        ``psi(0)``, > 0, state units.
    psi_min : float
        Lower bound of ``psi(t)`` over all time, state units.
    psi_dot_max : float
        Bound of ``|psi_dot|``, state units per second.
    theta0, kappa, mu : float
        Parameters of (11), all > 0 (``kappa`` in 1/s, ``mu`` in state units).

    Returns
    -------
    y_min : float
        Lower bound of ``psi + alpha``, state units, rounded down.
    alpha_dot_max : float
        Bound of ``|alpha_dot|``, state units per second, rounded up.

    Raises
    ------
    ValueError
        ``psi0 <= 0``, or a parameter of (11) not positive.
    """
    if not psi0 > 0:
        raise ValueError("psi(0) must be > 0")
    a_max = alpha_upper_bound(psi_min, theta0, kappa, mu)
    y_min = min(psi0, mu, float(np.sqrt(theta0 / (psi_dot_max + kappa * a_max))))
    y_min = float(np.nextafter(y_min, 0.0))
    ts = float(_theta_sup_upper(psi_min, theta0, mu))
    return y_min, float(np.nextafter(max(ts / y_min**2, kappa * a_max), np.inf))


def adaptive_law_form() -> dict:
    """The symbolic part of :func:`adaptive_law_checks`, for every ``theta0``, ``kappa``,
    ``mu`` > 0 and every ``psi``.

    On the deployed trigger (``pieces.conflict`` printed by the SymPy printer, in the
    symbols ``psi`` real, ``theta0`` and ``mu`` positive; ``deployed.trigger`` proves it
    equal to ``theta0 (1 - tanh(psi - mu))`` where its clamps are inactive): it is
    positive with its clamps, ``d theta/d psi = -theta0 sech^2(psi - mu)``, and the
    algebra of the upper bound's proof. Independent of the design: :mod:`.proofs` caches
    it.

    Returns
    -------
    dict
        ``trigger`` (the clamped deployed trigger, str), ``trigger_positive`` (bool),
        ``upper_bound_proved`` (bool) and ``df_da`` (``d/da kappa a (psi_min + a)^2``,
        str).
    """
    clamped, (p, th0, mu_s) = trigger_clamped()
    th = trigger()
    kap = sp.Symbol("kappa", positive=True)
    pm, aa, ts = sp.symbols("psi_min a theta_sup", real=True)
    # d theta/d psi of the deployed trigger (0 where a clamp acts: still <= 0)
    dth = sp.simplify((sp.diff(th, p) + th0 * sp.sech(p - mu_s) ** 2).rewrite(sp.exp))
    fa = kap * aa * (pm + aa) ** 2
    dfa = sp.factor(sp.diff(fa, aa))
    dfa_ok = sp.expand(dfa - kap * (pm + aa) * (pm + 3 * aa)) == 0
    split_ok = sp.simplify(ts / (pm + aa) ** 2 - kap * aa - (ts - fa) / (pm + aa) ** 2) == 0
    dinv = sp.diff(1 / (p + aa) ** 2, p)  # = -2/(p + a)^3 < 0 for p + a > 0
    dinv_ok = sp.simplify(dinv + 2 / (p + aa) ** 3) == 0
    return {"trigger": str(clamped), "trigger_positive": bool(clamped.is_positive),
            "upper_bound_proved": bool(dth == 0 and dfa_ok and split_ok and dinv_ok),
            "df_da": str(dfa)}


def adaptive_law_checks(
    psi_min: float,
    theta0: float,
    kappa: float,
    mu: float,
    psi0: float | None = None,
    psi_dot_max: float | None = None,
    form: dict | None = None,
) -> list[Check]:
    """Symbolic checks of the adaptive law (11) for given parameters.

    Parameters
    ----------
    psi_min : float
        ``min_t psi(t)`` supplied by the design (may be negative).
    theta0, kappa, mu : float
        Parameters of (11).
    psi0 : float, optional
        ``psi(0)``; enables the singularity check (``psi + alpha > 0``).
    psi_dot_max : float, optional
        ``sup_t |psi_dot(t)|`` (e.g. from :func:`.lemma.reach_rate_bound` and
        :func:`.lemma.bump_rate_bound`); with ``psi0`` gives an explicit bound
        of ``|alpha_dot|``, which Lemma 3.3 needs.
    form : dict, optional
        The result of :func:`adaptive_law_form` when already known (the proof cache,
        :mod:`.proofs`); proved here when omitted.

    Returns
    -------
    list of Check
        ``adaptive.parameters``, ``adaptive.nonnegative``,
        ``adaptive.upper_bound`` and, with ``psi0``, ``adaptive.singularity``.
    """
    out: list[Check] = []
    # -- parameters
    bad = [f"{n} = {v}" for n, v in (("theta0", theta0), ("kappa", kappa), ("mu", mu))
           if not v > 0]
    if bad:
        why = "; ".join(bad)
        if not kappa > 0:
            why += (" (kappa = 0: alpha_dot = theta/(psi+alpha)^2 > 0 never decays, "
                    "alpha^3 grows linearly in t: alpha unbounded)")
        out.append(Check("adaptive.parameters", False, f"invalid parameters: {why}",
                         {"theta0": theta0, "kappa": kappa, "mu": mu}))
        return out
    out.append(Check("adaptive.parameters", True,
                     f"theta0 = {theta0}, kappa = {kappa}, mu = {mu} all > 0 (kappa = 0 "
                     "would make alpha unbounded, growing like t^(1/3))",
                     {"theta0": theta0, "kappa": kappa, "mu": mu}))

    proved = adaptive_law_form() if form is None else form
    # -- non-negativity, on the deployed expression with its clamps
    positive = proved["trigger_positive"]
    zthr = theta_zero_threshold()
    out.append(Check(
        "adaptive.nonnegative",
        positive,
        f"the deployed theta = {proved['trigger']} is "
        f"{'proved > 0' if positive else 'NOT proved > 0'} for every psi (theta0 > 0), "
        "so alpha_dot >= -kappa "
        "alpha and alpha(0) = 0 give alpha(t) >= 0 (alpha_dot = theta/psi^2 >= 0 at "
        "alpha = 0). (The numpy oracle's 1 - tanh(psi - mu) rounds to 0 once psi - mu > "
        f"{zthr:.6g}; then alpha_dot = -kappa alpha, still >= 0.)",
        {"theta_zero_threshold": zthr},
    ))
    # -- upper bound
    a_max = alpha_upper_bound(psi_min, theta0, kappa, mu)
    ts_num = float(theta(psi_min, theta0, mu))
    out.append(Check(
        "adaptive.upper_bound",
        proved["upper_bound_proved"],
        f"alpha(t) <= alpha_max = {a_max:.12g}, the root a > max(0, -psi_min) of "
        f"kappa a (psi_min + a)^2 = theta_sup = theta0 (1 - tanh(psi_min - mu)) = "
        f"{ts_num:.6g} (psi_min = {psi_min}). Proof: d theta/d psi = -theta0 "
        "sech^2 <= 0 and d/dpsi (psi+a)^-2 = -2 (psi+a)^-3 < 0, so for psi >= psi_min, "
        "a >= alpha_max: alpha_dot <= theta_sup/(psi_min+a)^2 - kappa a = "
        "(theta_sup - f(a))/(psi_min+a)^2 <= 0, f' = kappa (psi_min+a)(psi_min+3a) > 0. "
        "Tight: the equilibrium of (11) for psi == psi_min. Assumes psi + alpha > 0 "
        "(adaptive.singularity)",
        {"alpha_max": a_max, "theta_sup": ts_num, "psi_min": psi_min,
         "df_da": proved["df_da"]},
    ))
    # -- singularity psi + alpha = 0
    if psi0 is not None:
        if not psi0 > 0:
            out.append(Check(
                "adaptive.singularity",
                False,
                f"psi(0) = {psi0} <= 0: psi + alpha starts at {psi0}; "
                + ("alpha_dot(0) = theta/0^2 is infinite"
                   if psi0 == 0 else
                   "alpha_dot >= theta0/(psi+alpha)^2 - kappa alpha drives alpha to -psi in "
                   "finite time with alpha_dot -> +oo") +
                ": alpha is not C^1, gamma_dot is unbounded and Lemma 3.3 fails",
                {"psi0": psi0},
            ))
        elif psi_dot_max is None:
            out.append(Check(
                "adaptive.singularity",
                True,
                f"psi(0) = {psi0} > 0 and y = psi + alpha cannot reach 0 from above "
                "(theta/y^2 -> +oo dominates any bounded psi_dot); give psi_dot_max "
                "for an explicit bound of alpha_dot",
                {"psi0": psi0},
            ))
        else:
            y_min, ad_max = alpha_rate_bound(psi0, psi_min, psi_dot_max, theta0, kappa, mu)
            out.append(Check(
                "adaptive.singularity",
                True,
                f"psi(0) = {psi0} > 0, |psi_dot| <= {psi_dot_max}: psi + alpha >= y_min = "
                f"min(psi(0), mu, sqrt(theta0/(L + kappa alpha_max))) = {y_min:.6g} "
                f"(below it y_dot > 0), hence |alpha_dot| <= {ad_max:.6g}",
                {"psi0": psi0, "psi_dot_max": psi_dot_max, "y_min": y_min,
                 "alpha_dot_max": ad_max},
            ))
    return out


def simulate_alpha(
    psi: PsiFn,
    t_end: float,
    theta0: float,
    kappa: float,
    mu: float,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    max_step: float = np.inf,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate (11) with ``solve_ivp`` (Radau, exact Jacobian).

    Parameters
    ----------
    psi : callable
        ``psi(t) -> float``, the conflict distance, state units.
    t_end : float
        End of the integration, s.
    theta0, kappa, mu : float
        Parameters of (11) (``kappa`` in 1/s, ``mu`` in state units).
    rtol, atol : float, optional
        Tolerances of ``solve_ivp``.
    max_step : float, optional
        Largest step of the integrator, s.

    Returns
    -------
    (t, alpha, psi_values) : arrays
        Accepted steps of the integrator.

    Raises
    ------
    RuntimeError
        The integrator failed.
    """

    def rhs(t: float, a: np.ndarray) -> np.ndarray:
        ps = psi(t)
        return np.array([theta(ps, theta0, mu) / (ps + a[0]) ** 2 - kappa * a[0]])

    def jac(t: float, a: np.ndarray) -> np.ndarray:
        ps = psi(t)
        return np.array([[-2 * theta(ps, theta0, mu) / (ps + a[0]) ** 3 - kappa]])

    # scipy.integrate takes ~0.4 s to import and only this numeric cross-check needs it
    from scipy.integrate import solve_ivp

    sol = solve_ivp(rhs, (0.0, t_end), [0.0], method="Radau", jac=jac, rtol=rtol,
                    atol=atol, max_step=max_step)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    ps = np.array([psi(t) for t in sol.t])
    return sol.t, sol.y[0], ps


def _smooth_step(t: float, t0: float, slope: float) -> float:
    return 0.5 * (1.0 + np.tanh(slope * (t - t0)))


def adversarial_psi_signals(psi0: float, psi_min: float) -> dict[str, PsiFn]:
    """Test signals ``psi(t)`` with ``psi(0) ~ psi0`` and ``min psi = psi_min``.

    Step-like drops (slopes 50 and 2000), a circumvent-like bump (eqs. (7)-(8)
    with ``k = 0.01``), an oscillation between the two levels, and a drop held
    for long (where ``alpha`` approaches ``alpha_max``).

    Parameters
    ----------
    psi0 : float
        The signals' value at ``t = 0``, state units.
    psi_min : float
        Their minimum, state units.

    Returns
    -------
    dict of str to callable
        ``name -> psi(t)``: ``step``, ``steep_step``, ``bump_like``, ``oscillating``, ``hold``.
    """
    drop = psi0 - psi_min

    def bump_like(t: float) -> float:
        m, r, k = 3.0, 2.0, 0.01
        s = t - m
        b = np.exp(-k * s * s / (r * r - s * s)) if abs(s) < r else 0.0
        return psi0 - drop * b

    return {
        "step": lambda t: psi0 - drop * _smooth_step(t, 1.0, 50.0),
        "steep_step": lambda t: psi0 - drop * _smooth_step(t, 1.0, 2000.0),
        "bump_like": bump_like,
        "oscillating": lambda t: psi_min + drop * 0.5 * (1.0 + np.cos(2 * np.pi * t / 0.7)),
        "hold": lambda t: psi0 - drop * _smooth_step(t, 0.5, 20.0),
    }


def check_adaptive_law_numeric(
    signals: Mapping[str, PsiFn],
    t_end: float,
    theta0: float,
    kappa: float,
    mu: float,
    psi_min: float | None = None,
) -> Check:
    """Integrate (11) on each signal and compare with the proved bounds.

    For each signal: ``psi_min`` (given, or the minimum over the accepted
    steps and a 20001-point grid), ``alpha_max`` from
    :func:`alpha_upper_bound`; PASS when ``0 <= alpha <= alpha_max`` (relative
    slack 1e-9 for the integrator) and ``psi + alpha > 0`` at every step.
    ``data`` holds per signal the peak ``alpha``, ``alpha_max``, their ratio
    and the least ``psi + alpha``.

    Parameters
    ----------
    signals : mapping of str to callable
        ``name -> psi(t)`` (e.g. :func:`adversarial_psi_signals`).
    t_end : float
        End of each integration, s.
    theta0, kappa, mu : float
        Parameters of (11) (``kappa`` in 1/s, ``mu`` in state units).
    psi_min : float, optional
        Lower bound of every ``psi``; default each signal's observed minimum.

    Returns
    -------
    Check
        ``adaptive.numeric``.
    """
    per: dict[str, dict[str, float]] = {}
    fails: list[str] = []
    for name, fn in signals.items():
        t, al, ps = simulate_alpha(fn, t_end, theta0, kappa, mu)
        grid = np.linspace(0.0, t_end, 20001)
        pmin = psi_min if psi_min is not None else float(
            min(ps.min(), min(fn(x) for x in grid)))
        amax = alpha_upper_bound(pmin, theta0, kappa, mu)
        y = ps + al
        per[name] = {"psi_min": pmin, "alpha_peak": float(al.max()),
                     "alpha_min": float(al.min()), "alpha_max": amax,
                     "ratio": float(al.max() / amax), "y_min": float(y.min()),
                     "steps": int(t.size)}
        if al.min() < -1e-12:
            fails.append(f"{name}: alpha = {al.min():.3g} < 0 at t = {t[al.argmin()]:.6g}")
        if al.max() > amax * (1 + 1e-9):
            fails.append(f"{name}: alpha = {al.max():.9g} > alpha_max = {amax:.9g} at "
                         f"t = {t[al.argmax()]:.6g}")
        if y.min() <= 0:
            fails.append(f"{name}: psi + alpha = {y.min():.3g} <= 0 at t = {t[y.argmin()]:.6g}")
    summary = ", ".join(f"{n}: peak/alpha_max = {d['ratio']:.4f}, min(psi+alpha) = "
                        f"{d['y_min']:.3g}" for n, d in per.items())
    return Check("adaptive.numeric", not fails,
                 ("; ".join(fails) if fails else
                  f"Radau on {len(per)} psi(t) signals: 0 <= alpha <= alpha_max and "
                  f"psi + alpha > 0 throughout ({summary})"),
                 {"signals": per})
