"""A spec's moving obstacles as the static boxes they sweep: what a static design can plan
around (the moving-obstacle design's swept step, :mod:`.moving`, and the legs of a tasks'
plan before the task an obstacle lasts until, :mod:`.tasks`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from ..spec.loader import Obstacle, Spec

__all__ = ["swept_spec"]


def swept_spec(spec: Spec, which: Sequence[int] | None = None) -> tuple[Spec | None, str]:
    """``spec`` with moving obstacles as the static boxes they sweep while active.

    Parameters
    ----------
    spec : Spec
    which : sequence of int, optional
        Positions in ``spec.moving_obstacles`` to sweep; default all. The others stay
        moving.

    Returns
    -------
    (Spec or None, str)
        The spec (those moving obstacles removed, their swept boxes, clipped to the state
        space, added as obstacles with the same index), or ``None`` and why not (a swept
        box meets the initial set or the target set).
    """
    extra = []
    space = spec.state_space
    chosen = range(len(spec.moving_obstacles)) if which is None else which
    for ob in (spec.moving_obstacles[i] for i in chosen):
        lo, hi, _ = ob.hull([ob.active[0]], [ob.active[1]])
        lower = tuple(max(float(a), space.lower[d]) for a, d in zip(lo[0], ob.dims))
        upper = tuple(min(float(b), space.upper[d]) for b, d in zip(hi[0], ob.dims))
        if any(a >= b for a, b in zip(lower, upper)):
            continue                       # never inside the state space
        swept = Obstacle(lower, upper, ob.dims, ob.source)
        box = swept.box(space)
        for label, other in (("initial", spec.initial_set), ("target", spec.target_set)):
            if box.meets(other):
                return None, (f"the region moving obstacle {ob.source} sweeps while active "
                              f"meets the {label} set")
        extra.append(swept)
    keep = tuple(ob for i, ob in enumerate(spec.moving_obstacles) if i not in chosen)
    return replace(spec, obstacles=spec.obstacles + tuple(extra), moving_obstacles=keep), ""
