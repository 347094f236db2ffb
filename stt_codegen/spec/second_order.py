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
  stage the cascade's default gains come from. Left out, they are the named model's own,
  from its ``parameters`` (:func:`model_bounds`: ``1 / mass``; gravity, and drag at the
  velocity bound), as the first-order models' are.

:func:`parse_second_order` checks them and gathers them in :class:`SecondOrder`, the
object the cascade code reads (``Spec.second_order``). Plain Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from ..errors import SpecError
from .plants import SECOND_ORDER_MODELS, SECOND_ORDER_PLANTS as MODELS, SecondOrderModel

__all__ = ["MODELS", "SECOND_ORDER_MODELS", "SECOND_ORDER_ONLY", "ModelBounds", "SecondOrder",
           "SecondOrderModel", "model_bounds", "parse_second_order"]

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
    drift_bounds : tuple of float
        ``assumptions.drift_bound``: the declared bound on ``|f_i|`` of each axis over the
        states of the task, velocity units per second, one per position (one number in
        the spec is the bound of every axis; without one, the model's own per axis, from
        its ``parameters``); the disturbance is ``[plant] disturbance_amplitude``.
    """

    model: str
    parameters: tuple[float, ...]
    initial_velocity: tuple[float, ...]
    velocity_bound: tuple[float, ...] | None
    input_gain: tuple[float, float]
    drift_bounds: tuple[float, ...]

    @property
    def drift_bound(self) -> float:
        """The largest of :attr:`drift_bounds`: a bound on every ``|f_i|``, velocity units
        per second."""
        return max(self.drift_bounds)


@dataclass(frozen=True)
class ModelBounds:
    """A named second-order model's own bounds over a spec's states, from its parameters.

    Attributes
    ----------
    input_gain : (float, float)
        ``(g_min, g_max)``: the extreme eigenvalues of ``g`` (symmetric) over the positions,
        ``1 / mass`` for the mass models; the default ``assumptions.input_gain``.
    drift_bounds : tuple of float or None
        ``sup |f_i|`` of each axis over the positions and ``|x2_i| <= velocity_bound_i``,
        velocity units per second (gravity, drag, Coriolis), one per position; the default
        ``assumptions.drift_bound``. ``None`` when it grows with the velocity and no
        ``velocity_bound`` is given.
    words : str
        How they follow from the parameters, for messages.
    """

    input_gain: tuple[float, float]
    drift_bounds: tuple[float, ...] | None
    words: str

    @property
    def drift_bound(self) -> float | None:
        """The largest of :attr:`drift_bounds` (``None`` where they are ``None``)."""
        return None if self.drift_bounds is None else max(self.drift_bounds)


def _mass_bounds(p: dict, offset: Sequence[float], slope: float,
                 velocity_bound: Sequence[float] | None) -> ModelBounds:
    """``g = I / m``, ``|f_i| <= slope |x2_i| + offset_i``."""
    g = 1.0 / p["mass"]
    axes = (tuple(offset) if slope == 0.0 else None if velocity_bound is None else
            tuple(o + slope * v for o, v in zip(offset, velocity_bound)))
    return ModelBounds((g, g), axes, f"g = I / mass = {g:.6g} I, |f_i| <= "
                       f"{slope:.6g} |x2_i| + [{', '.join(f'{o:.6g}' for o in offset)}]_i")


def _double_integrator(p: dict, n: int, velocity_bound, lower, upper) -> ModelBounds:
    return _mass_bounds(p, (0.0,) * n, 0.0, velocity_bound)


def _quadrotor(p: dict, n: int, velocity_bound, lower, upper) -> ModelBounds:
    return _mass_bounds(p, (0.0, 0.0, p["gravity"]), p["drag"] / p["mass"], velocity_bound)


def _cosine_range(lower: float, upper: float) -> tuple[float, float]:
    """``[min cos q, max cos q]`` over ``q`` in ``[lower, upper]`` (radians)."""
    ends = (math.cos(lower), math.cos(upper))
    def contains(angle: float) -> bool:        # angle + 2 pi k in [lower, upper] for some k
        return math.ceil((lower - angle) / (2.0 * math.pi)) <= math.floor(
            (upper - angle) / (2.0 * math.pi))
    return (-1.0 if contains(math.pi) else min(ends), 1.0 if contains(0.0) else max(ends))


def _arm(p: dict, n: int, velocity_bound, lower, upper) -> ModelBounds:
    """The two-link arm: ``M(q)``'s entries are affine in ``cos q2``, so its largest
    eigenvalue is convex and its least concave in ``cos q2``: both extremes are at the ends
    of the range of ``cos q2`` over the state space; ``g = M^-1``. ``|f_i| <= |M^-1 (C
    q_dot + G)| <= g_max (|C q_dot| + |G|)`` (Euclidean norms) with ``|h| <= m2 l1 c2``."""
    m1, m2, l1, l2, i1, i2, g0 = (p[k] for k in ("mass1", "mass2", "length1", "length2",
                                                  "inertia1", "inertia2", "gravity"))
    c1, c2 = l1 / 2.0, l2 / 2.0
    eigen = []
    for cos2 in _cosine_range(lower[1], upper[1]):
        m11 = i1 + i2 + m1 * c1 * c1 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cos2)
        m12 = i2 + m2 * (c2 * c2 + l1 * c2 * cos2)
        m22 = i2 + m2 * c2 * c2
        mean, half = 0.5 * (m11 + m22), math.hypot(0.5 * (m11 - m22), m12)
        eigen += [mean - half, mean + half]
    # rounded outwards: bounds of the class, not estimates (relative 1e-12)
    g_min, g_max = (1.0 - 1e-12) / max(eigen), (1.0 + 1e-12) / min(eigen)
    gravity = math.hypot((m1 * c1 + m2 * l1 + m2 * c2) * g0, m2 * c2 * g0)
    drift = None
    if velocity_bound is not None:
        v1, v2 = velocity_bound
        coriolis = m2 * l1 * c2 * math.hypot(2.0 * v1 * v2 + v2 * v2, v1 * v1)
        drift = ((1.0 + 1e-12) * g_max * (coriolis + gravity),) * n
    return ModelBounds((g_min, g_max), drift, f"eigenvalues of M(q)^-1 in [{g_min:.6g}, "
                       f"{g_max:.6g}] over the joint ranges, |f| <= g_max (|C q_dot| + |G|)")


#: Each named model's own bounds: ``(parameters by name, n, velocity_bound, lower,
#: upper) -> ModelBounds``, the positions' box ``[lower, upper]``.
_BOUNDS = {"double-integrator": _double_integrator, "quadrotor": _quadrotor,
           "two-link-arm": _arm}


def model_bounds(model: str, parameters: Sequence[float], n: int,
                 velocity_bound: Sequence[float] | None, lower: Sequence[float],
                 upper: Sequence[float]) -> ModelBounds | None:
    """A named second-order model's own ``input_gain`` and ``drift_bound`` over a box of
    positions (the first-order models' are :func:`~.model_bounds.model_bounds`).

    Parameters
    ----------
    model : str
        A :data:`SECOND_ORDER_MODELS` name.
    parameters : sequence of float
        Its ``plant.parameters``, SI units.
    n : int
        Number of positions.
    velocity_bound : sequence of float or None
        ``state_space.velocity_bound`` (velocity units), ``n`` entries.
    lower, upper : sequence of float
        The state space's box of positions, ``n`` entries each.

    Returns
    -------
    ModelBounds or None
        ``None`` for a model without equations (``mujoco-force``).

    Examples
    --------
    A 1.2 kg quadrotor with drag 0.3 N s/m under gravity, at most 3 m/s:

    >>> from stt_codegen.spec.second_order import model_bounds
    >>> own = model_bounds("quadrotor", (1.2, 0.3, 9.81), 3, (3.0, 3.0, 3.0), (0,) * 3,
    ...                    (6,) * 3)
    >>> [round(v, 4) for v in own.input_gain], round(own.drift_bound, 4)
    ([0.8333, 0.8333], 10.56)
    """
    bounds = _BOUNDS.get(model)
    if bounds is None:
        return None
    named = dict(zip(MODELS[model].parameters, (float(v) for v in parameters)))
    return bounds(named, n, velocity_bound, lower, upper)


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
                       drift_bound: float | Sequence[float] | None = None,
                       positions: tuple[Sequence[float], Sequence[float]] | None = None
                       ) -> SecondOrder:
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
        ``assumptions.input_gain``; default the model's own (:func:`model_bounds`).
    drift_bound : float or sequence of float, optional
        ``assumptions.drift_bound``: one bound on every ``|f_i|`` or one per position
        (``n`` entries, velocity units/s); default the model's own.
    positions : (sequence of float, sequence of float), optional
        The state space's ``(lower, upper)``, over which the model's own bounds are taken;
        default ``[-pi, pi]`` in every position.

    Returns
    -------
    SecondOrder

    Raises
    ------
    SpecError
        ``plant.model`` of another dimension, or ``plant.parameters``,
        ``initial.velocity``, ``state_space.velocity_bound``, ``assumptions.input_gain``,
        ``assumptions.drift_bound`` of the wrong length or out of range;
        ``assumptions.drift_bound`` left out where the
        model's drift grows with the velocity and no ``velocity_bound`` is given; the
        field is named.
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
    lower, upper = positions if positions is not None else ((-math.pi,) * n, (math.pi,) * n)
    own = model_bounds(model, params, n, bound, lower, upper)
    if own is None and (input_gain is None or drift_bound is None):
        raise SpecError("assumptions.input_gain" if input_gain is None else
                        "assumptions.drift_bound", f"required for plant.model = {model!r}: "
                        "the toolkit has no equations of this plant")
    gain = own.input_gain if input_gain is None else _numbers(input_gain,
                                                              "assumptions.input_gain", 2)
    if not 0 < gain[0] <= gain[1]:
        raise SpecError("assumptions.input_gain", "needs 0 < g_min <= g_max")
    if drift_bound is None:
        drifts = own.drift_bounds
        if drifts is None:
            raise SpecError("assumptions.drift_bound", f"the {info.name} model's drift "
                            "grows with the velocity (drag, Coriolis): give "
                            "state_space.velocity_bound, from which its bound is derived, "
                            "or declare assumptions.drift_bound")
    elif isinstance(drift_bound, (int, float)):
        drifts = (float(drift_bound),) * n
    else:
        drifts = _numbers(drift_bound, "assumptions.drift_bound", n)
        if min(drifts) < 0:
            raise SpecError("assumptions.drift_bound", "every entry must be >= 0")
    return SecondOrder(model, params, x2, bound, (gain[0], gain[1]), drifts)
