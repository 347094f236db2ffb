"""``stt-codegen bench stl``: stlpy's scenarios, designed as specs and judged by rtamt.

For each scenario of :mod:`.stl_scenarios` (stlpy's examples, written as specs without hand
choices):

1. the spec is loaded (``Spec.from_dict``); a refusal is reported as "not written";
2. :func:`~stt_codegen.design.search.design_tube` designs and certifies it; when the spec
   has the example's ``[actuator]`` bound and the design within it is refused, the same
   spec without ``[actuator]`` is designed too and reported on its own row ("no bound"),
   so the table says both what the bound costs and whether the task itself is met;
3. the generated C controller runs in closed loop (:func:`~stt_codegen.runtime.simulate.
   simulate`, backend ``c``, disturbance seed 0) over ``[0, t_c]``;
4. rtamt judges the run on the scenario's own formula (:mod:`.stl_judge`): at the samples
   (one per stlpy step) and on the 100 Hz grid. The grid's positions are the closed loop's
   own output, recorded at the controller's rate (1 kHz by default), taken at the grid's
   instants (linear interpolation between two records when the rate is not a multiple
   of 100 Hz).

**stlpy's plan.** stlpy's solvers that run here without a commercial licence
(:func:`solve_with_stlpy`): its ``ScipyGradientSolver`` (SLSQP on the robustness by
shooting; it takes no input or state bounds, so its plan is unbounded) and its
``DrakeMICPSolver`` with Drake's own branch and bound (``--solver drake-bnb``, with
``pip install drake``; Clp on each node; the example's bounds). Its other MICP solvers need
Gurobi or MOSEK. The plan's positions are judged the same way, at the samples and on the
grid, with the positions moving linearly between samples (stlpy's model:
``p[k+1] = p[k] + v[k]`` for the double integrator, ``p[k+1] = p[k] + dt v(theta)`` for
the unicycle, one velocity over the step).
"""

from __future__ import annotations

import contextlib
import io
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from stt_codegen.errors import DesignError, SpecError
from .stl_judge import FINE_PERIOD, robustness, stlpy_robustness
from .stl_scenarios import (ORDER_NOTE, SCENARIOS, SKIPPED, double_integrators, make_scenario,
                            scenario_names, scenario_spec, spec_toml, step_seconds, workspace)

_MISSING = 'stlpy and rtamt are not installed: install the optional extra with pip install ".[stl]"'

__all__ = ["SOLVERS", "format_stl_report", "judge_positions", "run_stl_bench", "run_stl_scenario",
           "solve_with_stlpy"]


def judge_positions(formula: Any, dt: float, horizon_steps: int, output_dim: int,
                    times: np.ndarray, positions: np.ndarray) -> dict[str, float]:
    """rtamt's robustness of a position trajectory at the samples and on the 100 Hz grid.

    Parameters
    ----------
    formula : stlpy.STL.STLFormula
        The scenario's formula.
    dt : float
        One stlpy step, s.
    horizon_steps : int
        The formula's horizon ``T``, steps.
    output_dim : int
        stlpy's output dimension (the positions fill its first two entries).
    times : ndarray, shape (N,)
        Increasing instants covering ``[0, T dt]``, s.
    positions : ndarray, shape (N, 2)
        The planar position at ``times``, linearly interpolated in between.

    Returns
    -------
    dict
        ``{"samples": float, "grid": float, "stlpy_samples": float}``: rtamt at the
        samples, rtamt on the grid, and stlpy's own robustness at the samples (equal to
        the first).
    """
    out: dict[str, float] = {}
    for key, period in (("samples", dt), ("grid", FINE_PERIOD)):
        count = int(round(horizon_steps * dt / period)) + 1
        grid = np.arange(count) * period
        y = np.full((count, output_dim), np.nan)
        y[:, 0] = np.interp(grid, times, positions[:, 0])
        y[:, 1] = np.interp(grid, times, positions[:, 1])
        out[key] = robustness(formula, dt, grid, y, period)
        if key == "samples":
            out["stlpy_samples"] = stlpy_robustness(formula, np.nan_to_num(y))
    return out


