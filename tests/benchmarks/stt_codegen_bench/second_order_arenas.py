"""``stt-codegen bench arenas --plant double-integrator``: the cascade on random arenas,
beside a planner and a tracker for the same plant (docs/second-order.md).

The arenas are the ``"paper"`` arenas of :func:`~.arenas.make_arena` (seeded, four 1 m obstacles, 5 m x 5 m,
``t_c = 9`` s). The plant is a double integrator ``x2_dot = u / m + w`` with ``m = 1`` kg
and the arena's disturbance bound (0.1 per axis, here m/s^2), starting at rest; both
methods run in the same loop (:func:`~stt_codegen.runtime.simulate.run_closed_loop`)
with the same disturbance seed (the arena index), judged by Definition 2.1:

* ``stt``: the tube of the arena's spec with ``circumvent_sharpness = 1`` (a second-order
  plant cannot follow the 0.1 bumps, docs/second-order.md), the default second stage for
  ``1/m`` in ``[0.8, 1.25]``, the emitted C of the cascade;
* ``astar``: the A* path of :func:`~.astar.plan_astar`, followed by the carrot of
  :class:`~.tracker.PathTracker` as a velocity reference, and a velocity loop
  ``u = m_nominal VELOCITY_GAIN (v_ref - x2)`` (nominal mass 1 kg).

Each arena also times, in CPU seconds of this process, ``design_tube`` of the arena as a
first-order spec and as the double integrator's spec (the position tube and the certified
second stage): the report's ``design_ratio`` is the median of their ratio, measured side by
side in one run.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from stt_codegen.design.cascade_gain import derived_second_stage
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.loader import Spec
from stt_codegen.spec.second_order import SecondOrder
from .arenas import arena_spec

__all__ = ["double_integrator_spec", "format_double_integrator_report",
           "run_arena_double_integrator", "run_double_integrator_bench"]

#: Velocity-loop gain of the baseline tracker, 1/s.
VELOCITY_GAIN = 10.0
#: Declared range of ``1/m`` for the cascade's default gains.
INPUT_GAIN = (0.8, 1.25)
#: The circumvent sharpness of the second-order designs.
SHARPNESS = 1.0


class VelocityTracker:
    """Carrot following as a velocity reference plus a proportional velocity loop (the
    controller step of :func:`~stt_codegen.runtime.backends.make_controller`, on
    ``x = [x1; x2]``)."""

    name = "astar-tracker"

    def __init__(self, path: np.ndarray) -> None:
        from .tracker import PathTracker
        self.carrot = PathTracker(path)

    def step(self, x, t, dt, alpha):
        """``u``, ``alpha`` (passed through) and status 0 (``Status.OK``)."""
        x = np.asarray(x, float)
        n = x.size // 2
        v_ref = self.carrot.command(x[:n])
        return VELOCITY_GAIN * (v_ref - x[n:]), np.asarray(alpha, float), 0


def double_integrator_spec(spec: Spec) -> Spec:
    """The arena's spec with a unit-mass double integrator as its plant.

    Parameters
    ----------
    spec : Spec
        A first-order arena spec (:func:`~.arenas.make_arena`).

    Returns
    -------
    Spec
        ``spec`` whose plant is ``x2_dot = u / m + w`` with ``m = 1`` kg, at rest at
        ``x(0)``, with the declared ``1/m`` range :data:`INPUT_GAIN`.
    """
    plant = SecondOrder(model="double-integrator", parameters=(1.0,),
                        initial_velocity=(0.0,) * spec.dimension, velocity_bound=None,
                        input_gain=INPUT_GAIN,
                        drift_bounds=(0.0,) * spec.dimension)
    return replace(spec, second_order=plant)


def _summary(result) -> dict:
    return {"satisfied": bool(result.satisfied), "reach_time": result.reach_time,
            "clearance": result.min_obstacle_clearance,
            "peak_u": max(result.max_abs_u), "collision": bool(result.collision),
            "in_tube": bool(result.stayed_in_tube and result.stayed_in_velocity_tube)}


def run_arena_double_integrator(seed: int, index: int) -> dict:
    """Both methods on one arena: ``{"index", "stt": {...}, "astar": {...}}`` with
    ``satisfied``, ``reach_time``, ``clearance``, ``peak_u`` or ``reason``.

    Parameters
    ----------
    seed : int
        Arena seed, >= 0.
    index : int
        Arena index, >= 0; also the disturbance seed of both runs.

    Returns
    -------
    dict
        ``index``, and per method (``stt``: the cascade on the designed tube; ``astar``: A*
        plus the tracker) ``satisfied``, ``seconds`` (design or planning time, s) and either
        ``reason`` (no design or no path) or ``reach_time`` (s), ``clearance`` (m),
        ``peak_u``, ``collision`` and ``in_tube``.
    """
    from .astar import plan_astar
    spec = arena_spec("paper", seed, index)
    spec = replace(spec, tube=replace(spec.tube, circumvent_sharpness=SHARPNESS))
    out: dict = {"index": index, "design_cpu": _design_cpu(spec)}
    begin = time.perf_counter()
    try:
        design = design_tube(spec)
    except DesignError as exc:
        design = None
        out["stt"] = {"satisfied": False, "reason": f"no design: {str(exc)[:120]}",
                      "seconds": time.perf_counter() - begin}
    else:
        stage, _ = derived_second_stage(design.tube, design.check.min_width, INPUT_GAIN,
                                        spec.disturbance_amplitude, np.zeros(2))
        result = run_closed_loop(double_integrator_spec(spec), design.tube, stage=stage,
                                 backend="c", seed=index)
        out["stt"] = {**_summary(result), "seconds": design.design_time_s}
    plan = plan_astar(spec)
    if plan.path is None:
        out["astar"] = {"satisfied": False, "reason": f"no path: {plan.reason}",
                        "seconds": plan.seconds}
    else:
        # the loop reports max |e1| in a tube: the arena's design, else the base tube
        # (unchecked); the tracker never reads it
        from stt_codegen.design.search import base_design
        tube = design.tube if design is not None else base_design(spec)
        result = run_closed_loop(double_integrator_spec(spec), tube,
                                 backend="astar-tracker", seed=index,
                                 controller=VelocityTracker(plan.path))
        summary = _summary(result)
        summary.pop("in_tube")
        out["astar"] = {**summary, "seconds": plan.seconds}
    return out


def _design_cpu(spec: Spec) -> dict:
    """CPU seconds of ``design_tube`` for the first-order arena and for its double
    integrator (``None`` where it refuses), each from a cold start of the caches that
    would carry one design into the other."""
    from stt_codegen.design.cascade_gain import _second_stage
    from stt_codegen.design.certificate.cascade_sampled import cascade_check_of
    out = {}
    for name, judged in (("first_order", spec), ("cascade", double_integrator_spec(spec))):
        _second_stage.cache_clear()
        cascade_check_of.cache_clear()
        start = time.process_time()
        try:
            design_tube(judged).stage
        except DesignError:
            out[name], out[f"{name}_designed"] = time.process_time() - start, False
        else:
            out[name], out[f"{name}_designed"] = time.process_time() - start, True
    return out


def run_double_integrator_bench(count: int, seed: int) -> dict:
    """Every arena in turn (sequential: no timing is compared), the satisfied rates.

    Parameters
    ----------
    count : int
        Number of arenas, >= 1.
    seed : int
        Arena seed, >= 0.

    Returns
    -------
    dict
        ``plant``, ``count``, ``seed``, ``satisfied_rate`` (method -> share in 0..1) and
        ``arenas`` (:func:`run_arena_double_integrator`'s results).
    """
    arenas = [run_arena_double_integrator(seed, k) for k in range(count)]
    rates = {m: sum(a[m]["satisfied"] for a in arenas) / count for m in ("stt", "astar")}
    times = [a["design_cpu"] for a in arenas]
    both = [t for t in times if t["first_order_designed"] and t["cascade_designed"]]
    ratio = float(np.median([t["cascade"] / t["first_order"] for t in both])) if both else None
    return {"plant": "double-integrator", "count": count, "seed": seed,
            "satisfied_rate": rates, "arenas": arenas, "design_ratio": ratio,
            "design_cpu_median": {m: float(np.median([t[m] for t in times]))
                                  for m in ("first_order", "cascade")},
            "design_cpu_max": {m: float(np.max([t[m] for t in times]))
                               for m in ("first_order", "cascade")},
            "cascade_designed": sum(t["cascade_designed"] for t in times)}


def format_double_integrator_report(report: dict) -> str:
    """The rates and the failures, a few lines.

    Parameters
    ----------
    report : dict
        The result of :func:`run_double_integrator_bench`.

    Returns
    -------
    str
        The satisfied rates, then one line per failed run with its reason.
    """
    lines = [f"double integrator, {report['count']} arenas, seed {report['seed']}: satisfied "
             f"STT cascade {100 * report['satisfied_rate']['stt']:.1f} %, A* + tracker "
             f"{100 * report['satisfied_rate']['astar']:.1f} %"]
    median, top = report["design_cpu_median"], report["design_cpu_max"]
    ratio = report["design_ratio"]
    lines.append(f"design_tube CPU, first order / cascade: median {median['first_order']:.2f} "
                 f"/ {median['cascade']:.2f} s, largest {top['first_order']:.2f} / "
                 f"{top['cascade']:.2f} s; cascade designed on {report['cascade_designed']} "
                 f"of {report['count']}; median ratio cascade / first order "
                 + ("n/a" if ratio is None else f"{ratio:.2f}"))
    for arena in report["arenas"]:
        for method in ("stt", "astar"):
            r = arena[method]
            if not r["satisfied"]:
                why = r.get("reason") or ("collision" if r["collision"] else
                                          "target not reached" if r["reach_time"] is None
                                          else "other")
                lines.append(f"  arena {arena['index']} {method}: {why}")
    return "\n".join(lines)
