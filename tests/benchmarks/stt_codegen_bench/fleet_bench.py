"""``stt-codegen bench fleet``: prioritized fleet design on seeded warehouse floors
(docs/fleets.md, docs/performance.md).

Floor ``k`` of seed ``S`` (``numpy.random.default_rng([S, k])``) for ``N`` robots is a
warehouse (:func:`floor_layout`): ``max(2, ceil(sqrt(N) / 1.5))`` rows of back-to-back
racks 1.2 m deep at a 3.6 m pitch (aisles 2.4 m wide), a 3.6 m corridor between the racks
and the walls; along a row, racks of 3.2 m with a 1.6 m bay between two of them and a
2.4 m cross aisle after every third; each rack's ends moved in by up to 0.2 m and its row
by up to 0.1 m. Docks (0.8 m boxes) lie every 2 m along the four walls (0.7 m from the
wall) and in every bay; the floor is widened 2 m at a time until it has
``2 N + 2 (N // 4 + 2)`` docks. ``2 (N + N // 4 + 2)`` docks drawn without replacement are
the starts and targets of the robots drawn; the first ``N`` of them that have a tube alone
are the fleet (:func:`fair_floor`; the others are reported as refused alone, no failure of
the fleet's design). Every fourth robot is a differential-drive base (the office base's
geometry, 200 Hz, ``|v| <= 1.6``, ``|omega| <= 16``), the others single-integrator AMRs
(radius 0.2 m, 100 Hz); ``prescribed_time`` is ``10 s + 1 s/m`` times the Manhattan
distance from start to target, rounded to the second.

On every floor, in one run: :func:`~stt_codegen.design_fleet` (CPU time), and each robot's
single spec designed alone (CPU time, summed): the ratio of the two is the fleet's cost
over its robots' own designs, measured side by side; and the baseline, prioritized
space-time A* (``design_fleet(planner="space-time A*")``: every robot's tube along its A*
path among the placed tubes, tracked by the same controller and certified by the same pair
certificate). Reported: certified or the refusal's
first words, the robots moved to the front, the narrowest certified pair margin, the
times and the ratio; with ``--simulate``, every robot's generated C in closed loop and
the closest approach.
"""

from __future__ import annotations

import math
import time

import numpy as np

from stt_codegen.design.fleet import PLANNER_SPACE_TIME, design_fleet
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.fleet import simulate_fleet
from stt_codegen.spec.fleet import FleetSpec

from .parallel import run_parallel

__all__ = ["fair_floor", "fleet_floor", "floor_layout", "format_fleet_report", "run_fleet_bench"]

#: The docks' spacing along the walls, m.
DOCK_STEP = 2.0
#: The perimeter corridor between the walls and the racks, m (docks 0.7 m from a wall).
CORRIDOR = 3.6
#: Rack rows: depth (back-to-back racks), pitch (a row and an aisle of 2.4 m), m.
ROW_DEPTH, ROW_PITCH = 1.2, 3.6
#: Along a row: rack, bay (a dock between two racks), rack, cross aisle; m.
RACK, BAY, CROSS = 3.2, 1.6, 2.4
#: The differential-drive bases' rate, Hz (their input proof's cost grows with the samples).
BASE_RATE = 200.0


def _rows(robots: int) -> int:
    """Rack rows for ``robots`` robots: 2 up to 9 robots, then ``sqrt(robots) / 1.5``
    rounded up."""
    return max(2, math.ceil(math.sqrt(robots) / 1.5))


def _height(rows: int) -> float:
    return 2 * (CORRIDOR + 0.6) + ROW_DEPTH + ROW_PITCH * (rows - 1)


def _row_pieces(width: float) -> tuple[list[tuple[float, float]], list[float]]:
    """One row's racks (x intervals) and bays (x centres) from ``CORRIDOR`` to
    ``width - CORRIDOR``: rack, bay, rack, bay, rack, cross aisle, ..., ending with a
    rack."""
    x, end = CORRIDOR, width - CORRIDOR
    racks, bays = [], []
    step = 0
    while end - x > 0.5:
        length = min(RACK, end - x)
        racks.append((x, x + length))
        x += length
        gap = CROSS if step % 3 == 2 else BAY
        if end - x < gap + 1.0:          # no room for another rack after a gap
            racks[-1] = (racks[-1][0], end)
            break
        if gap == BAY:
            bays.append(x + BAY / 2)
        x += gap
        step += 1
    return racks, bays


