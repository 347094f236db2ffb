"""``stt-codegen bench fleet``: prioritized fleet design on seeded warehouse floors
(docs/fleets.md, docs/performance.md).

Floor ``k`` of seed ``S`` (``numpy.random.default_rng([S, k])``) for ``N`` robots is
``W`` x 10 m, ``W = max(16, 2 (N - 2))`` m, with three racks 0.6 m deep across its
middle (from ``x = 3.5`` m to ``W - 3.5`` m, each end moved by up to 0.5 m, at
``y`` = 2.5, 5 and 7.5 m, each moved by up to 0.1 m), and docks (0.8 m boxes) along the
four walls: at ``y`` = 1, 3, 5, 7, 9 m on the west and east walls, every 2 m from
``x = 4`` m on the south and north walls. ``2 N`` docks drawn without replacement are the
robots' starts and targets. Every fourth robot is a differential-drive base (the office
base's geometry, 200 Hz, ``|v| <= 1.6``, ``|omega| <= 16``), the others single-integrator
AMRs (radius 0.2 m, 100 Hz); ``prescribed_time`` is ``12 s + 1.5 s/m`` times the
Manhattan distance from start to target, rounded to the second.

On every floor, in one run: :func:`~stt_codegen.design_fleet` (CPU time), and each robot's
single spec designed alone (CPU time, summed): the ratio of the two is the fleet's cost
over its robots' own designs, measured side by side. Reported: certified or the refusal's
first words, the robots moved to the front, the narrowest certified pair margin, the
times and the ratio; with ``--simulate``, every robot's generated C in closed loop and
the closest approach.
"""

from __future__ import annotations

import time

import numpy as np

from stt_codegen.design.fleet import design_fleet
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.fleet import simulate_fleet
from stt_codegen.spec.fleet import FleetSpec

__all__ = ["fleet_floor", "format_fleet_report", "run_fleet_bench"]

#: The floor's height, m.
HEIGHT = 10.0
#: The docks' spacing along the south and north walls, m.
DOCK_STEP = 2.0


def _docks(width: float) -> list[tuple[float, float]]:
    """The dock centres of a floor ``width`` m wide (module notes)."""
    docks = [(0.7, y) for y in (1.0, 3.0, 5.0, 7.0, 9.0)]
    docks += [(width - 0.7, y) for y in (1.0, 3.0, 5.0, 7.0, 9.0)]
    xs = np.arange(4.0, width - 4.0 + 1e-9, DOCK_STEP)
    docks += [(float(x), 0.7) for x in xs] + [(float(x), HEIGHT - 0.7) for x in xs]
    return docks


def fleet_floor(seed: int, index: int, robots: int) -> dict:
    """The fleet document of floor ``index`` of ``seed`` for ``robots`` robots.

    Parameters
    ----------
    seed, index : int
        >= 0.
    robots : int
        The number of robots, >= 1.

    Returns
    -------
    dict
        A fleet document for :meth:`~stt_codegen.spec.fleet.FleetSpec.from_dict`.

    Raises
    ------
    SpecError
        Field ``robots``: fewer than 1, or more than the floor's docks hold.
    """
    if robots < 1:
        raise SpecError("robots", f"must be at least 1, got {robots}")
    rng = np.random.default_rng([seed, index])
    width = max(16.0, DOCK_STEP * (robots - 2))
    docks = _docks(width)
    if 2 * robots > len(docks):
        raise SpecError("robots", f"at most {len(docks) // 2} robots on a floor")
    racks = []
    for y in (2.5, 5.0, 7.5):
        y0 = y + float(rng.uniform(-0.1, 0.1))
        x0, x1 = 3.5 + float(rng.uniform(0, 0.5)), width - 3.5 - float(rng.uniform(0, 0.5))
        racks.append({"lower": [round(x0, 3), round(y0 - 0.3, 3)],
                      "upper": [round(x1, 3), round(y0 + 0.3, 3)]})
    chosen = rng.permutation(len(docks))[:2 * robots]
    entries = []
    for i in range(robots):
        (sx, sy), (tx, ty) = docks[chosen[i]], docks[chosen[robots + i]]
        t_c = float(round(12.0 + 1.5 * (abs(tx - sx) + abs(ty - sy))))
        entry = {"name": f"r{i}", "prescribed_time": t_c,
                 "initial": {"lower": [sx - 0.4, sy - 0.4], "upper": [sx + 0.4, sy + 0.4]},
                 "target": {"lower": [tx - 0.4, ty - 0.4], "upper": [tx + 0.4, ty + 0.4]}}
        if i % 4 == 3:
            entry.update(radius=0.15, controller={"rate_hz": 200.0},
                         plant={"model": "differential-drive", "axle_offset": 0.1,
                                "track_width": 0.16},
                         actuator={"input_bound": [1.6, 16.0]})
            entry["initial"]["heading"] = float(np.arctan2(ty - sy, tx - sx))
        else:
            entry.update(radius=0.2, controller={"rate_hz": 100.0},
                         plant={"model": "single-integrator", "disturbance_amplitude": 0.05})
        entries.append(entry)
    return {"name": f"floor_{seed}_{index}",
            "state_space": {"lower": [0.0, 0.0], "upper": [width, HEIGHT]},
            "obstacles": racks, "robots": entries}


