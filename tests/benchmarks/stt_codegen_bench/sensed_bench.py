"""``stt-codegen bench sensed``: Real-Time STT's 2-D scenario with obstacles sensed at run
time (docs/sensing.md).

Real-Time Spatiotemporal Tubes for Dynamic Unsafe Sets (RA-L 2025, arXiv 2512.06151) run a
point robot across a plane among moving circles; their generator draws radii in
``U[0.1, 0.4]`` and velocity components in ``U[-1, 1]`` m/s. Here: a single integrator
(radius 0.1 m) crosses a 10 m x 10 m arena from ``[0.5, 1.5]^2`` to ``[8.5, 9.5]^2`` within
``t_c = 16 s`` at 100 Hz, among ``N`` circles drawn by that generator (seeded), at least
2.5 m from the start's centre at ``t = 0``, each moving straight and bouncing off the
arena's walls (a path of straight pieces). The envelope (``[sensing]``): range 5 m, latency
0.05 s, a measurement every 0.25 s, ``r_max = 0.4`` m, ``V = sqrt(2)`` m/s (the generator's
largest speed), replanning budget 0.25 s, horizon 0.5 s. With ``--adversary`` one more
circle (radius 0.3 m) starts 6 m away and heads for the robot at ``V``. With
``--warehouse``, a warehouse floor with people crossing its aisles instead
(:mod:`.sensed_warehouse`); with ``--script``, Real-Time STT's own script, its arena and
its five circles, seeded (:mod:`.sensed_script`); with ``--rooms``, a drone's room in
three dimensions with balls flying through it (:mod:`.sensed_rooms`).

Each episode is :func:`stt_codegen.simulate_sensed` (the CasADi backend). Reported per
``N``: collisions (and among them those at an instant some certificate covered, which must
be none), on-time arrivals, late ones, runs with uncertified spans (a replanning failed and
the guarantee lapsed), runs outside the envelope, switches, escapes (and among them the
best-effort ones a failed replan made, run uncertified: ``best``), plans certified over
the shortest horizon only (``short``), refusals, failed replans, and the replanner's
processor time per call (p95 and max over all calls); then the exact (Clopper-Pearson) 95 %
interval of the rates of collisions, on-time arrivals and uncertified runs, by which two
runs of the bench are compared.
"""

from __future__ import annotations

import math
import time
import tomllib

import numpy as np

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.sensed import WalkingObstacle

from .sensed_rooms import ROOM, flying_balls
from .sensed_script import PURSUER_RADIUS, PURSUER_START, SCRIPT, script_circles
from .sensed_warehouse import WAREHOUSE, aisle_people

__all__ = ["SCENARIO", "format_sensed_report", "moving_circles", "run_sensed_bench",
           "scenario_with", "target_costs"]

#: The arena, the robot and the envelope of the scenario (a spec dictionary).
SCENARIO = {
    "name": "rtstt-2d", "prescribed_time": 16.0,
    "state_space": {"lower": [0.0, 0.0], "upper": [10.0, 10.0]},
    "initial": {"lower": [0.5, 0.5], "upper": [1.5, 1.5], "half_width": [0.2, 0.2]},
    "target": {"lower": [8.5, 8.5], "upper": [9.5, 9.5]},
    "controller": {"rate_hz": 100.0},
    "plant": {"model": "single-integrator", "disturbance_amplitude": 0.05},
    "robot": {"radius": 0.1},
    "sensing": {"range": 5.0, "latency": 0.05, "period": 0.25, "max_obstacle_radius": 0.4,
                "max_obstacle_speed": math.sqrt(2.0), "replan_time": 0.25, "horizon": 0.5},
}
#: Circles start at least this far from the start set's centre, m.
CLEAR_OF_START = 2.5
#: The time step of a turning circle's path (the controller's period), s.
TURN_STEP = 0.01
#: The envelope's ``velocity_error`` with an acceleration bound, m/s: the estimate is the
#: velocity over the period before the measurement, which differs from the velocity after
#: it by at most ``A`` times the period (0.01 s).
VELOCITY_ERROR = 0.05


