"""How each controller variant splits the plant's state: where the run starts, and the
point the tube holds.

* ``"first-order"``: the plant's state is the tube's (``n`` states).
* ``"cascade"``: ``[x1; x2]``, positions then velocities (``2 n``); the tube holds ``x1``,
  the run starts at ``initial.state`` and ``initial.velocity``.
* ``"look-ahead"``: the differential drive's ``(x, y, theta)``; the tube holds the
  look-ahead point (:func:`stt_codegen.tube.look_ahead_reference.point`), ``initial.state``
  is that point's and ``initial.heading`` the heading.

The simulation and the plots call :func:`initial_state` and :func:`positions`, which
look the spec's variant up (:mod:`stt_codegen.spec.variants`, roles ``initial_state`` and
``positions``), never compare model names.
"""

from __future__ import annotations

import numpy as np

from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube import look_ahead_reference

__all__ = ["cascade_start", "initial_state", "leading_positions", "look_ahead_positions",
           "look_ahead_start", "positions", "tube_state_start"]


def tube_state_start(spec: Spec) -> np.ndarray:
    """The first-order plant's state at ``t = 0``: ``initial.state`` (role
    ``initial_state`` of :mod:`~stt_codegen.spec.variants`).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.array(spec.initial_state, dtype=float)


def cascade_start(spec: Spec) -> np.ndarray:
    """The second-order plant's state at ``t = 0``: ``initial.state``, then
    ``initial.velocity`` (role ``initial_state``).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    ndarray, shape (2 n,)
    """
    return np.array([*spec.initial_state, *spec.second_order.initial_velocity], dtype=float)


def look_ahead_start(spec: Spec) -> np.ndarray:
    """The base's state at ``t = 0``: the axle behind the look-ahead point
    ``initial.state`` at ``initial.heading`` (role ``initial_state``).

    Parameters
    ----------
    spec : Spec

    Returns
    -------
    ndarray, shape (3,)
        ``(x, y)`` of the axle's midpoint, m, and the heading, rad.
    """
    return np.array(spec.drive.initial_axle(spec.initial_state), dtype=float)


def leading_positions(spec: Spec, states: np.ndarray) -> np.ndarray:
    """The tube's coordinates as the leading ``n`` states (first order; the cascade's
    positions ``x1``): role ``positions``.

    Parameters
    ----------
    spec : Spec
    states : ndarray, shape (N, m)

    Returns
    -------
    ndarray, shape (N, n)
    """
    return states[:, :spec.dimension]


def look_ahead_positions(spec: Spec, states: np.ndarray) -> np.ndarray:
    """The look-ahead points of the base's states (role ``positions``).

    Parameters
    ----------
    spec : Spec
    states : ndarray, shape (N, 3)

    Returns
    -------
    ndarray, shape (N, 2)
        :func:`stt_codegen.tube.look_ahead_reference.point`, m.
    """
    return look_ahead_reference.point(states, spec.drive.axle_offset)


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
    return variant_of(spec).entry("initial_state")(spec)


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
    return variant_of(spec).entry("positions")(spec, np.atleast_2d(states))