#: stlpy's solvers the bench can run: ``scipy`` (``ScipyGradientSolver``) and
#: ``drake-bnb`` (``DrakeMICPSolver`` with Drake's own branch and bound on Clp).
SOLVERS = ("scipy", "drake-bnb")


def _stlpy_solvers() -> Any:
    """``stlpy.solvers``, importable beside today's Drake.

    stlpy 0.3.0 imports ``pydrake.solvers.branch_and_bound`` and ``pydrake.solvers.all``,
    which Drake has since folded into ``pydrake.solvers`` (Drake 1.51 still has
    ``MixedIntegerBranchAndBound``, ``IpoptSolver``... there): without the two names,
    importing ``stlpy.solvers`` fails with Drake installed, its scipy solver included.
    They are given as aliases of ``pydrake.solvers`` when Drake is installed.
    """
    try:
        import pydrake.solvers
    except ImportError:
        pass
    else:
        for old in ("pydrake.solvers.branch_and_bound", "pydrake.solvers.all"):
            sys.modules.setdefault(old, pydrake.solvers)
    # stlpy.solvers prints a warning on stdout for each solver it cannot load
    with contextlib.redirect_stdout(io.StringIO()):
        import stlpy.solvers
    return stlpy.solvers


def solve_with_stlpy(name: str, horizon: int | None = None,
                     solver: str = "scipy") -> dict[str, Any]:
    """stlpy's own plan for the example, from the example's ``x0``.

    ``scipy``: ``ScipyGradientSolver`` with the cost of ``reach_avoid.py`` (double
    integrator) or ``nonlinear_reach_avoid.py`` (unicycle); no bounds (the solver takes
    none). ``drake-bnb``: ``DrakeMICPSolver(solver="bnb")`` (Drake's branch and bound, Clp
    on each node, no licence), maximising the robustness, with the example's control and
    state bounds when the example passes them (``x_min``, ``x_max``: the positions in
    ``[0, x_max]`` of the field of view the example gives, the velocities within its
    bound); double integrators only (the MICP needs a linear system).

    Parameters
    ----------
    name : str
        A key of :data:`~.stl_scenarios.SCENARIOS`.
    horizon : int, optional
        ``T`` in steps instead of the example's.
    solver : str
        One of :data:`SOLVERS`.

    Returns
    -------
    dict
        ``{"solver", "seconds", "plan": (times, positions) or None, "note"}``.
    """
    try:
        solvers = _stlpy_solvers()
    except ImportError as exc:
        return {"solver": solver, "seconds": None, "plan": None,
                "note": f"stlpy.solvers does not import: {exc}"}
    sc = make_scenario(name, horizon)
    system = sc.GetSystem()
    setting = SCENARIOS[name]
    x0 = np.array(setting.x0, dtype=float)
    formula = sc.GetSpecification()
    if solver == "scipy":
        solve = solvers.ScipyGradientSolver(formula, system, x0, sc.T, verbose=False)
        if system.n == 4:      # reach_avoid.py's cost: velocities and inputs
            solve.AddQuadraticCost(1e-1 * np.diag([0.0, 0.0, 1.0, 1.0]), 1e-1 * np.eye(system.m))
        else:                  # nonlinear_reach_avoid.py's: inputs only
            solve.AddQuadraticCost(np.zeros((system.n, system.n)), 1e-3 * np.eye(system.m))
    elif not hasattr(solvers, "DrakeMICPSolver"):
        return {"solver": solver, "seconds": None, "plan": None,
                "note": "Drake is not installed (pip install drake)"}
    elif not hasattr(system, "A"):
        return {"solver": solver, "seconds": None, "plan": None,
                "note": "the MICP needs a linear system"}
    else:
        solve = solvers.DrakeMICPSolver(formula, system, x0, sc.T, solver="bnb",
                                        verbose=False)
        if setting.input_bound is not None:
            u_max = np.array(setting.input_bound, dtype=float)
            solve.AddControlBounds(-u_max, u_max)
        if setting.velocity_bound is not None:
            (_, x_hi), (_, y_hi) = workspace(sc)
            v_max = np.array(setting.velocity_bound, dtype=float)
            solve.AddStateBounds(np.concatenate([[0.0, 0.0], -v_max]),
                                 np.concatenate([setting.position_max or (x_hi, y_hi), v_max]))
    start = time.perf_counter()
    try:
        with contextlib.redirect_stdout(io.StringIO()):   # Drake's B&B announces itself
            x, _, _, _ = solve.Solve()
    except RuntimeError as exc:   # Drake's B&B gives up on some problems
        return {"solver": solver, "seconds": time.perf_counter() - start, "plan": None,
                "note": f"failed: {exc}"}
    seconds = time.perf_counter() - start
    if x is None:
        return {"solver": solver, "seconds": seconds, "plan": None, "note": "no solution"}
    steps = x.shape[1]
    return {"solver": solver, "seconds": seconds, "note": "",
            "plan": (np.arange(steps) * step_seconds(sc), x[:2, :].T)}


