"""``stt-codegen bench second-order``: the cascade on random second-order plants within the
declared bounds of a bundled second-order case (docs/second-order.md).

For a design whose spec has a second-order ``plant.model``, the default second stage is derived once
from the spec's declared bounds (as ``simulate`` does); then ``count`` plants are drawn
within those bounds and each runs the closed loop with the emitted C of the cascade
(:func:`stt_codegen.runtime.simulate.run_closed_loop`, backend ``c``):

* double integrator: mass ``m`` uniform with ``1/m`` in ``assumptions.input_gain``;
* quadrotor: the same mass range, drag uniform in ``[0, DRAG_MAX]`` (the value the bundled
  case's ``drift_bound`` assumes), gravity 9.81;
* every plant: disturbance amplitude uniform in ``[0, plant.disturbance_amplitude]``, its
  own disturbance seed.

The report gives the share satisfied (Definition 2.1 and the velocity bound), the share
that stayed in both tubes, and every failure with its plant and what went wrong.
"""

from __future__ import annotations

import time

import numpy as np

from stt_codegen.design.search import design_tube
from stt_codegen.errors import SpecError
from stt_codegen.runtime.plants import second_order_plant
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.loader import load_spec
from stt_codegen.design.certificate.cascade_adversary import search_cascade
from stt_codegen.design.certificate.cascade_sampled import cascade_class

__all__ = ["DRAG_MAX", "format_second_order_report", "random_parameters", "run_second_order_study"]

#: Largest drag of the random quadrotors, N s / m.
DRAG_MAX = 0.4
#: Gravity of the random quadrotors, m/s^2.
GRAVITY = 9.81


def random_parameters(model: str, input_gain: tuple, rng: np.random.Generator,
                      spread: float = 1.0, corners: bool = False) -> list[float]:
    """One plant's parameters within the declared bounds (the module docstring), or, with
    ``spread > 1``, beyond them: ``1/m`` in ``[g_min / spread, g_max spread]``, drag up to
    ``spread DRAG_MAX``; with ``corners``, at a corner of that range (each parameter at one
    of its ends, drawn).

    Parameters
    ----------
    model : {"double-integrator", "quadrotor"}
        The plant model.
    input_gain : tuple of float, (g_min, g_max)
        The declared bounds on ``1/m``, 1/kg.
    rng : numpy.random.Generator
        The source of the draw.
    spread : float, optional
        Factor by which the draw goes beyond the bounds (1: within them).
    corners : bool, optional
        Draw each parameter at an end of its range (default: uniform in it).

    Returns
    -------
    list of float
        ``[m]`` (kg) for the double integrator; ``[m, drag, gravity]`` (kg, N s/m, m/s^2)
        for the quadrotor.

    Raises
    ------
    SpecError
        A model the study does not draw (field ``plant.model``).
    """
    g_min, g_max = input_gain

    def draw(low: float, high: float) -> float:
        return float(rng.choice([low, high]) if corners else rng.uniform(low, high))
    mass = 1.0 / draw(g_min / spread, g_max * spread)
    if model not in _OTHER_PARAMETERS:
        raise SpecError("plant.model", f"the study draws double-integrator and quadrotor "
                                       f"plants, not {model!r}")
    return [mass] + _OTHER_PARAMETERS[model](draw, spread)


#: The parameters after the mass each model the study draws takes, ``(draw, spread) ->
#: list``, in :data:`~stt_codegen.spec.plants.SECOND_ORDER_PLANTS`'s order.
_OTHER_PARAMETERS = {
    "double-integrator": lambda draw, spread: [],
    "quadrotor": lambda draw, spread: [draw(0.0, DRAG_MAX * spread), GRAVITY],
}


