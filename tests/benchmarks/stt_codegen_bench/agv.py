"""``stt-codegen bench agv``: a warehouse AGV's reach time against the straight-line time
at ``v_max`` along its route, on seeded floors (docs/differential-drive.md,
docs/performance.md).

Floor ``k`` of seed ``S`` (``numpy.random.default_rng([S, k])``) is 20 x 12 m with three
1.2 m deep racks, each 6-8.5 m long, standing from the south or the north wall at ``x`` =
5, 10 and 15 m, each moved by up to 0.3 m (aisles at least 3.2 m wide); the AGV of
``tests/specs/agv-warehouse.toml`` (``v_max`` 1.2 m/s, ``omega_max`` 1.5 rad/s, body
radius 0.4 m, look-ahead 0.8 m, 50 Hz) drives from the south-west corner to the
south-east corner. On every floor, in one run:

1. the design at a generous ``prescribed_time`` (120 s) gives the route (the via boxes:
   :func:`~stt_codegen.design.route.route_length`) and the straight-line time
   ``route / v_max``;
2. the design at ``prescribed_time`` equal to that straight-line time is refused (no tube
   is that fast), naming the smallest certified ``prescribed_time`` (two significant
   digits); that time is designed (certified), its route measured again, and the closed
   loop run with the generated C on the spec's base.

The figures are the ratios of the certified ``t_c`` and of the simulated reach time to the
straight-line time along the same route, per floor and their median.
"""

from __future__ import annotations

import math

import numpy as np

from stt_codegen.design.certificate.actuator import prove_input_bound
from stt_codegen.design.look_ahead import base_proof
from stt_codegen.design.route import route_length
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import Spec

__all__ = ["agv_floor", "format_agv_report", "run_agv_bench"]

#: The AGV's ``[actuator] input_bound``: v_max m/s, omega_max rad/s.
LIMITS = (1.2, 1.5)
#: The generous ``prescribed_time`` of the first design (the route), seconds.
GENEROUS = 120.0


def agv_floor(seed: int, index: int, prescribed_time: float = GENEROUS) -> dict:
    """The spec dict of floor ``index`` of ``seed`` (module notes).

    Parameters
    ----------
    seed, index : int
        >= 0.
    prescribed_time : float
        Seconds.

    Returns
    -------
    dict
        A spec document for :meth:`~stt_codegen.spec.loader.Spec.from_dict`.
    """
    rng = np.random.default_rng([seed, index])
    racks = []
    for centre in (5.0, 10.0, 15.0):
        x = centre + float(rng.uniform(-0.3, 0.3))
        length = float(rng.uniform(6.0, 8.5))
        south = bool(rng.integers(2))
        racks.append({"lower": [round(x - 0.6, 3), 0.0 if south else round(12.0 - length, 3)],
                      "upper": [round(x + 0.6, 3), round(length, 3) if south else 12.0]})
    return {"name": f"agv_floor_{seed}_{index}", "prescribed_time": prescribed_time,
            "state_space": {"lower": [0.0, 0.0], "upper": [20.0, 12.0]},
            "initial": {"lower": [1.5, 1.5], "upper": [2.5, 2.5], "state": [2.0, 2.0],
                        "heading": 0.0},
            "target": {"lower": [17.5, 1.5], "upper": [18.5, 2.5]},
            "obstacles": racks, "controller": {"rate_hz": 50.0},
            "plant": {"model": "differential-drive", "axle_offset": 0.8, "track_width": 0.5,
                      "wheel_radius_error": [0.02, -0.02], "slip": [0.02, 0.01, 0.02]},
            "actuator": {"input_bound": list(LIMITS)}, "robot": {"radius": 0.4}}


