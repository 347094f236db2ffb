"""``stt-codegen bench alpha [SPEC]``: the implicit alpha step of (11), measured.

Two studies, whose figures docs/decisions.md (decision on the implicit step) quotes:

* **Newton iterations.** The model's backward-Euler step
  (:func:`stt_codegen.tube.model.implicit_alpha_update`) with ``k`` Newton iterations,
  ``k = 1 .. NEWTON_ITERATIONS + 1``, against the bisection root
  (:func:`stt_codegen.tube.reference.implicit_alpha_root`) on an adversarial batch of
  100 000 steps: ``psi`` in ``[-3, 5]`` (jumps far past the singularity), ``alpha`` 0 or
  exponential, ``dt`` from 1e-5 to 1 s, ``kappa = 5``. The error is
  ``|a_k - root| / max(1, |root|)``, largest over the batch.
* **Convergence in dt.** The deployed ``alpha`` sequence of SPEC's design at its rate
  ``r``, at ``2 r`` and at ``4 r`` (:func:`stt_codegen.design.samples.sample_tube`),
  against a Radau solution of (11) (rtol 1e-10, atol 1e-12, steps of at most 10 ms) over
  ``1.1 t_c``, compared at the instants of rate ``r``. Backward Euler is first order:
  the error halves with ``dt``, and the Richardson extrapolation ``2 a_2r - a_r`` is much
  closer to the solution than either.

``tests/test_alpha_step.py`` asserts the properties (the batch within 1e-12 of the root,
one iteration fewer not, the deployed rate's error and its first order); this command
prints the figures.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import design_tube
from stt_codegen.spec.loader import load_spec
from stt_codegen.tube import reference as R
from stt_codegen.tube.model import implicit_alpha_update
from stt_codegen.tube.parameters import NEWTON_ITERATIONS, TubeDesign
from .report import machine, machine_line, table

__all__ = ["RATE_FACTORS", "format_alpha_report", "run_alpha_bench"]

#: The adversarial batch: size, seed, and the adaptive law's kappa.
BATCH = 100_000
SEED = 0
KAPPA = 5.0
#: The stiff reference: Radau's tolerances and largest step, seconds.
RTOL, ATOL, MAX_STEP = 1e-10, 1e-12, 0.01
#: Rates compared, as multiples of the design's.
RATE_FACTORS = (1, 2, 4)


def adversarial_batch(count: int = BATCH, seed: int = SEED) -> tuple[np.ndarray, ...]:
    """``(alpha, psi, theta, dt)`` of the adversarial batch, each of shape ``(count,)``."""
    rng = np.random.default_rng(seed)
    psi = rng.uniform(-3, 5, count)
    alpha = rng.choice([0.0, 1.0], count) * rng.exponential(1.0, count)
    theta = 0.01 * (1 - np.tanh(psi - 1.0))
    dt = rng.choice([1e-5, 1e-4, 1e-3, 1e-2, 0.1, 1.0], count)
    return alpha, psi, theta, dt


def newton_errors(count: int = BATCH) -> list[dict[str, Any]]:
    """Largest relative error of ``k`` Newton iterations on the batch, per ``k``."""
    alpha, psi, theta, dt = adversarial_batch(count)
    root = R.implicit_alpha_root(alpha, psi, theta, dt, KAPPA)
    a, p, th, h = (ca.SX.sym(n) for n in ("a", "p", "th", "h"))
    rows = []
    for k in range(1, NEWTON_ITERATIONS + 2):
        step = ca.Function("step", [a, p, th, h],
                           [implicit_alpha_update(a, p, th, h, KAPPA, iterations=k)])
        got = np.array(step.map(count)(alpha, psi, theta, dt)).ravel()
        error = np.abs(got - root) / np.maximum(1.0, np.abs(root))
        rows.append({"iterations": k, "max_relative_error": float(error.max()),
                     "deployed": k == NEWTON_ITERATIONS})
    return rows


def convergence(design: TubeDesign) -> dict[str, Any]:
    """Error of the deployed ``alpha`` against Radau at the design's rate times 1, 2, 4."""
    horizon = 1.1 * design.prescribed_time

    def rhs(t, a):
        return R.adaptive_law(design, t, a)[0][0]

    def jac(t, a):
        return np.diag(R.adaptive_law(design, t, a)[1][0])

    exact = solve_ivp(rhs, (0.0, horizon), np.zeros(2 * design.dimension), method="Radau",
                      rtol=RTOL, atol=ATOL, jac=jac, dense_output=True, max_step=MAX_STEP)
    if exact.status != 0:
        raise RuntimeError(f"Radau failed: {exact.message}")
    runs = {}
    for factor in RATE_FACTORS:
        samples = sample_tube(dataclasses.replace(design, rate_hz=factor * design.rate_hz),
                              horizon)
        runs[factor] = samples.alpha[::factor]
    t = sample_tube(design, horizon).t
    reference = exact.sol(np.minimum(t, horizon)).T
    rows, previous = [], None
    for factor in RATE_FACTORS:
        error = float(np.abs(runs[factor] - reference).max())
        rows.append({"rate_hz": factor * design.rate_hz, "max_abs_error": error,
                     "ratio_to_previous": None if previous is None else previous / error})
        previous = error
    richardson = float(np.abs(2 * runs[2] - runs[1] - reference).max())
    return {"horizon_s": horizon, "max_abs_alpha": float(np.abs(reference).max()),
            "rates": rows, "richardson_max_abs_error": richardson,
            "radau": {"rtol": RTOL, "atol": ATOL, "max_step_s": MAX_STEP,
                      "evaluations": int(exact.nfev)}}


