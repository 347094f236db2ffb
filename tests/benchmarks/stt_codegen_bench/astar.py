"""Baseline 1: A* on an 8-connected occupancy grid, with networkx.

The grid has :data:`RESOLUTION` = 0.05 m spacing (101 x 101 nodes on the 5 m arena). A
node is free when :meth:`~.planning.FreeSpace.is_free` holds at it (obstacles and walls
inflated by the 0.2 m margin); diagonal moves need both side neighbours free (no corner
cutting). Edge weights are Euclidean lengths, the heuristic is the Euclidean distance.
``x(0)`` and the goal are joined to their nearest free node. The planning time includes
building the graph, as a user pays it for every new arena.
"""

from __future__ import annotations

import math
import time

import networkx as nx
import numpy as np

from stt_codegen.spec.loader import Spec
from .planning import FreeSpace, Plan

__all__ = ["RESOLUTION", "grid_graph", "grid_path", "plan_astar"]

#: Grid spacing, metres.
RESOLUTION = 0.05


def grid_graph(space: FreeSpace, resolution: float = RESOLUTION) -> tuple[nx.Graph, np.ndarray]:
    """The free nodes of the grid and their 8-connected edges.

    Parameters
    ----------
    space : FreeSpace
        The arena: its bounds and its obstacles grown by the planners' margin.
    resolution : float, optional
        Grid spacing, metres.

    Returns
    -------
    graph : networkx.Graph
        Nodes ``(i, j)`` at ``origin + resolution * (i, j)``; attribute ``weight`` in metres.
    origin : numpy.ndarray, shape (2,)
        The position of node ``(0, 0)``, metres (a multiple of ``resolution``).
    """
    origin = space.lower - (space.lower % resolution)
    counts = np.floor((space.upper - origin) / resolution).astype(int) + 1
    ii, jj = np.meshgrid(np.arange(counts[0]), np.arange(counts[1]), indexing="ij")
    points = origin + resolution * np.stack([ii.ravel(), jj.ravel()], axis=1)
    free = space.is_free(points).reshape(counts)
    graph = nx.Graph()
    graph.add_nodes_from(zip(*np.nonzero(free)))
    diagonal = resolution * math.sqrt(2.0)
    for di, dj, w in ((1, 0, resolution), (0, 1, resolution), (1, 1, diagonal), (1, -1, diagonal)):
        a = free[max(0, -di):counts[0] - max(0, di), max(0, -dj):counts[1] - max(0, dj)]
        b = free[max(0, di):, max(0, dj):][:a.shape[0], :a.shape[1]]
        ok = a & b
        if di and dj:  # both side neighbours free
            ok &= free[max(0, di):, max(0, -dj):counts[1] - max(0, dj)][:a.shape[0], :a.shape[1]]
            ok &= free[max(0, -di):counts[0] - max(0, di), max(0, dj):][:a.shape[0], :a.shape[1]]
        i0, j0 = np.nonzero(ok)
        i0, j0 = i0 + max(0, -di), j0 + max(0, -dj)
        graph.add_weighted_edges_from(
            ((int(i), int(j)), (int(i + di), int(j + dj)), w) for i, j in zip(i0, j0))
    return graph, origin


def _nearest(graph: nx.Graph, origin: np.ndarray, point: np.ndarray,
             resolution: float) -> tuple[int, int] | None:
    nodes = np.array(list(graph.nodes), dtype=float).reshape(-1, 2)
    if not len(nodes):
        return None
    k = int(np.argmin(np.sum((origin + resolution * nodes - point) ** 2, axis=1)))
    return int(nodes[k, 0]), int(nodes[k, 1])


def grid_path(graph: nx.Graph, origin: np.ndarray, start: np.ndarray, goal: np.ndarray,
              resolution: float = RESOLUTION) -> np.ndarray | None:
    """A* on the occupancy grid between the free nodes nearest ``start`` and ``goal``.

    Parameters
    ----------
    graph, origin
        From :func:`grid_graph`.
    start, goal : ndarray, shape (2,)
        Metres.
    resolution : float
        The grid's spacing, metres.

    Returns
    -------
    ndarray, shape (K, 2), or None
        The grid nodes of the path, metres (``start`` and ``goal`` not included); ``None``
        when no free node is reachable from the other.
    """
    source = _nearest(graph, origin, start, resolution)
    target = _nearest(graph, origin, goal, resolution)

    def heuristic(a, b):
        return resolution * math.hypot(a[0] - b[0], a[1] - b[1])

    try:
        if source is None or target is None:
            raise nx.NetworkXNoPath
        nodes = nx.astar_path(graph, source, target, heuristic=heuristic, weight="weight")
    except nx.NetworkXNoPath:
        return None
    return origin + resolution * np.array(nodes, dtype=float)


def plan_astar(spec: Spec, resolution: float = RESOLUTION) -> Plan:
    """Plan from ``x(0)`` to the target's centre with A* on the occupancy grid.

    Parameters
    ----------
    spec : Spec
        A 2-D spec.
    resolution : float
        Grid spacing, metres.

    Returns
    -------
    Plan
        ``reason`` is ``"no path found"`` when the goal is not reachable on the grid.
    """
    begin = time.perf_counter()
    space = FreeSpace.of(spec)
    graph, origin = grid_graph(space, resolution)
    path = grid_path(graph, origin, space.start, space.goal, resolution)
    if path is None:
        return Plan(None, time.perf_counter() - begin, "no path found")
    path = np.vstack([space.start, path, space.goal])
    return Plan(path, time.perf_counter() - begin)
