"""How each controller variant splits the plant's state: where the run starts, and the
point the tube holds.

* ``"first-order"``: the plant's state is the tube's (``n`` states).
* ``"cascade"``: ``[x1; x2]``, positions then velocities (``2 n``); the tube holds ``x1``,
  the run starts at ``initial.state`` and ``initial.velocity``.
* ``"look-ahead"``: the differential drive's ``(x, y, theta)``; the tube holds the
  look-ahead point (:func:`stt_codegen.tube.look_ahead_reference.point`), ``initial.state``
  is that point's and ``initial.heading`` the heading.

The simulation and the plots look the variant up here (:func:`initial_state`,
:func:`positions`), never compare model names.
"""

from __future__ import annotations

import numpy as np

from ..spec.loader import Spec
from ..spec.plants import model_behaviour
from ..tube import look_ahead_reference

__all__ = ["initial_state", "positions"]


def _cascade_start(spec: Spec) -> np.ndarray:
    return np.array([*spec.initial_state, *spec.second_order.initial_velocity], dtype=float)


_STARTS = {
    "first-order": lambda spec: np.array(spec.initial_state, dtype=float),
    "cascade": _cascade_start,
    "look-ahead": lambda spec: np.array(spec.drive.initial_axle(spec.initial_state),
                                        dtype=float),
}

_POINTS = {
    "first-order": lambda spec, states: states[:, :spec.dimension],
    "cascade": lambda spec, states: states[:, :spec.dimension],
    "look-ahead": lambda spec, states: look_ahead_reference.point(states,
                                                                   spec.drive.axle_offset),
}


def initial_state(spec: Spec) -> np.ndarray:
    """The plant's state at ``t = 0``.

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    ndarray
        ``n`` states (first order), ``2 n`` (cascade: positions, then velocities) or 3
        (differential drive: the axle's midpoint, m, and the heading, rad).
    """
    return model_behaviour(_STARTS, spec.variant, "initial state")(spec)


def positions(spec: Spec, states: np.ndarray) -> np.ndarray:
    """The points the tube holds, of plant states.

    Parameters
    ----------
    spec : Spec
    states : ndarray, shape (N, m)
        Plant states (:func:`initial_state`'s layout).

    Returns
    -------
    ndarray, shape (N, n)
        The positions in the spec's state space, state units.
    """
    return model_behaviour(_POINTS, spec.variant, "state split")(spec, np.atleast_2d(states))