def _bouncing(start: np.ndarray, velocity: np.ndarray, radius: float, side: float,
              until: float) -> tuple[tuple[float, ...], ...]:
    """Path rows of a circle moving straight and bouncing off the walls of ``[0, side]^2``."""
    rows = [(0.0, *start)]
    p, v, t = start.copy(), velocity.copy(), 0.0
    lo, hi = radius, side - radius
    while t < until:
        hits = [((hi if v[k] > 0 else lo) - p[k]) / v[k] for k in range(2) if v[k] != 0.0]
        dt = min([h for h in hits if h > 1e-12] + [until - t])
        p, t = p + v * dt, t + dt
        for k in range(2):
            if p[k] >= hi - 1e-12 or p[k] <= lo + 1e-12:
                v[k] = -v[k] if (p[k] >= hi - 1e-12) == (v[k] > 0) else v[k]
        rows.append((t, *p))
    return tuple(tuple(float(c) for c in r) for r in rows)


def _turning(start: np.ndarray, velocity: np.ndarray, radius: float, side: float,
             until: float, acceleration: float) -> tuple[tuple[float, ...], ...]:
    """Path rows (every :data:`TURN_STEP` s) of a circle moving straight and turning back
    before the walls of ``[0, side]^2``: on each axis, once its stopping distance at
    ``acceleration`` reaches the wall, that axis's velocity turns to its opposite at
    ``acceleration`` (so the velocity changes by at most ``sqrt(2) acceleration`` per
    second, and its speed never grows)."""
    rows = [(0.0, *start)]
    p, v = start.copy(), velocity.copy()
    lo, hi = radius, side - radius
    back: list[float | None] = [None, None]     # the velocity an axis turns back to
    for k in range(1, int(math.ceil(until / TURN_STEP)) + 1):
        a = np.zeros(2)
        for i in range(2):
            wall = hi - p[i] if v[i] > 0 else p[i] - lo
            if back[i] is None and v[i] != 0.0 and v[i] * v[i] / (2.0 * acceleration) >= wall:
                back[i] = -v[i]
            if back[i] is not None:
                a[i] = math.copysign(min(acceleration, abs(back[i] - v[i]) / TURN_STEP),
                                     back[i] - v[i])
                if abs(back[i] - v[i] - a[i] * TURN_STEP) <= 1e-12:
                    back[i] = None
        v = v + a * TURN_STEP
        p = p + v * TURN_STEP
        rows.append((k * TURN_STEP, *p))
    return tuple(tuple(float(c) for c in r) for r in rows)


def moving_circles(rng: np.random.Generator, count: int, until: float,
                   acceleration: float | None = None) -> list[WalkingObstacle]:
    """``count`` circles by Real-Time STT's generator, bouncing in the arena.

    Parameters
    ----------
    rng : numpy.random.Generator
        The episode's stream.
    count : int
        How many.
    until : float
        The path's length, s.
    acceleration : float, optional
        Turn back before the walls at this acceleration per axis (m/s^2) instead of
        bouncing off them (a bounce changes the velocity at once: it is outside any bound
        on the acceleration).

    Returns
    -------
    list of WalkingObstacle
    """
    side = SCENARIO["state_space"]["upper"][0]
    start = np.array([1.0, 1.0])
    out = []
    while len(out) < count:
        radius = float(rng.uniform(0.1, 0.4))
        centre = rng.uniform(radius, side - radius, 2)
        velocity = rng.uniform(-1.0, 1.0, 2)
        if np.linalg.norm(centre - start) < CLEAR_OF_START + radius:
            continue
        path = (_bouncing(centre, velocity, radius, side, until) if acceleration is None
                else _turning(centre, velocity, radius, side, until, acceleration))
        out.append(WalkingObstacle(tuple(float(c) for c in centre), radius, path=path))
    return out


