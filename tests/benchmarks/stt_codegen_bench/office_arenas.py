"""``stt-codegen bench drive``: a differential-drive base beside a holonomic base on random
offices (docs/differential-drive.md, docs/performance.md).

Office ``k`` of seed ``S`` (``numpy.random.default_rng([S, k])``): a 10 m x 8 m room, six
desks and cabinets (boxes of sides drawn in [0.6, 1.6] m, anywhere in the room), the start
box ``[0.5, 1.5]^2`` with a heading drawn in ``[-pi, pi)``, the target box by the door
``[8.6, 9.6] x [6.6, 7.6]``, ``t_c = 20`` s, 50 Hz; an office is redrawn while a box,
grown by :data:`CLEARANCE`, meets the start or the target box. On every office, in one
run, two specs are designed and run with the generated C on their own plants, with the
same seed:

* ``drive``: ``plant.model = "differential-drive"`` (axle offset 0.1 m, track 0.16 m, wheel
  errors ``+-5 %``, slip ``[0.02, 0.01, 0.05]``, body radius 0.12 m);
* ``holonomic``: ``plant.model = "single-integrator"`` with the same body radius and the
  same disturbance bound (a base that moves in every direction, law (13) on its centre).

The design time is :attr:`~stt_codegen.design.result.Design.design_time_s` (the design and
its certificate, in process); compare the two methods' figures within one run.
"""

from __future__ import annotations

import math

import numpy as np

from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import Spec

__all__ = ["format_office_report", "office_doc", "run_office_bench"]

#: The room, the start and target boxes, m.
ROOM = ((0.0, 0.0), (10.0, 8.0))
START = ((0.5, 0.5), (1.5, 1.5))
TARGET = ((8.6, 6.6), (9.6, 7.6))
#: Obstacles, their side range (m) and the clearance they keep from start and target.
OBSTACLES, SIDES, CLEARANCE = 6, (0.6, 1.6), 0.3
#: The bases: body radius (m), the drive's axle offset and track width (m), wheel errors,
#: slip (m/s, m/s, rad/s).
RADIUS, AXLE_OFFSET, TRACK_WIDTH = 0.12, 0.1, 0.16
WHEEL_ERRORS, SLIP = (0.05, -0.05), (0.02, 0.01, 0.05)
METHODS = ("drive", "holonomic")


def _meets(box, other, grow: float) -> bool:
    return all(box[0][i] - grow < other[1][i] and other[0][i] < box[1][i] + grow
               for i in range(2))