def floor_layout(robots: int, spare: int) -> dict:
    """The floor for ``robots`` robots with at least ``2 robots + spare`` docks (module notes).

    Parameters
    ----------
    robots : int
        >= 1.
    spare : int
        Docks beyond two per robot.

    Returns
    -------
    dict
        ``width``, ``height`` (m), ``rows`` (the rows' centre heights), ``racks`` (per row,
        x intervals) and ``docks`` (dock centres).
    """
    rows = _rows(robots)
    height = _height(rows)
    ys = [CORRIDOR + 0.6 + ROW_DEPTH / 2 + ROW_PITCH * k for k in range(rows)]
    width = 16.0
    while True:
        racks, bays = _row_pieces(width)
        docks = [(0.7, float(y)) for y in np.arange(2.0, height - 2.0 + 1e-9, DOCK_STEP)]
        docks += [(width - 0.7, float(y)) for y in np.arange(2.0, height - 2.0 + 1e-9,
                                                               DOCK_STEP)]
        xs = np.arange(3.0, width - 3.0 + 1e-9, DOCK_STEP)
        docks += [(float(x), 0.7) for x in xs] + [(float(x), height - 0.7) for x in xs]
        docks += [(float(x), float(y)) for y in ys for x in bays]
        if len(docks) >= 2 * robots + spare:
            return {"width": width, "height": height, "rows": ys, "racks": racks,
                    "docks": docks}
        width += DOCK_STEP