def run_sensed_bench(episodes: int, seed: int, counts: tuple[int, ...] = (5, 20),
                     adversary: bool = False, acceleration: float | None = None,
                     speed_only: bool = False, warehouse: bool = False,
                     script: bool = False, rooms: bool = False) -> dict:
    """Seeded episodes of the scenario per obstacle count.

    Parameters
    ----------
    episodes : int
        Episodes per count.
    seed : int
        The first episode's seed (episode ``e`` of count ``N`` draws from ``[seed, N, e]``).
    counts : tuple of int
        The obstacle counts.
    adversary : bool
        Add a pursuer at the envelope's speed.
    acceleration : float, optional
        The envelope's ``max_obstacle_acceleration`` ``A`` (m/s^2), with ``velocity_error``
        :data:`VELOCITY_ERROR`: the circles turn back before the walls at ``A / 2`` per
        axis, and the pursuer turns at ``A``. ``None``: no acceleration bound, bouncing
        circles, a pursuer that turns at once.
    speed_only : bool
        With ``acceleration``: the same obstacles, but the envelope without the
        acceleration bound (the reachable sets grow at the speed bound).
    warehouse : bool
        The warehouse floor with people crossing its aisles instead
        (:mod:`.sensed_warehouse`; ``counts`` are people; episode ``e`` draws from
        ``[seed, N, e]``); not with ``adversary`` or ``acceleration``
        (:class:`~stt_codegen.errors.SpecError`, field ``--warehouse``).
    script : bool
        Real-Time STT's own script instead, its five circles seeded
        (:mod:`.sensed_script`; ``counts`` must be ``(5,)``); the pursuer starts at the
        target's centre at the script's speed bound; not with ``acceleration`` or
        ``warehouse`` (:class:`~stt_codegen.errors.SpecError`, field ``--script``).
    rooms : bool
        A drone's room in three dimensions with balls flying through it instead
        (:mod:`.sensed_rooms`; ``counts`` are balls); not with ``adversary``,
        ``acceleration``, ``warehouse`` or ``script`` (field ``--rooms``).

    Returns
    -------
    dict
        Per count, the tallies, the replanner's times (s), and the episodes that collided
        and that had uncertified spans (``e``: rerun one with the same ``seed`` and ``N``).
    """
    if warehouse and (adversary or acceleration is not None):
        raise SpecError("--warehouse", "the warehouse floor's people walk straight and start "
                                       "at once: not with --adversary or --acceleration")
    if script and (warehouse or acceleration is not None or tuple(counts) != (5,)):
        raise SpecError("--script", "Real-Time STT's script has five circles at constant "
                                    "velocities: --obstacles 5, not with --warehouse or "
                                    "--acceleration")
    if rooms and (adversary or acceleration is not None or warehouse or script):
        raise SpecError("--rooms", "the drone's room has balls flying straight: not with "
                                   "--adversary, --acceleration, --warehouse or --script")
    if rooms:
        with open(ROOM, "rb") as stream:
            scenario = tomllib.load(stream)         # the spec file's own tables
        spec = stt.load_spec(ROOM)
    else:
        scenario = (WAREHOUSE if warehouse else SCRIPT if script else
                    scenario_with(None if speed_only else acceleration))
        spec = stt.Spec.from_dict(scenario)
    design = stt.design_tube(spec)
    speed = spec.sensing.max_obstacle_speed
    pursuer = (PURSUER_START, PURSUER_RADIUS) if script else ((7.0, 1.0), 0.3)
    t_c = spec.prescribed_time
    target = spec.target_set
    rows = []
    for count in counts:
        tally = {"obstacles": count, "episodes": episodes, "collisions": 0,
                 "collisions_certified": 0, "on_time": 0, "late": 0, "not_reached": 0,
                 "uncertified_runs": 0, "outside_envelope": 0, "switches": 0, "escapes": 0,
                 "best_effort": 0, "shortened": 0, "refused": 0, "failures": 0, "replans": 0,
                 "collided_episodes": [], "uncertified_episodes": []}
        cpu, started = [], time.process_time()
        for e in range(episodes):
            rng = np.random.default_rng([seed, count, e])
            obstacles = (aisle_people(rng, count, t_c) if warehouse else
                         script_circles(rng) if script else
                         flying_balls(rng, count, spec.state_space.lower,
                                      spec.state_space.upper, spec.initial_state,
                                      spec.sensing.max_obstacle_radius) if rooms else
                         moving_circles(rng, count, t_c + 1.0,
                                        None if acceleration is None else acceleration / 2.0))
            if adversary:
                obstacles.append(WalkingObstacle(*pursuer, pursuit_speed=speed,
                                                 pursuit_acceleration=acceleration))
            # the CasADi model, as the measurements of docs/performance.md (the C's runs
            # are the same bit for bit, where a compiler is found)
            run = stt.simulate_sensed(design, obstacles, backend="casadi", seed=e)
            record = run.sensing
            tally["collisions"] += record.sensed_collision or run.collision
            if record.sensed_collision or run.collision:
                tally["collided_episodes"].append(e)
            if record.uncertified:
                tally["uncertified_episodes"].append(e)
            tally["collisions_certified"] += record.sensed_collision and (
                record.collision_certified or record.guaranteed)
            tally["on_time"] += run.reached
            late = not run.reached and bool(np.any(np.all(
                (run.trajectory.x >= target.lower) & (run.trajectory.x <= target.upper),
                axis=1)))
            tally["late"] += late
            tally["not_reached"] += not run.reached and not late
            tally["uncertified_runs"] += bool(record.uncertified)
            tally["outside_envelope"] += record.outside_envelope
            for key in ("switches", "escapes", "best_effort", "shortened", "refused",
                        "failures", "replans"):
                tally[key] += getattr(record, key)
            cpu += [ev.cpu_s for ev in record.events]
        tally["replan_cpu_p95_s"] = float(np.percentile(cpu, 95)) if cpu else 0.0
        tally["replan_cpu_max_s"] = float(max(cpu, default=0.0))
        tally["episode_cpu_s"] = (time.process_time() - started) / max(1, episodes)
        rows.append(tally)
    return {"scenario": {k: scenario[k] for k in ("prescribed_time", "sensing")},
            "floor": ("warehouse" if warehouse else "script" if script else
                      "rooms" if rooms else "circles"),
            "seed": seed, "adversary": adversary, "acceleration": acceleration,
            "speed_only": bool(speed_only and acceleration is not None), "rows": rows}