def _row(name: str, variant: str) -> dict[str, Any]:
    return {"scenario": name, "variant": variant, "written": False, "designed": False,
            "satisfied": None, "samples": None, "grid": None, "stlpy_samples": None,
            "design_s": None, "peak_u": None, "input_bound": None, "choices": None,
            "reason": "", "advice": {}}


def _design_and_judge(name: str, variant: str, doc: dict[str, Any], sc: Any,
                      output_dim: int, prescribed_time: float | None = None
                      ) -> dict[str, Any]:
    from stt_codegen.design.search import design_tube
    from stt_codegen.runtime.simulate import simulate
    from stt_codegen.spec.deadline import with_deadline
    from stt_codegen.spec.loader import Spec
    row = _row(name, variant)
    row["input_bound"] = doc.get("actuator", {}).get("input_bound")
    try:
        spec = Spec.from_dict(doc)
        if prescribed_time is not None:       # a named time: the spec moved there, as named
            spec = with_deadline(spec, prescribed_time)
    except SpecError as exc:
        row["reason"] = f"not written: {exc}"
        return row
    row["written"] = True
    started = time.process_time()
    try:
        design = design_tube(spec)
    except DesignError as exc:
        row["reason"] = f"not designed: {str(exc).splitlines()[0]}"
        row["advice"] = dict(exc.advice)
        row["design_s"] = time.process_time() - started
        return row
    row["designed"] = True
    row["design_s"] = time.process_time() - started
    row["choices"] = {"tasks": list(design.task_choices), "target": design.target_choice}
    result = simulate(design, backend="c", seed=0)
    row["satisfied"] = bool(result.satisfied)
    row["peak_u"] = [float(v) for v in result.max_abs_u]
    traj = result.trajectory
    dt = step_seconds(sc)
    row.update(judge_positions(sc.GetSpecification(), dt, sc.T, output_dim, traj.t,
                               traj.x[:, :2]))
    return row


def _second_order_rows(name: str, horizon: int | None, disturbance: float | None = None
                       ) -> list[dict[str, Any]]:
    """A double integrator as itself (the cascade at the example's ``|u|`` and ``|v|``);
    when refused naming a ``prescribed_time``, the same spec moved to that time (as the
    refusal names it: :func:`~stt_codegen.spec.deadline.with_deadline`), judged on the
    scenario with the horizon ``T`` (whole steps) that covers it, and the named time over
    stlpy's horizon as ``ratio``."""
    sc = make_scenario(name, horizon)
    doc = scenario_spec(name, horizon, order="second", disturbance=disturbance)
    rows = [_design_and_judge(name, "second order", doc, sc, sc.GetSystem().p)]
    named = rows[0]["advice"].get("prescribed_time")
    if named is not None:
        dt = step_seconds(sc)
        rows[0]["ratio"] = named / (sc.T * dt)
        longer = int(math.ceil(named / dt - 1e-9))
        sc_long = make_scenario(name, longer)
        rows.append(_design_and_judge(name, f"second order, t_c = {named:g} s", doc,
                                      sc_long, sc_long.GetSystem().p, prescribed_time=named))
    return rows