def fleet_floor(seed: int, index: int, robots: int, spare: int = 0,
                base_every: int = 4) -> dict:
    """The fleet document of floor ``index`` of ``seed`` for ``robots`` robots.

    Parameters
    ----------
    seed, index : int
        >= 0.
    robots : int
        The number of robots, >= 1.
    spare : int
        Robots beyond ``robots`` drawn on the same floor, for :func:`fair_floor` (which
        keeps the first ``robots`` that have a tube alone).
    base_every : int
        Robot ``i`` is a differential-drive base when ``i % base_every ==
        base_every - 1`` (0: none), else an AMR.

    Returns
    -------
    dict
        A fleet document for :meth:`~stt_codegen.spec.fleet.FleetSpec.from_dict`, with
        ``robots + spare`` robots on distinct docks.

    Raises
    ------
    SpecError
        Field ``robots``: fewer than 1.
    """
    if robots < 1:
        raise SpecError("robots", f"must be at least 1, got {robots}")
    count = robots + spare
    rng = np.random.default_rng([seed, index])
    layout = floor_layout(robots, 2 * (robots // 4 + 2))
    width, height, docks = layout["width"], layout["height"], layout["docks"]
    racks = []
    for y in layout["rows"]:
        for x0, x1 in layout["racks"]:
            dy = float(rng.uniform(-0.1, 0.1))
            a, b = (float(v) for v in rng.uniform(0.0, 0.2, 2))
            racks.append({"lower": [round(x0 + a, 3), round(y + dy - ROW_DEPTH / 2, 3)],
                          "upper": [round(x1 - b, 3), round(y + dy + ROW_DEPTH / 2, 3)]})
    chosen = rng.permutation(len(docks))[:2 * count]
    entries = []
    for i in range(count):
        (sx, sy), (tx, ty) = docks[chosen[2 * i]], docks[chosen[2 * i + 1]]
        t_c = float(round(10.0 + 1.0 * (abs(tx - sx) + abs(ty - sy))))
        entry = {"name": f"r{i}", "prescribed_time": t_c,
                 "initial": {"lower": [sx - 0.4, sy - 0.4], "upper": [sx + 0.4, sy + 0.4]},
                 "target": {"lower": [tx - 0.4, ty - 0.4], "upper": [tx + 0.4, ty + 0.4]}}
        if base_every and i % base_every == base_every - 1:
            entry.update(radius=0.15, controller={"rate_hz": BASE_RATE},
                         plant={"model": "differential-drive", "axle_offset": 0.1,
                                "track_width": 0.16},
                         actuator={"input_bound": [1.6, 16.0]})
            entry["initial"]["heading"] = float(np.arctan2(ty - sy, tx - sx))
        else:
            entry.update(radius=0.2, controller={"rate_hz": 100.0},
                         plant={"model": "single-integrator", "disturbance_amplitude": 0.05})
        entries.append(entry)
    return {"name": f"floor_{seed}_{index}",
            "state_space": {"lower": [0.0, 0.0], "upper": [width, height]},
            "obstacles": racks, "robots": entries}


def fair_floor(seed: int, index: int, robots: int,
               base_every: int = 4) -> tuple[dict, list[str], float]:
    """Floor ``index`` of ``seed`` with only robots that have a tube alone.

    The floor of :func:`fleet_floor` with ``robots // 4 + 2`` spare robots; each robot is
    designed alone (:func:`~stt_codegen.design_tube`) in turn and the first ``robots``
    designed are kept (renamed ``r0``, ``r1``, ... in order, every fourth still a base
    where the draw allows). A robot refused alone is no fleet's failure: it is reported.

    Parameters
    ----------
    seed, index, robots, base_every : int
        As :func:`fleet_floor`.

    Returns
    -------
    doc : dict
        The fleet document.
    refused : list of str
        The robots drawn that have no tube alone (their names in the draw).
    solo_s : float
        CPU seconds of the designs alone of the robots kept.

    Raises
    ------
    SpecError
        Fewer than ``robots`` robots of the draw have a tube alone (field ``robots``).
    """
    doc = fleet_floor(seed, index, robots, spare=robots // 4 + 2, base_every=base_every)
    fleet = FleetSpec.from_dict(doc)
    kept, refused, solo = [], [], 0.0
    for entry, robot in zip(doc["robots"], fleet.robots):
        if len(kept) == robots:
            break
        start = time.process_time()
        try:
            design_tube(robot.spec)
        except DesignError:
            refused.append(robot.name)
            continue
        solo += time.process_time() - start
        kept.append(entry)
    if len(kept) < robots:
        raise SpecError("robots", f"only {len(kept)} of the robots drawn on floor {index} "
                                  "have a tube alone")
    doc = dict(doc, robots=[dict(e, name=f"r{i}") for i, e in enumerate(kept)])
    return doc, refused, solo


def _baseline(fleet: FleetSpec) -> dict:
    """The space-time A* baseline on ``fleet``: ``astar_certified``, ``astar_s`` (CPU)."""
    start = time.process_time()
    try:
        certified = design_fleet(fleet, planner=PLANNER_SPACE_TIME).certified
    except DesignError:
        certified = False
    return {"astar_certified": certified, "astar_s": time.process_time() - start}


def _floor(seed: int, index: int, robots: int, simulate: bool) -> dict:
    """One floor's row (module notes)."""
    doc, refused, solo = fair_floor(seed, index, robots)
    fleet = FleetSpec.from_dict(doc)
    baseline = _baseline(fleet)
    start = time.process_time()
    try:
        designed = design_fleet(fleet)
    except DesignError as exc:
        return {"index": index, "certified": False, "fleet_s": time.process_time() - start,
                "solo_s": solo, "solo_failed": len(refused), "reason": str(exc)[:300],
                **baseline}
    row = {"index": index, "certified": designed.certified,
           "fleet_s": time.process_time() - start, "solo_s": solo,
           "solo_failed": len(refused), "reordered": len(designed.reordered),
           "margin": designed.narrowest.margin if designed.pairs else None, "reason": "",
           "placements": [[p.placed, p.near, p.cpu_s] for p in designed.placements],
           **baseline}
    if simulate:
        run = simulate_fleet(designed, backend="c", seed=index)
        row.update(satisfied=run.satisfied,
                   closest=run.closest.clearance if run.closest else None)
    return row


def run_fleet_bench(count: int, seed: int, robots: int = 8, simulate: bool = False,
                    workers: int = 1, scheduler: str | None = None, first: int = 0) -> dict:
    """Fleet design on ``count`` seeded floors: one after another, or a floor per job on
    local processes or a Dask scheduler (:func:`~.parallel.run_parallel`). Each floor's
    times are the CPU of the process that designs it, so they do not depend on how many
    run beside it (beyond the machine's load).

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
    workers : int
        Local processes; 1 (the default) designs the floors in this process, in turn.
    scheduler : str, optional
        Address of a running Dask scheduler: the floors are its jobs (``workers`` ignored).
    first : int
        The first floor's index, >= 0: floors ``first`` to ``first + count - 1`` (one
        floor of a long run designed again on its own).

    Returns
    -------
    dict
        ``count``, ``seed``, ``robots``, ``floors`` (per floor: ``certified``,
        ``fleet_s`` and ``solo_s`` (CPU seconds), ``solo_failed`` (robots with no tube
        even alone), ``reordered``, ``margin`` (m), with ``simulate`` ``satisfied`` and
        ``closest`` (m), or ``reason``; ``astar_certified`` and ``astar_s``: the
        space-time A* baseline's), ``certified_fraction``, ``astar_fraction`` and the
        medians ``fleet_s``, ``astar_s`` and ``ratio`` (fleet over solo, per floor) over
        the floors.

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``), ``first < 0`` (field ``first``), a bad
        ``robots``, ``workers < 1`` (field ``workers``), a scheduler that does not answer
        (field ``scheduler``).
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    if first < 0:
        raise SpecError("first", f"must be at least 0, got {first}")
    if workers < 1:
        raise SpecError("workers", f"must be at least 1, got {workers}")
    fleet_floor(seed, 0, robots)                    # a bad robots fails before any job
    calls = [(seed, k, robots, simulate) for k in range(first, first + count)]
    if workers == 1 and scheduler is None:
        floors = [_floor(*call) for call in calls]
    else:
        floors = run_parallel(_floor, calls, workers=workers, scheduler=scheduler,
                              progress=False, description="floors")
    return {"count": count, "seed": seed, "robots": robots, "floors": floors,
            "certified_fraction": sum(f["certified"] for f in floors) / count,
            "astar_fraction": sum(f["astar_certified"] for f in floors) / count,
            "astar_s": float(np.median([f["astar_s"] for f in floors])),
            "fleet_s": float(np.median([f["fleet_s"] for f in floors])),
            "ratio": float(np.median([f["fleet_s"] / f["solo_s"] for f in floors])),
            "by_near": placement_growth(floors)}


#: The buckets of ``near`` (placed robots near a robot's way) of :func:`placement_growth`.
NEAR_BUCKETS = ((0, 0), (1, 2), (3, 5), (6, 10), (11, 10**9))


def placement_growth(floors: list[dict]) -> list[dict]:
    """A robot's placement CPU against the placed robots near its way, over every robot of
    the certified floors: per bucket of :data:`NEAR_BUCKETS`, the robots, the median and
    the mean CPU seconds, and the mean CPU per robot near (the growth the space-time index
    is to keep at most linear)."""
    rows = [p for f in floors for p in f.get("placements", ())]
    out = []
    for low, high in NEAR_BUCKETS:
        cpu = [c for _, near, c in rows if low <= near <= high]
        if cpu:
            out.append({"near": [low, high], "robots": len(cpu),
                        "median_s": float(np.median(cpu)), "mean_s": float(np.mean(cpu))})
    return out


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
             "| ratio | space-time A* | closest approach (C) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for f in report["floors"]:
        closest = f.get("closest")
        lines.append(
            f"| {f['index']} | {'yes' if f['certified'] else 'no: ' + f['reason'][:70]} | "
            f"{f.get('reordered', '-')} | "
            f"{'-' if f.get('margin') is None else format(f['margin'], '.3f') + ' m'} | "
            f"{f['fleet_s']:.1f} s | {f['solo_s']:.1f} s"
            f"{'' if not f['solo_failed'] else ' (' + str(f['solo_failed']) + ' refused)'} | "
            f"{f['fleet_s'] / f['solo_s']:.1f} | "
            f"{'yes' if f['astar_certified'] else 'no'}, {f['astar_s']:.1f} s | "
            f"{'-' if closest is None else format(closest, '.3f') + ' m'} |")
    lines.append(f"certified {100 * report['certified_fraction']:.0f} % of the floors; median "
                 f"fleet design {report['fleet_s']:.1f} s of CPU, {report['ratio']:.1f} times "
                 "its robots designed alone; space-time A* (prioritized, longest trip first) "
                 f"certified {100 * report['astar_fraction']:.0f} %, median "
                 f"{report['astar_s']:.1f} s")
    growth = "; ".join(
        f"{b['near'][0]}" + ("" if b['near'][1] == b['near'][0] else
                             "+" if b['near'][1] > 10**6 else f"-{b['near'][1]}")
        + f" near: {b['robots']} robots, median {b['median_s']:.2f} s, mean {b['mean_s']:.2f} s"
        for b in report.get("by_near", ()))
    if growth:
        lines.append("a robot's placement CPU by the placed robots near its way: " + growth)
    return "\n".join(lines)
