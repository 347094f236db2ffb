"""The fleet's closed loops: every robot with its own plant, the pairs' closest approach.

The robots never communicate, so each robot's closed loop is its own: each is simulated
apart (:func:`~.simulate.simulate`, its own plant and seeded disturbance) on the same
horizon, and every pair's distance is then measured on the sampling instants of the
slower of the two (docs/fleets.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..design.fleet import FleetDesign
from .simulate import SimulationResult, simulate

__all__ = ["Approach", "FleetRun", "simulate_fleet"]

#: The fleet's runs last this many times the longest prescribed time.
HORIZON_FACTOR = 1.25


@dataclass(frozen=True)
class Approach:
    """Two robots' closest approach in a run.

    Attributes
    ----------
    pair : (str, str)
        The robots' names.
    clearance : float
        The smallest distance between their reference points less both reaches (a lower
        bound of the distance between their bodies), at the common sampling instants,
        state units (metres); negative: the bodies may have touched.
    t : float
        When, seconds.
    """

    pair: tuple[str, str]
    clearance: float
    t: float


@dataclass(frozen=True)
class FleetRun:
    """Every robot's closed loop and every pair's closest approach.

    Attributes
    ----------
    results : dict of str to SimulationResult
        Per robot, its own run (Definition 2.1 judged on its spec, where the other robots'
        tubes are moving obstacles).
    approaches : tuple of Approach
        Per pair, closest first.
    horizon : float
        The runs' length, seconds.
    """

    results: dict[str, SimulationResult]
    approaches: tuple[Approach, ...]
    horizon: float

    @property
    def satisfied(self) -> bool:
        """Every robot satisfied its task and no two bodies came closer than their reaches."""
        return (all(r.satisfied for r in self.results.values())
                and all(a.clearance > 0 for a in self.approaches))

    @property
    def closest(self) -> Approach | None:
        """The closest pair (``None`` for one robot)."""
        return self.approaches[0] if self.approaches else None


def simulate_fleet(fleet: FleetDesign, *, backend: str | None = None,
                   horizon: float | None = None, seed: int = 0) -> FleetRun:
    """Run every robot's controller against its own plant; measure every pair's approach.

    Parameters
    ----------
    fleet : FleetDesign
        From :func:`stt_codegen.design_fleet`.
    backend : str, optional
        As :func:`stt_codegen.simulate` (``"c"`` runs each robot's generated C).
    horizon : float, optional
        Seconds; default 1.25 times the longest ``prescribed_time`` (every robot rests in
        its target at the end).
    seed : int, optional
        The robot at position ``i`` of the fleet file uses ``seed + i``.

    Returns
    -------
    FleetRun

    Raises
    ------
    TypeError
        ``fleet`` is not a :class:`~stt_codegen.design.fleet.FleetDesign`.
    SpecError
        As :func:`stt_codegen.simulate` (``horizon``, ``seed``, ``backend``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> run = stt.simulate_fleet(fleet, backend="c")
    >>> run.satisfied, run.closest.pair, run.closest.clearance > fleet.narrowest.margin
    (True, ('east', 'west'), True)
    """
    if not isinstance(fleet, FleetDesign):
        raise TypeError("simulate_fleet(): parameter 'fleet' must be a FleetDesign (call "
                        f"stt_codegen.design_fleet first), not {type(fleet).__name__}")
    robots = fleet.fleet.robots
    if horizon is None:
        horizon = HORIZON_FACTOR * max(r.spec.prescribed_time for r in robots)
    results = {r.name: simulate(fleet.designs[r.name], backend=backend, horizon=horizon,
                                seed=seed + r.index) for r in robots}
    approaches = []
    for a in range(len(robots)):
        for b in range(a + 1, len(robots)):
            ra, rb = robots[a], robots[b]
            approaches.append(_approach(ra, rb, results[ra.name], results[rb.name]))
    return FleetRun(results, tuple(sorted(approaches, key=lambda p: p.clearance)),
                    float(horizon))


def _approach(ra, rb, a: SimulationResult, b: SimulationResult) -> Approach:
    """The closest approach of two runs, on the instants of the slower one."""
    ta, tb = a.trajectory.t, b.trajectory.t
    slow, fast = (ta, tb) if ta.size <= tb.size else (tb, ta)
    # the fast run's sample at or before each slow instant (the same instant when one
    # rate is a multiple of the other)
    k = np.clip(np.searchsorted(fast, slow + 1e-9, side="right") - 1, 0, fast.size - 1)
    xa = a.trajectory.x if slow is ta else a.trajectory.x[k]
    xb = b.trajectory.x if slow is tb else b.trajectory.x[k]
    d = list(ra.dims)
    dist = np.linalg.norm(xa[:, d] - xb[:, d], axis=1) - (ra.reach + rb.reach)
    i = int(np.argmin(dist))
    return Approach((ra.name, rb.name), float(dist[i]), float(slow[i]))