def run_stl_scenario(name: str, horizon: int | None = None, solver: str | None = "scipy",
                     orders: tuple[str, ...] = ("first", "second"),
                     disturbance: float | None = None) -> list[dict[str, Any]]:
    """One scenario: its spec as written and, if that is refused by the bound, without it;
    a double integrator also as itself (second order).

    Parameters
    ----------
    name : str
        A key of :data:`~.stl_scenarios.SCENARIOS` or of :data:`~.stl_scenarios.SKIPPED`.
    horizon : int, optional
        ``T`` in steps instead of the example's.
    solver : str or None
        Also run this solver of stlpy (:data:`SOLVERS`) and judge its plan (on the first
        row); ``None``: none.
    orders : tuple of str
        ``"first"``: the spec as written (a double integrator as the first-order position
        law); ``"second"``: a double integrator as itself (:func:`_second_order_rows`).
    disturbance : float, optional
        ``plant.disturbance_amplitude`` of every spec written (0: stlpy's model); ``None``:
        the project's default.

    Returns
    -------
    list of dict
        One row per variant (module notes): ``scenario``, ``variant`` (``"as written"``,
        ``"no bound"``, ``"second order"``, ``"second order, t_c = <named> s"``), ``written``,
        ``designed``, ``satisfied`` (the project's judge of the C run), ``samples``/``grid``
        (rtamt's robustness), ``stlpy_samples`` (stlpy's own at the samples), ``design_s``
        (CPU s of ``design_tube``, refusal included), ``peak_u``, ``input_bound``,
        ``choices``, ``reason``, ``advice`` (a refusal's named values), ``ratio`` (a named
        ``prescribed_time`` over stlpy's horizon), and on the first row ``spec`` (the TOML
        text) and ``solver`` (stlpy's plan judged: ``{"solver", "seconds", "samples",
        "grid", "note"}``).
    """
    if name in SKIPPED:
        row = _row(name, "skipped")
        row["reason"] = f"not written: {SKIPPED[name]}"
        return [row]
    sc = make_scenario(name, horizon)
    output_dim = sc.GetSystem().p
    rows = []
    if "first" in orders:
        doc = scenario_spec(name, horizon, disturbance=disturbance)
        rows = [_design_and_judge(name, "as written", doc, sc, output_dim)]
        rows[0]["spec"] = spec_toml(doc, f"stlpy {name}, written by stt-codegen bench stl")
        if rows[0]["written"] and not rows[0]["designed"] and "actuator" in doc:
            unbounded = {k: v for k, v in doc.items() if k != "actuator"}
            rows.append(_design_and_judge(name, "no bound", unbounded, sc, output_dim))
    if "second" in orders and name in double_integrators():
        second = _second_order_rows(name, horizon, disturbance)
        second[0]["spec"] = spec_toml(scenario_spec(name, horizon, order="second",
                                                    disturbance=disturbance),
                                      f"stlpy {name} as a double integrator, written by "
                                      "stt-codegen bench stl")
        rows += second
    if solver and rows:
        plan = solve_with_stlpy(name, horizon, solver)
        judged = {"solver": plan["solver"], "seconds": plan["seconds"], "note": plan["note"],
                  "samples": None, "grid": None}
        if plan["plan"] is not None:
            times, positions = plan["plan"]
            scores = judge_positions(sc.GetSpecification(), step_seconds(sc), sc.T,
                                     output_dim, times, positions)
            judged.update(samples=scores["samples"], grid=scores["grid"])
        rows[0]["solver"] = judged
    return rows