def target_costs(acceleration: float | None = None, warehouse: bool = False,
                 script: bool = False, rooms: bool = False) -> dict:
    """The scenario's controller on the Cortex-M4F with the tube as data
    (:func:`stt_codegen.embedded.tube_data_loop.run_tube_data`): instructions per switch
    and per step on the scenario's tube and on one with 16 circumvent windows open.

    Parameters
    ----------
    acceleration : float, optional
        As :func:`run_sensed_bench` (the envelope does not change the controller).
    warehouse : bool
        The warehouse floor's tube instead (:mod:`.sensed_warehouse`).
    script : bool
        Real-Time STT's script's tube instead (:mod:`.sensed_script`).
    rooms : bool
        The drone's tube in its 3-D room instead (:mod:`.sensed_rooms`).

    Returns
    -------
    dict
        ``step``, ``step_16_windows`` (mean instructions), ``switch``, ``switch_16_windows``,
        ``self_test`` (``"passed/total"``), or ``missing`` (the tools to install) without
        the Arm toolchain or QEMU.
    """
    from stt_codegen.codegen.tube_data import DEFAULT_CAPACITY
    from stt_codegen.embedded import missing_message
    from stt_codegen.embedded.tube_data_loop import run_tube_data
    message = missing_message()
    if message:
        return {"missing": message}
    design = stt.design_tube(stt.load_spec(ROOM) if rooms else stt.Spec.from_dict(
        WAREHOUSE if warehouse else SCRIPT if script else scenario_with(acceleration)))
    r = run_tube_data(design, DEFAULT_CAPACITY)
    mean = lambda v: float(np.mean(v))   # noqa: E731
    return {"step": mean(r["steps_design"]["instructions"]),
            "step_16_windows": mean(r["steps_cost"]["instructions"]),
            "switch": r["switch_design"]["instructions"],
            "switch_16_windows": r["switch_cost"]["instructions"],
            "self_test": f"{r['vectors_passed']}/{r['vectors_passed'] + r['vectors_failed']}"}


