"""Baseline 2: RRT* from OMPL (``pip install ompl``, the maintained Open Motion Planning
Library's own Python bindings), optional.

Configuration: ``RealVectorStateSpace(2)`` on the arena shrunk by the margin, the state
validity checker :meth:`~.planning.FreeSpace.point_checker` (obstacles inflated by 0.2 m),
motion checked every 0.5 % of the space's extent (3.5 cm), goal tolerance
:data:`GOAL_TOLERANCE`, OMPL's default range and path-length objective. The planner
stops after :data:`ITERATIONS` iterations (a fixed budget, so that the run is
deterministic for a seed: OMPL's RNG is seeded per arena) or :data:`MAX_SECONDS`.

Only imported inside worker processes: OMPL 2.0.1's nanobind bindings print reference-leak
warnings when an interpreter that imported them exits normally.
"""

from __future__ import annotations

import time

import numpy as np

from stt_codegen.spec.loader import Spec
from .planning import FreeSpace, Plan

__all__ = ["ompl_available", "plan_rrtstar"]

#: RRT* iterations per arena (the first solution typically appears within 100).
ITERATIONS = 2000
#: Wall-clock cap per arena, seconds.
MAX_SECONDS = 10.0
#: Distance to the target's centre at which the goal counts as reached, metres.
GOAL_TOLERANCE = 0.05
#: Motion validity resolution as a fraction of the space's extent.
CHECK_RESOLUTION = 0.005


def ompl_available() -> str:
    """Empty when OMPL's Python bindings import, else why not (one line).

    Returns
    -------
    str
        ``""`` when OMPL imports, else the reason and how to install it.
    """
    try:
        from ompl import base, geometric, util  # noqa: F401
    except ImportError as exc:
        return f"ompl is not installed ({exc}); pip install ompl"
    return ""


def plan_rrtstar(spec: Spec, seed: int, iterations: int = ITERATIONS) -> Plan:
    """Plan from ``x(0)`` to the target's centre with OMPL's RRT*.

    Parameters
    ----------
    spec : Spec
        A 2-D spec.
    seed : int
        Seed of OMPL's random number generator (positive; 0 is mapped to 1).
    iterations : int
        Planner iterations.

    Returns
    -------
    Plan
        ``reason`` is ``"no path found"`` when RRT* has no exact solution at the end.
    """
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    begin = time.perf_counter()
    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(max(1, int(seed)))
    space = FreeSpace.of(spec)
    state_space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    for i in range(2):
        bounds.setLow(i, float(space.lower[i]))
        bounds.setHigh(i, float(space.upper[i]))
    state_space.setBounds(bounds)
    info = ob.SpaceInformation(state_space)
    free = space.point_checker()
    info.setStateValidityChecker(lambda s: free(s[0], s[1]))
    info.setStateValidityCheckingResolution(CHECK_RESOLUTION)
    info.setup()
    start, goal = state_space.allocState(), state_space.allocState()
    for i in range(2):
        start[i], goal[i] = float(space.start[i]), float(space.goal[i])
    problem = ob.ProblemDefinition(info)
    problem.setStartAndGoalStates(start, goal, GOAL_TOLERANCE)
    planner = og.RRTstar(info)
    planner.setProblemDefinition(problem)
    planner.setup()
    deadline = begin + MAX_SECONDS
    planner.solve(ob.PlannerTerminationCondition(
        lambda: planner.numIterations() >= iterations or time.perf_counter() > deadline))
    if not problem.hasExactSolution():
        return Plan(None, time.perf_counter() - begin, "no path found")
    solution = problem.getSolutionPath()
    path = np.array([[solution.getState(k)[0], solution.getState(k)[1]]
                     for k in range(solution.getStateCount())])
    path = np.vstack([path, space.goal])
    return Plan(path, time.perf_counter() - begin)