def run_stl_bench(names: list[str] | None = None, horizon: int | None = None,
                  solver: str | None = "scipy", specs: Path | None = None,
                  orders: tuple[str, ...] = ("first", "second"),
                  disturbance: float | None = None) -> dict[str, Any]:
    """Every scenario (module notes), one after another in one process.

    Parameters
    ----------
    names : list of str, optional
        Scenarios to run (default: all six written plus ``SteppingStones``, skipped).
    horizon : int, optional
        ``T`` in steps for every scenario instead of the examples'.
    solver : str or None
        Also run this solver of stlpy on each (:data:`SOLVERS`); ``None``: none.
    specs : Path, optional
        Also write each written spec there as ``stlpy-<scenario>.toml`` (a double
        integrator as itself: ``stlpy-<scenario>-second-order.toml``).
    orders : tuple of str
        As :func:`run_stl_scenario`.
    disturbance : float, optional
        As :func:`run_stl_scenario` (``>= 0``).

    Returns
    -------
    dict
        ``{"rows": [...] (:func:`run_stl_scenario`'s rows), "order_note": str}``.

    Raises
    ------
    SpecError
        An unknown scenario name (field ``scenarios``); a negative ``disturbance`` (field
        ``disturbance``); stlpy or rtamt not installed (field ``stl``).
    """
    try:
        import rtamt  # noqa: F401
        import stlpy  # noqa: F401
    except ImportError:
        raise SpecError("stl", _MISSING) from None
    known = scenario_names() + list(SKIPPED)
    names = known if names is None else list(names)
    if solver is not None and solver not in SOLVERS:
        raise SpecError("solver", f"unknown solver {solver!r} (known: {', '.join(SOLVERS)})")
    if disturbance is not None and not disturbance >= 0.0:
        raise SpecError("disturbance", f"must be a number >= 0 (|w_i| of the plant), not "
                                       f"{disturbance!r}")
    for name in names:
        if name not in known:
            raise SpecError("scenarios", f"unknown scenario {name!r} (known: "
                                         f"{', '.join(known)})")
    rows: list[dict[str, Any]] = []
    for name in names:
        rows += run_stl_scenario(name, horizon, solver, orders, disturbance)
    if specs is not None:
        specs.mkdir(parents=True, exist_ok=True)
        for row in rows:
            if "spec" in row:
                tail = "-second-order" if row["variant"] == "second order" else ""
                (specs / f"stlpy-{row['scenario']}{tail}.toml").write_text(row["spec"])
    return {"rows": rows, "order_note": ORDER_NOTE}


def _num(value: float | None, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def format_stl_report(report: dict[str, Any]) -> str:
    """The report of :func:`run_stl_bench` as a Markdown table and its notes.

    Parameters
    ----------
    report : dict
        From :func:`run_stl_bench`.

    Returns
    -------
    str
        The table (one row per scenario and variant) and a note per row with a reason.
    """
    head = ("| scenario | spec | written | designed | satisfied (C) | rtamt samples | "
            "rtamt 100 Hz grid | design CPU (s) | peak \\|u\\| | stlpy's plan: samples / grid "
            "(solve s) |")
    lines = [head, "|" + "---|" * 10]
    notes = []
    for row in report["rows"]:
        bound = row["input_bound"]
        spec = row["variant"] + (f", bound {bound}" if bound else "")
        solver = row.get("solver")
        if solver is None:
            stl = "-"
        elif solver["samples"] is None:
            stl = solver["note"] or "-"
        else:
            stl = (f"{_num(solver['samples'])} / {_num(solver['grid'])} "
                   f"({_num(solver['seconds'], 1)})")
        peak = "-" if row["peak_u"] is None else ", ".join(f"{v:.2f}" for v in row["peak_u"])
        satisfied = "-" if row["satisfied"] is None else ("yes" if row["satisfied"] else "no")
        lines.append(f"| {row['scenario']} | {spec} | {'yes' if row['written'] else 'no'} | "
                     f"{'yes' if row['designed'] else 'no'} | {satisfied} | "
                     f"{_num(row['samples'])} | {_num(row['grid'])} | "
                     f"{_num(row['design_s'], 2)} | {peak} | {stl} |")
        if row["reason"]:
            named = (f" (named over stlpy's horizon: {row['ratio']:.2f})"
                     if row.get("ratio") is not None else "")
            notes.append(f"- {row['scenario']} ({row['variant']}): {row['reason']}{named}")
    return "\n".join(lines + [""] + notes + [f"- {report['order_note']}"])