def scenario_with(acceleration: float | None) -> dict:
    """:data:`SCENARIO`, with ``max_obstacle_acceleration = acceleration`` and
    ``velocity_error`` :data:`VELOCITY_ERROR` in its envelope when given.

    Parameters
    ----------
    acceleration : float or None
        ``A``, m/s^2.

    Returns
    -------
    dict
    """
    if acceleration is None:
        return SCENARIO
    return {**SCENARIO, "sensing": {**SCENARIO["sensing"],
                                    "max_obstacle_acceleration": float(acceleration),
                                    "velocity_error": VELOCITY_ERROR}}


#: The counts of a report row given with their 95 % intervals as rates: name, key.
RATES = (("collisions", "collisions"), ("on time", "on_time"),
         ("uncertified", "uncertified_runs"))


def _interval(count: int, episodes: int) -> str:
    """The exact (Clopper-Pearson) 95 % interval of the rate ``count / episodes``, in
    percent: what a difference between two runs of the bench can be read as (on 100
    episodes, 12 collisions is 6.4-20.0 %)."""
    from scipy.stats import binomtest
    ci = binomtest(int(count), int(episodes)).proportion_ci(0.95, method="exact")
    return f"{100.0 * ci.low:.1f}-{100.0 * ci.high:.1f} %"


def format_sensed_report(report: dict) -> str:
    """The report as a table, one row per obstacle count.

    Parameters
    ----------
    report : dict
        From :func:`run_sensed_bench`.

    Returns
    -------
    str
    """
    head = (f"{'N':>4} {'episodes':>8} {'collisions':>10} {'(certified)':>11} {'on time':>8} "
            f"{'late':>5} {'uncert.':>7} {'outside':>7} {'switches':>8} {'escapes':>7} "
            f"{'best':>5} {'short':>5} {'failed':>6} "
            f"{'replan p95 [s]':>14} {'max [s]':>8}")
    accel = report.get("acceleration")
    lines = [f"bench sensed: seed {report['seed']}"
             + (", the warehouse floor, people crossing its aisles (N: people)"
                if report.get("floor") == "warehouse" else
                ", Real-Time STT's script, its five circles seeded"
                if report.get("floor") == "script" else
                ", a drone's room in 3-D, balls flying through it (N: balls)"
                if report.get("floor") == "rooms" else "")
             + (", with a pursuer at the envelope's speed" if report["adversary"] else "")
             + ("" if accel is None else
                (f", circles turning at {accel / 2:g} m/s^2 per axis, " +
                 ("the envelope without its acceleration bound" if report.get("speed_only")
                  else f"max_obstacle_acceleration {accel:g} m/s^2"))),
             head]
    for r in report["rows"]:
        lines.append(f"{r['obstacles']:>4} {r['episodes']:>8} {r['collisions']:>10} "
                     f"{r['collisions_certified']:>11} {r['on_time']:>8} {r['late']:>5} "
                     f"{r['uncertified_runs']:>7} {r['outside_envelope']:>7} "
                     f"{r['switches']:>8} {r.get('escapes', 0):>7} "
                     f"{r.get('best_effort', 0):>5} {r.get('shortened', 0):>5} "
                     f"{r['failures']:>6} "
                     f"{r['replan_cpu_p95_s']:>14.3f} {r['replan_cpu_max_s']:>8.3f}")
    for r in report["rows"]:
        if r["episodes"]:
            lines.append(f"N = {r['obstacles']}, 95 % intervals of the rates (exact): "
                         + ", ".join(f"{name} {_interval(r[key], r['episodes'])}"
                                     for name, key in RATES))
    for r in report["rows"]:
        if r.get("collided_episodes"):
            lines.append(f"N = {r['obstacles']}: collisions in episodes "
                         + ", ".join(str(e) for e in r["collided_episodes"]))
    target = report.get("cortex_m4f")
    if target is not None:
        lines.append("Cortex-M4F (QEMU), the tube as data: " + (
            f"not measured ({target['missing']})" if "missing" in target else
            f"{target['step']:.0f} instructions per step on the scenario's tube, "
            f"{target['step_16_windows']:.0f} with 16 windows open; a switch "
            f"{target['switch']} and {target['switch_16_windows']}; self-test "
            f"{target['self_test']}"))
    return "\n".join(lines)
