"""Second-order plants in a spec: the ``[second_order]`` table (docs/second-order.md).

A spec with ``[second_order]`` describes a plant ``x1_dot = x2``, ``x2_dot = f + g u + w``
whose positions ``x1`` are the spec's state space (the tube constrains them as for any
spec). The table names the simulated model (:data:`MODELS`, whose dynamics are
:mod:`stt_codegen.runtime.second_order_plants`), its parameters, the initial velocity, an
optional velocity bound, and the declared bounds the cascade's default gains come from.
Plain Python: the registry of the models' facts, and the parser of the table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import SpecError

if TYPE_CHECKING:
    from .schema import SecondOrderTable

__all__ = ["MODELS", "SECOND_ORDER_MODELS", "SecondOrder", "SecondOrderModel",
           "parse_second_order"]


@dataclass(frozen=True)
class SecondOrderModel:
    """A named second-order model: its dimension (``None``: any), a summary, parameter
    names and nominal parameter values (SI units)."""

    name: str
    summary: str
    dimension: int | None
    parameters: tuple[str, ...]
    nominal: tuple[float, ...]


#: Every second-order model, by name.
MODELS: dict[str, SecondOrderModel] = {m.name: m for m in (
    SecondOrderModel("double-integrator", "x2_dot = u / mass + w, any n", None, ("mass",),
                     (1.0,)),
    SecondOrderModel("quadrotor", "x2_dot = u / mass - (drag / mass) x2 - gravity e3 + w, "
                     "thrust vector u, n = 3", 3, ("mass", "drag", "gravity"),
                     (1.0, 0.3, 9.81)),
    SecondOrderModel("two-link-arm", "joint space, M(q) q_ddot + C(q, q_dot) q_dot + G(q) = "
                     "u + w, n = 2", 2,
                     ("mass1", "mass2", "length1", "length2", "inertia1", "inertia2",
                      "gravity"),
                     (1.0, 1.0, 1.0, 1.0, 1.0 / 12.0, 1.0 / 12.0, 0.0)),
)}
#: The model names, in order.
SECOND_ORDER_MODELS: tuple[str, ...] = tuple(MODELS)


@dataclass(frozen=True)
class SecondOrder:
    """The parsed ``[second_order]`` table.

    Attributes
    ----------
    model : str
        A :data:`SECOND_ORDER_MODELS` entry: the plant ``simulate`` runs.
    parameters : tuple of float
        The simulated plant's parameters (:attr:`SecondOrderModel.parameters`).
    initial_velocity : tuple of float
        ``x2(0)``, velocity units (state units per second), one per position.
    velocity_bound : tuple of float or None
        ``|x2_i|`` must stay below it (the run is judged on it); ``None``: no bound.
    input_gain : (float, float)
        Declared ``[g_min, g_max]`` of the symmetric part of ``g``, ``0 < g_min <= g_max``.
    drift_bound : float
        Declared bound on every ``|f_i|`` over the states of the task, velocity units per
        second (the disturbance is ``[plant] disturbance_amplitude``).
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


def parse_second_order(table: "SecondOrderTable | None", n: int) -> SecondOrder | None:
    """The ``[second_order]`` table of a spec with ``n`` positions, checked.

    Parameters
    ----------
    table : SecondOrderTable or None
        The document's table (``None``: a first-order spec).
    n : int

    Returns
    -------
    SecondOrder or None

    Raises
    ------
    SpecError
        ``second_order.model`` of another dimension, or ``parameters``,
        ``initial_velocity``, ``velocity_bound``, ``input_gain`` of the wrong length or out
        of range; the field is named.
    """
    if table is None:
        return None
    info = MODELS[table.model]
    if info.dimension is not None and info.dimension != n:
        raise SpecError("second_order.model", f"the {info.name} model has {info.dimension} "
                                              f"positions, the state space has {n}")
    params = (info.nominal if table.parameters is None else
              _numbers(table.parameters, "second_order.parameters", len(info.parameters)))
    if not all(v >= 0 for v in params) or not all(
            v > 0 for name, v in zip(info.parameters, params) if name != "gravity"
            and name != "drag"):
        raise SpecError("second_order.parameters", f"({', '.join(info.parameters)}) must be "
                                                   "positive (drag and gravity >= 0)")
    x2 = ((0.0,) * n if table.initial_velocity is None else
          _numbers(table.initial_velocity, "second_order.initial_velocity", n))
    bound = (None if table.velocity_bound is None else
             _numbers(table.velocity_bound, "second_order.velocity_bound", n))
    if bound is not None and not all(abs(v) < b for v, b in zip(x2, bound)):
        raise SpecError("second_order.initial_velocity", "is not inside velocity_bound")
    gain = _numbers(table.input_gain, "second_order.input_gain", 2)
    if not 0 < gain[0] <= gain[1]:
        raise SpecError("second_order.input_gain", "needs 0 < g_min <= g_max")
    return SecondOrder(table.model, params, x2, bound, (gain[0], gain[1]),
                       float(table.drift_bound))