def _floor(seed: int, index: int) -> dict:
    """One floor's row (module notes)."""
    spec = Spec.from_dict(agv_floor(seed, index))
    try:
        route = route_length(design_tube(spec).tube, spec.initial_state)
    except DesignError as exc:
        return {"index": index, "reason": f"no design at {GENEROUS:g} s: {str(exc)[:100]}"}
    straight = route / LIMITS[0]
    fast = Spec.from_dict(agv_floor(seed, index, round(straight, 1)))
    try:
        design_tube(fast)
    except DesignError as exc:
        named = exc.advice.get("prescribed_time")
    else:
        named = fast.prescribed_time
    if named is None:
        return {"index": index, "straight_s": straight, "reason": "no prescribed_time named"}
    spec = Spec.from_dict(agv_floor(seed, index, named))
    design = design_tube(spec)         # a refusal's named time is certified
    straight = route_length(design.tube, spec.initial_state) / LIMITS[0]
    result = simulate(design, backend="c", seed=index)
    point = prove_input_bound(design.tube, spec)       # law (13)'s at the look-ahead point
    backing = base_proof(point, design.tube, spec)      # from the heading the base can have
    return {"index": index, "route_m": straight * LIMITS[0], "straight_s": straight,
            "t_c": named, "reach_s": result.reach_time, "satisfied": bool(result.satisfied),
            "peak_v": float(result.max_abs_u[0]), "peak_omega": float(result.max_abs_u[1]),
            "proved": [float(p) for p in design.input_proof.peak],
            "speed_per_sample": point.speed, "speed_of_peaks": math.hypot(*point.peak),
            "backing_proved": backing.backward,
            "backing_sim": max(0.0, -float(np.min(result.trajectory.u[:, 0]))),
            "t_c_ratio": named / straight,
            "reach_ratio": (result.reach_time / straight
                            if result.reach_time is not None else None), "reason": ""}


def run_agv_bench(count: int, seed: int) -> dict:
    """The AGV on ``count`` seeded floors, sequentially.

    Parameters
    ----------
    count : int
        Number of floors, >= 1.
    seed : int
        Floor seed, >= 0.

    Returns
    -------
    dict
        ``count``, ``seed``, ``floors`` (per floor: ``route_m``, ``straight_s``, ``t_c``,
        ``reach_s``, ``satisfied``, the simulated ``peak_v``, ``peak_omega`` and the
        ``proved`` peaks, the bound of ``|u|`` at the point sample by sample
        (``speed_per_sample``, the one the design uses) and from the per-input peaks
        (``speed_of_peaks``, ``hypot(peak_1, peak_2)``), the speed the base is proved to
        back up at (``backing_proved``, docs/differential-drive.md, "Backing up") and the
        largest it backs up at in the run (``backing_sim``), ``t_c_ratio``, ``reach_ratio``,
        or ``reason``), and the medians
        ``t_c_ratio`` and ``reach_ratio`` over the floors designed.

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``).
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    floors = [_floor(seed, k) for k in range(count)]
    done = [f for f in floors if not f["reason"]]
    reach = [f["reach_ratio"] for f in done if f["reach_ratio"] is not None]
    return {"count": count, "seed": seed, "floors": floors,
            "t_c_ratio": float(np.median([f["t_c_ratio"] for f in done])) if done else None,
            "reach_ratio": float(np.median(reach)) if reach else None}


def format_agv_report(report: dict) -> str:
    """The table of the floors and the medians.

    Parameters
    ----------
    report : dict
        :func:`run_agv_bench`'s result.

    Returns
    -------
    str
    """
    lines = [f"{report['count']} floors, seed {report['seed']}, v_max {LIMITS[0]:g} m/s, "
             f"omega_max {LIMITS[1]:g} rad/s, generated C, one run",
             "| floor | route | straight at v_max | certified t_c | ratio | reach (sim) | "
             "ratio | peak v, omega (sim) | proved | proved |u| from the peaks | "
             "backing up: proved, sim |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for f in report["floors"]:
        if f["reason"]:
            lines.append(f"| {f['index']} | {f['reason']} |")
            continue
        lines.append(f"| {f['index']} | {f['route_m']:.1f} m | {f['straight_s']:.1f} s | "
                     f"{f['t_c']:g} s | {f['t_c_ratio']:.2f} | {f['reach_s']:.1f} s"
                     f"{'' if f['satisfied'] else ' (not satisfied)'} | "
                     f"{f['reach_ratio']:.2f} | {f['peak_v']:.2f}, {f['peak_omega']:.2f} | "
                     f"{f['proved'][0]:.2f}, {f['proved'][1]:.2f} | "
                     f"{f['speed_of_peaks']:.2f} | "
                     f"{f['backing_proved']:.3f}, {f['backing_sim']:.3f} m/s |")
    if report["t_c_ratio"] is not None:
        lines.append(f"median t_c / straight-line time: {report['t_c_ratio']:.2f}; "
                     f"median reach / straight-line time: {report['reach_ratio']:.2f}")
    return "\n".join(lines)
