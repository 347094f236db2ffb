"""Second-order plants in a spec: ``[plant] model`` a second-order model (docs/second-order.md).

A spec whose ``[plant] model`` is one of :data:`~.plants.SECOND_ORDER_MODELS` describes a
plant ``x1_dot = x2``, ``x2_dot = f + g u + w`` whose positions ``x1`` are the spec's
state space (the tube constrains them as for any spec). Its keys live where the
first-order ones do:

* ``[plant] model`` and ``parameters`` (the simulated model, :mod:`.plants`, whose
  dynamics are :mod:`stt_codegen.runtime.second_order_plants`), ``disturbance_amplitude``;
* ``[initial] velocity``: ``x2(0)``, default 0;
* ``[state_space] velocity_bound``: the bound on ``|x2_i|`` the run must keep, optional;
* ``[assumptions] input_gain`` and ``drift_bound``: the declared bounds of the second
  stage the cascade's default gains come from.

:func:`parse_second_order` checks them and gathers them in :class:`SecondOrder`, the
object the cascade code reads (``Spec.second_order``). Plain Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from ..errors import SpecError
from .plants import SECOND_ORDER_MODELS, SECOND_ORDER_PLANTS as MODELS, SecondOrderModel

__all__ = ["MODELS", "SECOND_ORDER_MODELS", "SECOND_ORDER_ONLY", "SecondOrder",
           "SecondOrderModel", "parse_second_order"]

#: The spec keys only a second-order model takes.
SECOND_ORDER_ONLY = ("plant.parameters", "initial.velocity", "state_space.velocity_bound")


@dataclass(frozen=True)
class SecondOrder:
    """The second-order plant of a spec, gathered from its tables.

    Attributes
    ----------
    model : str
        ``plant.model``, a :data:`SECOND_ORDER_MODELS` entry: the plant ``simulate`` runs.
    parameters : tuple of float
        ``plant.parameters``, the simulated plant's (:attr:`SecondOrderModel.parameters`).
    initial_velocity : tuple of float
        ``initial.velocity``: ``x2(0)``, velocity units (state units per second), one per
        position.
    velocity_bound : tuple of float or None
        ``state_space.velocity_bound``: ``|x2_i|`` must stay below it (the run is judged
        on it); ``None``: no bound.
    input_gain : (float, float)
        ``assumptions.input_gain``: declared ``[g_min, g_max]`` of the symmetric part of
        ``g``, ``0 < g_min <= g_max``.
    drift_bound : float
        ``assumptions.drift_bound``: declared bound on every ``|f_i|`` over the states of
        the task, velocity units per second (the disturbance is ``[plant]
        disturbance_amplitude``).
    """

    model: str
    parameters: tuple[float, ...]
    initial_velocity: tuple[float, ...]
    velocity_bound: tuple[float, ...] | None
    input_gain: tuple[float, float]
    drift_bound: float


def _numbers(values, field: str, count: int | None = None) -> tuple[float, ...]:
    out = tuple(float(v) for v in values)
    if count is not None and len(out) != count:
        raise SpecError(field, f"needs {count} entries, got {len(out)}")
    if not all(math.isfinite(v) for v in out):
        raise SpecError(field, "every entry must be a finite number")
    return out


def parse_second_order(model: str, n: int, parameters: Sequence[float] | None = None,
                       velocity: Sequence[float] | None = None,
                       velocity_bound: Sequence[float] | None = None,
                       input_gain: Sequence[float] | None = None,
                       drift_bound: float = 0.0) -> SecondOrder:
    """The second-order plant of a spec with ``n`` positions, checked.

    Parameters
    ----------
    model : str
        ``plant.model``, a :data:`SECOND_ORDER_MODELS` entry.
    n : int
        Number of positions (the state space's dimension).
    parameters : sequence of float, optional
        ``plant.parameters`` (default the model's nominal ones).
    velocity : sequence of float, optional
        ``initial.velocity`` (default 0).
    velocity_bound : sequence of float, optional
        ``state_space.velocity_bound`` (default none).
    input_gain : sequence of float, optional
        ``assumptions.input_gain`` (default ``[1, 1]``).
    drift_bound : float
        ``assumptions.drift_bound``.

    Returns
    -------
    SecondOrder

    Raises
    ------
    SpecError
        ``plant.model`` of another dimension, or ``plant.parameters``,
        ``initial.velocity``, ``state_space.velocity_bound``, ``assumptions.input_gain``
        of the wrong length or out of range; the field is named.
    """
    info = MODELS[model]
    if info.dimension is not None and info.dimension != n:
        raise SpecError("plant.model", f"the {info.name} model has {info.dimension} "
                                       f"positions, the state space has {n}")
    params = (info.nominal if parameters is None else
              _numbers(parameters, "plant.parameters", len(info.parameters)))
    if not all(v >= 0 for v in params) or not all(
            v > 0 for name, v in zip(info.parameters, params) if name != "gravity"
            and name != "drag"):
        raise SpecError("plant.parameters", f"({', '.join(info.parameters)}) must be "
                                            "positive (drag and gravity >= 0)")
    x2 = (0.0,) * n if velocity is None else _numbers(velocity, "initial.velocity", n)
    bound = (None if velocity_bound is None else
             _numbers(velocity_bound, "state_space.velocity_bound", n))
    if bound is not None and not all(abs(v) < b for v, b in zip(x2, bound)):
        raise SpecError("initial.velocity", "is not inside state_space.velocity_bound")
    gain = (1.0, 1.0) if input_gain is None else _numbers(input_gain,
                                                           "assumptions.input_gain", 2)
    if not 0 < gain[0] <= gain[1]:
        raise SpecError("assumptions.input_gain", "needs 0 < g_min <= g_max")
    return SecondOrder(model, params, x2, bound, (gain[0], gain[1]), float(drift_bound))