def _floor(seed: int, index: int, robots: int, simulate: bool) -> dict:
    """One floor's row (module notes)."""
    fleet = FleetSpec.from_dict(fleet_floor(seed, index, robots))
    start = time.process_time()
    solo_failed = 0
    for robot in fleet.robots:
        try:
            design_tube(robot.spec)
        except DesignError:
            solo_failed += 1
    solo = time.process_time() - start
    start = time.process_time()
    try:
        designed = design_fleet(fleet)
    except DesignError as exc:
        return {"index": index, "certified": False, "fleet_s": time.process_time() - start,
                "solo_s": solo, "solo_failed": solo_failed, "reason": str(exc)[:160]}
    row = {"index": index, "certified": designed.certified,
           "fleet_s": time.process_time() - start, "solo_s": solo,
           "solo_failed": solo_failed, "reordered": len(designed.reordered),
           "margin": designed.narrowest.margin if designed.pairs else None, "reason": ""}
    if simulate:
        run = simulate_fleet(designed, backend="c", seed=index)
        row.update(satisfied=run.satisfied,
                   closest=run.closest.clearance if run.closest else None)
    return row


def run_fleet_bench(count: int, seed: int, robots: int = 8, simulate: bool = False) -> dict:
    """Fleet design on ``count`` seeded floors, sequentially.

    Parameters
    ----------
    count : int
        Number of floors, >= 1.
    seed : int
        Floor seed, >= 0.
    robots : int
        Robots per floor.
    simulate : bool
        Also run every robot's generated C in closed loop (the closest approach).

    Returns
    -------
    dict
        ``count``, ``seed``, ``robots``, ``floors`` (per floor: ``certified``,
        ``fleet_s`` and ``solo_s`` (CPU seconds), ``solo_failed`` (robots with no tube
        even alone), ``reordered``, ``margin`` (m), with ``simulate`` ``satisfied`` and
        ``closest`` (m), or ``reason``), ``certified_fraction`` and the medians
        ``fleet_s`` and ``ratio`` (fleet over solo, per floor) over the floors.

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``), a bad ``robots``.
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    floors = [_floor(seed, k, robots, simulate) for k in range(count)]
    return {"count": count, "seed": seed, "robots": robots, "floors": floors,
            "certified_fraction": sum(f["certified"] for f in floors) / count,
            "fleet_s": float(np.median([f["fleet_s"] for f in floors])),
            "ratio": float(np.median([f["fleet_s"] / f["solo_s"] for f in floors]))}


def format_fleet_report(report: dict) -> str:
    """The table of the floors and the summary.

    Parameters
    ----------
    report : dict
        :func:`run_fleet_bench`'s result.

    Returns
    -------
    str
    """
    lines = [f"{report['count']} floors, seed {report['seed']}, {report['robots']} robots "
             "each, CPU times in one run",
             "| floor | certified | moved | narrowest pair | fleet design | robots alone "
             "| ratio | closest approach (C) |", "|---|---|---|---|---|---|---|---|"]
    for f in report["floors"]:
        closest = f.get("closest")
        lines.append(
            f"| {f['index']} | {'yes' if f['certified'] else 'no: ' + f['reason'][:70]} | "
            f"{f.get('reordered', '-')} | "
            f"{'-' if f.get('margin') is None else format(f['margin'], '.3f') + ' m'} | "
            f"{f['fleet_s']:.1f} s | {f['solo_s']:.1f} s"
            f"{'' if not f['solo_failed'] else ' (' + str(f['solo_failed']) + ' refused)'} | "
            f"{f['fleet_s'] / f['solo_s']:.1f} | "
            f"{'-' if closest is None else format(closest, '.3f') + ' m'} |")
    lines.append(f"certified {100 * report['certified_fraction']:.0f} % of the floors; median "
                 f"fleet design {report['fleet_s']:.1f} s of CPU, {report['ratio']:.1f} times "
                 "its robots designed alone")
    return "\n".join(lines)
