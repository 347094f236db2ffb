"""stlpy's benchmark scenarios (Kurtz and Lin) written as specs, without hand choices.

stlpy's scenario objects (``stlpy.benchmarks``) carry their regions, their horizon ``T``
(in steps) and their system; the initial state and the bounds passed to the solver live in
stlpy's example scripts. :data:`SCENARIOS` holds those example settings as published
(``examples/*.py`` of stlpy 0.3.0); everything else is read from the scenario object:

* **Time.** One step is the system's own: ``dt`` of a system that has one (the unicycle,
  0.1 s), else 1 s (the double integrator, whose ``A = [[I, I], [0, I]]`` is one second of
  ``p_dot = v``). ``prescribed_time = T dt``; windows ``[0, T]`` steps become ``[0, T dt]``
  seconds.
* **State space.** The scenario's own field of view (the limits ``add_to_plot`` sets).
  Boxes are clipped to it (stlpy draws walls a hundredth past the border); the judge
  keeps the scenario's own boxes.
* **Initial set.** ``x0`` of the example, with :data:`INITIAL_HALF_SIDE` either side in
  every position dimension (clipped to the state space).
* **Plant.** A double integrator is written twice. As itself (``order="second"``): the
  ``double-integrator`` model with unit mass (stlpy's ``B = [[0], [I]]``: the input is the
  acceleration), ``state_space.velocity_bound`` the example's ``|v|`` bound and
  ``[actuator] input_bound`` its ``|u|`` bound (ReachAvoid's example defines ``|u| <=
  0.5``, ``|v| <= 1`` without passing them to its solver: :data:`DEFINED_BOUNDS`). And as
  the project's first-order position law (``single-integrator``, the stage ``p_dot = v``
  whose input is the velocity) with ``[actuator] input_bound`` the example's velocity
  bound (``x_max``'s velocity entries, when the example passes state bounds to its
  solver); see :data:`ORDER_NOTE`. The unicycle
  is written as the omnidirectional robot of eq. (14) (the nearest plant the project has;
  it may also move sideways, which the unicycle may not) with ``input_bound`` the example's
  ``|v| <= 10`` for both body velocities and ``|omega| <= 5``; its heading is kept in
  ``[-HEADING, HEADING]`` rad (:data:`HEADING`), inside the range where Assumption 2
  holds for eq. (14) and narrow enough for the sampled-data check at 1 kHz.
* **Formula.** ``F[0,T] G`` is the target (an or of boxes: ``[target] any_of``; a circle:
  the square inscribed in it); ``G[0,T] not O`` an obstacle (a circle: a ball obstacle);
  another ``F[0,T]`` of boxes a reach task with ``window = [0, T dt]``; ``F[0,T-tau]
  G[0,tau]`` of an or of boxes a stay task with ``duration = tau dt``; ``not D U[0,T] K`` a
  reach task ``K`` and an obstacle ``D`` with ``active_until = K``. With several tasks,
  ``[task_order] order = "any"``. A scenario whose ``F`` goals have no distinguished last
  goal (``RandomMultitarget``) takes its last group as the target.

Every key not listed here takes the project's default (disturbance ``|w_i| <= 0.1``, which
``disturbance`` replaces: 0 is stlpy's model, ``rate_hz = 1000``, ...). ``SteppingStones``
is not written (:data:`SKIPPED`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

__all__ = ["DEFINED_BOUNDS", "HEADING", "INITIAL_HALF_SIDE", "ORDER_NOTE", "SCENARIOS", "SKIPPED",
           "ScenarioSetting", "double_integrators", "make_scenario", "scenario_names",
           "scenario_spec", "spec_toml", "step_seconds", "workspace"]

#: Half side of the initial box around the example's ``x0``, state units.
INITIAL_HALF_SIDE = 0.1
#: The unicycle's heading bound, rad: the state space and the target keep the heading in
#: ``[-HEADING, HEADING]``. Eq. (14)'s input gain couples the two body velocities by
#: ``sin`` of the heading; over ``[-1.2, 1.2]`` (coupling 0.93) the sampled-data check of
#: the bound fails at every rate up to 16 kHz, over ``[-0.3, 0.3]`` it passes at 1 kHz.
#: stlpy's formula does not constrain the heading.
HEADING = 0.3

#: How a double-integrator scenario is written.
ORDER_NOTE = ("double integrators are written as themselves (second order: the cascade, "
              "|u| and |v| the example's bounds) and as the first-order position law "
              "(single-integrator: its input is the velocity, bounded by the example's |v|)")

#: Bounds an example defines without passing them to its solver, ``(|u|, |v|)`` per axis:
#: the second-order spec takes them (a cascade needs a velocity bound to be compared).
DEFINED_BOUNDS = {"ReachAvoid": ((0.5, 0.5), (1.0, 1.0))}

#: Scenarios not written, with the reason.
SKIPPED = {"SteppingStones": "a union safe set (G[0,T] of an or of stones) cannot be a "
                             "spec (one state-space box, box obstacles), and for seed 1 it "
                             "is impossible in continuous time: the stones that touch "
                             "x0 = (2, 1.3) and their neighbours (3 of 15) never meet the "
                             "target stone, so every path to it leaves the stones between "
                             "samples"}


@dataclass(frozen=True)
class ScenarioSetting:
    """The settings of one stlpy example script.

    Attributes
    ----------
    args : tuple
        The scenario's constructor arguments (positional), as the example passes them.
    kwargs : dict
        Its keyword arguments.
    x0 : tuple of float
        The example's initial state (positions first).
    input_bound : tuple of float or None
        ``u_max`` when the example passes control bounds to its solver (symmetric in every
        example that does, except the unicycle's forward speed ``[0, 10]``), else ``None``.
    velocity_bound : tuple of float or None
        ``x_max``'s velocity entries when the example passes state bounds to its solver.
    position_max : tuple of float or None
        ``x_max``'s position entries when they differ from the field of view's upper
        limits (``x_min``'s are 0 in every double-integrator example).
    """

    args: tuple
    kwargs: dict = field(default_factory=dict)
    x0: tuple[float, ...] = ()
    input_bound: tuple[float, ...] | None = None
    velocity_bound: tuple[float, ...] | None = None
    position_max: tuple[float, ...] | None = None


#: stlpy 0.3.0's examples: ``reach_avoid.py`` defines ``u_min``/``x_min`` but passes
#: neither to its solver, so it has no bound here.
SCENARIOS: dict[str, ScenarioSetting] = {
    "ReachAvoid": ScenarioSetting(((7, 8, 8, 9), (3, 5, 4, 6), 10), x0=(1.0, 2.0, 0.0, 0.0)),
    "EitherOr": ScenarioSetting(((7, 8, 8, 9), (1, 2, 6, 7), (7, 8, 4.5, 5.5), (3, 5, 4, 6),
                                 20, 5), x0=(2.0, 2.0, 0.0, 0.0),
                                input_bound=(0.5, 0.5), velocity_bound=(1.0, 1.0)),
    "NarrowPassage": ScenarioSetting((25,), x0=(3.0, 3.6, 0.0, 0.0),
                                     input_bound=(0.5, 0.5), velocity_bound=(1.0, 1.0),
                                     position_max=(10.0, 10.0)),
    "RandomMultitarget": ScenarioSetting((1, 5, 2, 25), {"seed": 0}, x0=(5.0, 2.0, 0.0, 0.0),
                                         input_bound=(0.5, 0.5), velocity_bound=(1.0, 1.0)),
    "DoorPuzzle": ScenarioSetting((25, 2), x0=(6.0, 1.0, 0.0, 0.0),
                                  input_bound=(0.5, 0.5), velocity_bound=(2.0, 2.0)),
    "NonlinearReachAvoid": ScenarioSetting(((7.5, 8.5), 0.75, (3.5, 5), 1.5, 15),
                                           x0=(1.0, 2.0, 0.0), input_bound=(10.0, 5.0)),
}


def scenario_names() -> list[str]:
    """The scenarios :func:`scenario_spec` writes, in stlpy's order.

    Returns
    -------
    list of str
    """
    return list(SCENARIOS)


def double_integrators() -> list[str]:
    """The scenarios whose system is stlpy's double integrator (all but the unicycle).

    Returns
    -------
    list of str
    """
    return [name for name in SCENARIOS if name != "NonlinearReachAvoid"]


def make_scenario(name: str, horizon: int | None = None) -> Any:
    """The stlpy scenario object of an example.

    Parameters
    ----------
    name : str
        A key of :data:`SCENARIOS`.
    horizon : int, optional
        ``T`` in steps instead of the example's (the CI's small sizes); for
        ``NonlinearReachAvoid`` and the others alike it replaces the argument ``T``.

    Returns
    -------
    stlpy.benchmarks.BenchmarkScenario

    Raises
    ------
    KeyError
        An unknown name.
    ImportError
        stlpy is not installed (``pip install stt-codegen[stl]``).
    """
    import stlpy.benchmarks as benchmarks
    setting = SCENARIOS[name]
    args = list(setting.args)
    if horizon is not None:
        args[_HORIZON_ARG[name]] = int(horizon)
    return getattr(benchmarks, name)(*args, **setting.kwargs)


#: Position of ``T`` among each scenario's constructor arguments.
_HORIZON_ARG = {"ReachAvoid": 2, "EitherOr": 4, "NarrowPassage": 0, "RandomMultitarget": 3,
                "DoorPuzzle": 0, "NonlinearReachAvoid": 4}


def step_seconds(scenario: Any) -> float:
    """One step of the scenario's system: its ``dt`` if it has one, else 1 s.

    Parameters
    ----------
    scenario : stlpy.benchmarks.BenchmarkScenario

    Returns
    -------
    float
        Seconds.
    """
    return float(getattr(scenario.GetSystem(), "dt", 1.0))


def workspace(scenario: Any) -> tuple[tuple[float, float], tuple[float, float]]:
    """The scenario's field of view, the limits its ``add_to_plot`` sets.

    Parameters
    ----------
    scenario : stlpy.benchmarks.BenchmarkScenario

    Returns
    -------
    tuple
        ``((x_lo, x_hi), (y_lo, y_hi))``, state units.
    """
    from matplotlib.figure import Figure
    ax = Figure().add_subplot()
    scenario.add_to_plot(ax)
    return tuple(float(v) for v in ax.get_xlim()), tuple(float(v) for v in ax.get_ylim())


def _clip(bounds, space) -> list[float] | None:
    """stlpy's ``(x_lo, x_hi, y_lo, y_hi)`` clipped to the workspace as ``[lo], [hi]``."""
    (xl, xh), (yl, yh) = space
    lo = [max(bounds[0], xl), max(bounds[2], yl)]
    hi = [min(bounds[1], xh), min(bounds[3], yh)]
    if lo[0] >= hi[0] or lo[1] >= hi[1]:
        return None
    return [float(v) for v in lo], [float(v) for v in hi]


def _box(bounds, space) -> dict[str, list[float]]:
    lo, hi = _clip(bounds, space)
    return {"lower": lo, "upper": hi}


def _goal(options: list, space) -> dict[str, Any]:
    boxes = [_box(b, space) for b in options if _clip(b, space) is not None]
    return boxes[0] if len(boxes) == 1 else {"any_of": boxes}


def _reach(options: list, space, seconds: float) -> dict[str, Any]:
    return {"kind": "reach", "window": [0.0, seconds], **_goal(options, space)}


def _parts(name: str, sc: Any, space, seconds: float, dt: float) -> dict[str, Any]:
    """Target, obstacles and tasks of one scenario kind, from the object's attributes."""
    if name == "ReachAvoid":
        return {"target": _goal([sc.goal_bounds], space), "obstacles": [sc.obstacle_bounds]}
    if name == "EitherOr":
        stay = {"kind": "stay", "window": [0.0, seconds], "duration": sc.T_dwell * dt,
                **_goal([sc.target_one, sc.target_two], space)}
        return {"target": _goal([sc.goal], space), "obstacles": [sc.obstacle],
                "tasks": [stay]}
    if name == "NarrowPassage":
        return {"target": _goal(sc.goals, space), "obstacles": list(sc.obstacles)}
    if name == "RandomMultitarget":
        *groups, last = sc.targets
        return {"target": _goal(last, space), "obstacles": list(sc.obstacles),
                "tasks": [_reach(g, space, seconds) for g in groups]}
    if name == "DoorPuzzle":
        keys = [sc.key1_bounds, sc.key2_bounds, sc.key3_bounds, sc.key4_bounds][:sc.N]
        doors = [sc.door1_bounds, sc.door2_bounds, sc.door3_bounds, sc.door4_bounds][:sc.N]
        walls = [sc.obs1_bounds, sc.obs2_bounds, sc.obs3_bounds, sc.obs4_bounds,
                 sc.obs5_bounds]
        return {"target": _goal([sc.goal_bounds], space), "obstacles": walls,
                "tasks": [_reach([k], space, seconds) for k in keys],
                "until": doors}
    if name == "NonlinearReachAvoid":
        (cx, cy), r = sc.goal_center, sc.goal_radius / math.sqrt(2.0)
        return {"target": _box((cx - r, cx + r, cy - r, cy + r), space),
                "balls": [(tuple(sc.obstacle_center), sc.obstacle_radius)]}
    raise KeyError(name)


def scenario_spec(name: str, horizon: int | None = None, order: str = "first",
                  disturbance: float | None = None) -> dict[str, Any]:
    """The spec document of one stlpy example (module notes), as :meth:`Spec.from_dict`
    takes it.

    Parameters
    ----------
    name : str
        A key of :data:`SCENARIOS` (``ReachAvoid``, ``EitherOr``, ``NarrowPassage``,
        ``RandomMultitarget``, ``DoorPuzzle``, ``NonlinearReachAvoid``).
    horizon : int, optional
        ``T`` in steps instead of the example's.
    order : {"first", "second"}
        A double integrator as the first-order position law or as itself (module notes).
    disturbance : float, optional
        ``plant.disturbance_amplitude`` (``|w_i|``, state units per second; 0 is stlpy's
        own model, which has none); ``None``: the project's default (0.1).

    Returns
    -------
    dict
        The spec's tables (``name`` is ``stlpy-<name>``, ``stlpy-<name>-second-order``).

    Raises
    ------
    KeyError
        An unknown or skipped scenario (:data:`SKIPPED`).
    ValueError
        ``order="second"`` for a scenario that is not a double integrator, or another
        ``order``.
    ImportError
        stlpy is not installed.
    """
    if name in SKIPPED:
        raise KeyError(f"{name}: {SKIPPED[name]}")
    if order not in ("first", "second") or (order == "second"
                                            and name not in double_integrators()):
        raise ValueError(f"order {order!r} for {name}: 'first', or 'second' for a double "
                         "integrator")
    setting = SCENARIOS[name]
    sc = make_scenario(name, horizon)
    dt = step_seconds(sc)
    seconds = sc.T * dt
    space = workspace(sc)
    parts = _parts(name, sc, space, seconds, dt)
    unicycle = name == "NonlinearReachAvoid"
    lower = [space[0][0], space[1][0]] + ([-HEADING] if unicycle else [])
    upper = [space[0][1], space[1][1]] + ([HEADING] if unicycle else [])
    dims = len(lower)
    x0 = list(setting.x0[:dims])
    init_lo = [max(x - INITIAL_HALF_SIDE, lo) for x, lo in zip(x0, lower)]
    init_hi = [min(x + INITIAL_HALF_SIDE, hi) for x, hi in zip(x0, upper)]
    if unicycle:
        parts["target"] = {"lower": parts["target"]["lower"] + [-HEADING],
                           "upper": parts["target"]["upper"] + [HEADING]}
    doc: dict[str, Any] = {
        "name": f"stlpy-{name}",
        "prescribed_time": float(seconds),
        "state_space": {"lower": lower, "upper": upper},
        "initial": {"lower": init_lo, "upper": init_hi, "state": x0},
        "target": parts["target"],
    }
    obstacles = [{"lower": lo, "upper": hi} for lo, hi in
                 (_clip(b, space) for b in parts["obstacles"]) if lo is not None] \
        if parts.get("obstacles") else []
    obstacles += [{"center": list(map(float, c)), "radius": float(r)}
                  for c, r in parts.get("balls", [])]
    tasks = parts.get("tasks", [])
    for k, door in enumerate(parts.get("until", [])):
        lo, hi = _clip(door, space)
        obstacles.append({"lower": lo, "upper": hi, "active_until": f"T{k + 1}"})
    if obstacles:
        doc["obstacles"] = obstacles
    if tasks:
        doc["tasks"] = tasks
        if len(tasks) > 1:
            doc["task_order"] = {"order": "any"}
    if unicycle:
        doc["plant"] = {"model": "omnidirectional"}
        speed, turn = setting.input_bound
        doc["actuator"] = {"input_bound": [speed, speed, turn]}
    elif order == "second":
        force, speed = DEFINED_BOUNDS.get(name, (setting.input_bound, setting.velocity_bound))
        doc["name"] += "-second-order"
        doc["plant"] = {"model": "double-integrator", "parameters": [1.0]}
        doc["state_space"]["velocity_bound"] = list(speed)
        doc["actuator"] = {"input_bound": list(force)}
    elif setting.velocity_bound is not None:
        doc["actuator"] = {"input_bound": list(setting.velocity_bound)}
    if disturbance is not None:
        doc.setdefault("plant", {})["disturbance_amplitude"] = float(disturbance)
    return doc


def _value(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v + '"'
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(float(v) + 0.0)     # repr round-trips: the file is the same spec


def spec_toml(doc: dict[str, Any], header: str) -> str:
    """A spec document of :func:`scenario_spec` as TOML text.

    Parameters
    ----------
    doc : dict
        From :func:`scenario_spec`.
    header : str
        The file's leading comment (one or more lines).

    Returns
    -------
    str
        The TOML text: top-level keys, tables, then arrays of tables.
    """
    lines = [f"# {line}" for line in header.splitlines()]
    tables: list[str] = []
    for key, v in doc.items():
        if isinstance(v, dict):
            tables += [f"\n[{key}]"] + [f"{k} = {_value(x)}" for k, x in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for entry in v:
                tables += [f"\n[[{key}]]"] + [f"{k} = {_value(x)}" for k, x in entry.items()]
        else:
            lines.append(f"{key} = {_value(v)}")
    return "\n".join(lines + tables) + "\n"