def office_doc(seed: int, index: int, method: str) -> dict:
    """The spec document of office ``index`` of ``seed`` for one base.

    Parameters
    ----------
    seed, index : int
        Non-negative.
    method : {"drive", "holonomic"}
        The base.

    Returns
    -------
    dict
        A spec document (:meth:`~stt_codegen.spec.loader.Spec.from_dict`).

    Raises
    ------
    SpecError
        A negative ``seed`` or ``index``, or an unknown ``method``.
    """
    if seed < 0 or index < 0:
        raise SpecError("seed", f"seed and index must be non-negative, got {seed}, {index}")
    if method not in METHODS:
        raise SpecError("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
    rng = np.random.default_rng([seed, index])
    while True:
        boxes = []
        for _ in range(OBSTACLES):
            side = rng.uniform(*SIDES, 2)
            corner = rng.uniform(ROOM[0], np.array(ROOM[1]) - side)
            boxes.append(((float(corner[0]), float(corner[1])),
                          (float(corner[0] + side[0]), float(corner[1] + side[1]))))
        if not any(_meets(b, s, CLEARANCE) for b in boxes for s in (START, TARGET)):
            break
    heading = float(rng.uniform(-math.pi, math.pi))
    doc = {"name": f"office-{seed}-{index}-{method}", "prescribed_time": 20.0,
           "state_space": {"lower": list(ROOM[0]), "upper": list(ROOM[1])},
           "initial": {"lower": list(START[0]), "upper": list(START[1])},
           "target": {"lower": list(TARGET[0]), "upper": list(TARGET[1])},
           "obstacles": [{"lower": list(lo), "upper": list(hi)} for lo, hi in boxes],
           "controller": {"rate_hz": 50.0}, "robot": {"radius": RADIUS}}
    if method == "drive":
        doc["initial"]["heading"] = heading
        doc["plant"] = {"model": "differential-drive", "axle_offset": AXLE_OFFSET,
                        "track_width": TRACK_WIDTH, "wheel_radius_error": list(WHEEL_ERRORS),
                        "slip": list(SLIP)}
    else:       # the same disturbance bound: sqrt(2) a = |w| of the drive's slip
        bound = math.hypot(SLIP[0], SLIP[1] + AXLE_OFFSET * SLIP[2])
        doc["plant"] = {"model": "single-integrator",
                        "disturbance_amplitude": bound / math.sqrt(2.0)}
    return doc


def _run(doc: dict, seed: int) -> dict:
    try:
        spec = Spec.from_dict(doc)
        design = design_tube(spec)
    except (DesignError, SpecError) as exc:
        return {"satisfied": False, "reason": f"no design: {str(exc)[:100]}", "seconds": None}
    result = simulate(design, backend="c", seed=seed)
    return {"satisfied": bool(result.satisfied), "seconds": design.design_time_s,
            "reach_time": result.reach_time, "clearance": result.min_obstacle_clearance,
            "peak_u": [float(v) for v in result.max_abs_u],
            "reason": "" if result.satisfied else ("collision" if result.collision else
                                                   "left the tube" if not result.stayed_in_tube
                                                   else "target not reached")}


def run_office_bench(count: int, seed: int) -> dict:
    """Both bases on ``count`` offices, sequentially (each design timed in process).

    Parameters
    ----------
    count : int
        Number of offices, >= 1.
    seed : int
        Office seed, >= 0.

    Returns
    -------
    dict
        ``count``, ``seed``, per method ``satisfied`` (count), ``design_median_s`` and
        ``design_p95_s`` (over the designed offices), ``ratio`` (the drive's median over
        the holonomic base's) and ``offices`` (per office and method: ``satisfied``,
        ``seconds``, ``reach_time``, ``clearance``, ``peak_u``, ``reason``).

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``) or a negative seed.
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    offices = [{"index": k, **{m: _run(office_doc(seed, k, m), k) for m in METHODS}}
               for k in range(count)]
    out: dict = {"count": count, "seed": seed, "offices": offices}
    for m in METHODS:
        times = [o[m]["seconds"] for o in offices if o[m]["seconds"] is not None]
        out[m] = {"satisfied": sum(o[m]["satisfied"] for o in offices),
                  "design_median_s": float(np.median(times)) if times else None,
                  "design_p95_s": float(np.percentile(times, 95)) if times else None}
    a, b = out["drive"]["design_median_s"], out["holonomic"]["design_median_s"]
    out["ratio"] = a / b if a and b else None
    return out


def format_office_report(report: dict) -> str:
    """The table of both bases and one line per failed run.

    Parameters
    ----------
    report : dict
        :func:`run_office_bench`'s result.

    Returns
    -------
    str
    """
    lines = [f"{report['count']} offices, seed {report['seed']}, generated C, one run",
             "| base | satisfied | design median | design p95 |", "|---|---|---|---|"]
    for m in METHODS:
        r = report[m]
        med = "-" if r["design_median_s"] is None else f"{1e3 * r['design_median_s']:.1f} ms"
        p95 = "-" if r["design_p95_s"] is None else f"{1e3 * r['design_p95_s']:.1f} ms"
        lines.append(f"| {m} | {r['satisfied']}/{report['count']} | {med} | {p95} |")
    if report["ratio"] is not None:
        lines.append(f"design median, drive / holonomic: {report['ratio']:.2f}")
    for office in report["offices"]:
        for m in METHODS:
            if not office[m]["satisfied"]:
                lines.append(f"  office {office['index']} {m}: {office[m]['reason']}")
    return "\n".join(lines)