def run_second_order_study(case: str = "second-order-s1", count: int = 300, seed: int = 0,
                           backend: str = "c", spread: float = 1.0,
                           corners: bool = False, adversary: bool = False) -> dict:
    """Run the study (module docstring).

    Parameters
    ----------
    case : str
        A bundled case or spec file with a second-order ``plant.model``.
    count : int
        Plants, >= 1.
    seed : int
        Seed of the draws.
    backend : str
        Controller backend (``c`` by default: the emitted C of the cascade).
    spread : float
        1 (default): plants within the declared bounds; > 1: beyond them
        (:func:`random_parameters`, and disturbance amplitudes up to ``spread`` times the
        declared one), to find where the cascade fails.
    corners : bool
        Plants at the corners of the range (:func:`random_parameters`) with the largest
        disturbance amplitude of the range (default: uniform draws).
    adversary : bool
        Also run the adversary of :func:`~stt_codegen.design.certificate.cascade_adversary.search_cascade`
        on the class the design's certificate proves (``adversary``: the exits it found,
        which must be none for a certified design, and its seconds).

    Returns
    -------
    dict
        ``case``, ``model``, ``count``, ``satisfied`` and ``in_both_tubes`` (counts and
        shares), ``stage`` (the second stage used), ``failures`` (plant, seed, amplitude,
        result summary), ``seconds``.

    Raises
    ------
    SpecError
        A first-order spec, a bad count.
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    if not spread >= 1.0:
        raise SpecError("spread", f"must be at least 1, got {spread}")
    started = time.perf_counter()
    design = design_tube(load_spec(case))
    stage, derivation = design.second_stage
    spec = design.spec
    order = spec.second_order
    rng = np.random.default_rng(seed)
    satisfied = in_tubes = 0
    failures = []
    for k in range(count):
        params = random_parameters(order.model, order.input_gain, rng, spread, corners)
        amplitude = (spread * spec.disturbance_amplitude if corners
                     else float(rng.uniform(0.0, spread * spec.disturbance_amplitude)))
        plant_seed = int(rng.integers(0, 2**32))
        plant = second_order_plant(order.model, spec.dimension, params, amplitude, plant_seed)
        result = run_closed_loop(spec, design.tube, stage=stage, backend=backend,
                                 seed=plant_seed, plant=plant)
        satisfied += result.satisfied
        both = result.stayed_in_tube and result.stayed_in_velocity_tube
        in_tubes += both
        if not (result.satisfied and both):
            summary = result.to_json()
            failures.append({"index": k, "params": params, "amplitude": amplitude,
                             "seed": plant_seed,
                             **{key: summary[key] for key in (
                                 "satisfied", "reach_time", "min_obstacle_clearance",
                                 "stayed_in_tube", "stayed_in_velocity_tube", "max_abs_e",
                                 "max_abs_u", "max_abs_velocity", "exceeded_velocity_bound")}})
    found = None
    if adversary:
        begun = time.perf_counter()
        exits = search_cascade(design.tube, stage, cascade_class(spec), order.initial_velocity)
        found = {"exits": [e.to_json() for e in exits],
                 "seconds": time.perf_counter() - begun}
    return {"case": spec.name, "model": order.model, "count": count, "seed": seed,
            "spread": spread, "corners": corners, "adversary": found,
            "backend": backend, "satisfied": satisfied, "satisfied_share": satisfied / count,
            "in_both_tubes": in_tubes, "in_both_tubes_share": in_tubes / count,
            "stage": {"position_gain": stage.position_gain,
                      "velocity_gain": stage.velocity_gain,
                      "width_floor": stage.width_floor[0], "decay": stage.decay,
                      "input_gain": list(order.input_gain),
                      "drift_bound": derivation["drift_bound"]},
            "failures": failures, "seconds": time.perf_counter() - started}


def format_second_order_report(report: dict) -> str:
    """The study as a few lines of text.

    Parameters
    ----------
    report : dict
        The result of :func:`run_second_order_study`.

    Returns
    -------
    str
        The shares satisfied and in both tubes, then the first 20 failures, one a line.
    """
    lines = [f"{report['case']} ({report['model']}), {report['count']} random plants "
             f"(spread {report['spread']:g}{', at the corners' if report['corners'] else ''}),"
             f" seed "
             f"{report['seed']}, backend {report['backend']}: satisfied "
             f"{report['satisfied']}/{report['count']} ({100 * report['satisfied_share']:.1f} %),"
             f" in both tubes {report['in_both_tubes']}/{report['count']} "
             f"({100 * report['in_both_tubes_share']:.1f} %), {report['seconds']:.0f} s"]
    if report["adversary"] is not None:
        exits = report["adversary"]["exits"]
        lines.append(f"adversary (extreme members switched per interval, "
                     f"{report['adversary']['seconds']:.0f} s): "
                     + ("no member left a tube" if not exits else
                        "; ".join(f"{e['strategy']} left the {e['tube']} tube at "
                                  f"{e['time']:g} s (depth {e['depth']:.3g})"
                                  for e in exits)))
    for f in report["failures"][:20]:
        lines.append(f"  plant {f['index']}: params {[round(v, 4) for v in f['params']]}, "
                     f"|w| <= {f['amplitude']:.3g}: satisfied {f['satisfied']}, position tube "
                     f"{f['stayed_in_tube']}, velocity tube {f['stayed_in_velocity_tube']}, "
                     f"max |e1| {f['max_abs_e']:.3g}")
    return "\n".join(lines)