def run_alpha_bench(spec_arg: str = "omnirobot-s1") -> dict[str, Any]:
    """Both studies; the convergence one on ``spec_arg``'s design.

    Parameters
    ----------
    spec_arg : str, optional
        A bundled case name or a spec file; its design's ``alpha`` is integrated for the
        convergence study.

    Returns
    -------
    dict
        ``spec`` (name), ``batch`` and ``kappa`` (of the Newton study), ``newton`` (rows of
        iterations and largest relative error against the bisection root), ``convergence``
        (error of the deployed ``alpha`` against Radau per rate, Hz) and ``machine``.

    Raises
    ------
    SpecError
        An invalid or unknown spec.
    DesignError
        The spec has no design.
    """
    spec = load_spec(spec_arg)
    design = design_tube(spec).tube
    return {"spec": spec.name, "batch": BATCH, "kappa": KAPPA, "newton": newton_errors(),
            "convergence": convergence(design), "machine": machine()}


def format_alpha_report(report: dict[str, Any]) -> str:
    """The human-readable tables of :func:`run_alpha_bench`'s result.

    Parameters
    ----------
    report : dict
        The result of :func:`run_alpha_bench`.

    Returns
    -------
    str
        The tables and the machine line, lines separated by newlines.
    """
    newton = [[str(r["iterations"]) + (" (deployed)" if r["deployed"] else ""),
               f"{r['max_relative_error']:.2g}"] for r in report["newton"]]
    conv = report["convergence"]
    rates = [[f"{r['rate_hz']:g} Hz", f"{r['max_abs_error']:.3g}",
              "-" if r["ratio_to_previous"] is None else f"{r['ratio_to_previous']:.3g}"]
             for r in conv["rates"]]
    return "\n".join([
        f"Newton iterations on {report['batch']} adversarial steps (kappa = {report['kappa']:g}),"
        " against the bisection root:",
        table(["iterations", "largest relative error"], newton),
        f"deployed alpha of {report['spec']} against Radau (rtol {conv['radau']['rtol']:g}) "
        f"over {conv['horizon_s']:g} s (largest |alpha| {conv['max_abs_alpha']:.3g}):",
        table(["rate", "largest error", "halving dt divides it by"], rates),
        f"Richardson 2 a(2r) - a(r): largest error {conv['richardson_max_abs_error']:.3g}",
        machine_line(report["machine"])])

