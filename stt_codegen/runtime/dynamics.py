"""The plants' dynamics, written once, as CasADi SX Functions.

``x_dot = f(x) + g(x) u + w`` of system (1) for the plants the toolkit knows by name: the
omnidirectional robot of eq. (14) (``g(x) = R(x3)``, ``f = 0``) and the single integrator
(``g = I``, ``f = 0``). Everything that uses a plant derives from these Functions:

* the simulation (:mod:`.plants`) evaluates :func:`plant_rhs`, printed to Python by the
  emitter;
* ``stt-codegen verify`` (Assumption 2) prints :func:`input_matrix` with the SymPy printer
  and takes the symmetric part of ``g(x)``;
* the embedded closed loop (``templates/embedded_closed_loop.c.j2``) contains
  :func:`plant_rhs` printed by the C printer.

The spec's ``linear`` plant (``x_dot = a x + c + g u + w``, matrices from the spec) is
:func:`linear_rhs`, used the same way by the simulation and the embedded closed loop
(its Assumption 2 check is :func:`stt_codegen.verification.sampled.linear_plant_checks`, on the
spec's ``g``). :func:`plant_function` picks the one of a spec's ``[plant]``.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import casadi as ca
import numpy as np

from ..spec.plants import (NAMED_MODELS, MissingPlantBehaviour, dimension_mismatch, plant_entry,
                           model_behaviour)

__all__ = ["INPUT_MATRICES", "NAMED_MODELS", "input_matrix", "linear_rhs", "plant_function", "plant_rhs"]


def _rotation(x):
    c, s = ca.cos(x[2]), ca.sin(x[2])
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


#: ``g(x)`` of each named first-order model (the ``linear`` model's comes from the spec).
INPUT_MATRICES = {
    "omnidirectional": _rotation,
    "single-integrator": lambda x: ca.SX.eye(x.numel()),
}


def _g(model: str, x):
    try:
        return model_behaviour(INPUT_MATRICES, model, "input matrix g(x)")(x)
    except MissingPlantBehaviour as err:
        raise ValueError(f"unknown plant model {model!r}; known: "
                         f"{', '.join(NAMED_MODELS)}") from err


def _dimension(model: str, n: int) -> None:
    if dimension_mismatch(model, n):
        raise ValueError(dimension_mismatch(model, n))


@lru_cache(maxsize=None)
def input_matrix(model: str, n: int) -> ca.Function:
    """``plant_input_matrix(x) -> g`` of system (1): ``g(x)``, shape (n, n).

    Parameters
    ----------
    model : str
        ``"omnidirectional"`` (eq. (14): ``g(x) = R(x3)``, the rotation by the heading
        ``x3``; ``n = 3``) or ``"single-integrator"`` (``g = I_n``).
    n : int
        State dimension.

    Returns
    -------
    casadi.Function
        ``plant_input_matrix(x) -> g``, ``x`` (n,), ``g`` (n, n).

    Raises
    ------
    ValueError
        Unknown model, or a dimension the model does not have.
    """
    _dimension(model, n)
    x = ca.SX.sym("x", n)
    return ca.Function("plant_input_matrix", [x], [_g(model, x)], ["x"], ["g"])


@lru_cache(maxsize=None)
def plant_rhs(model: str, n: int) -> ca.Function:
    """``plant_rhs(x, u) -> x_dot = g(x) u`` (system (1) without the disturbance ``w``).

    Parameters
    ----------
    model, n
        As :func:`input_matrix`.

    Returns
    -------
    casadi.Function
        ``plant_rhs(x, u) -> x_dot``, each (n,); ``x_dot`` in state units per second.

    Raises
    ------
    ValueError
        As :func:`input_matrix`.
    """
    _dimension(model, n)
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", n)
    return ca.Function("plant_rhs", [x, u], [ca.mtimes(_g(model, x), u)], ["x", "u"],
                       ["x_dot"])


def linear_rhs(a: Sequence[Sequence[float]], g: Sequence[Sequence[float]],
               c: Sequence[float]) -> ca.Function:
    """``plant_rhs(x, u) -> x_dot = a x + c + g u`` (the spec's ``linear`` plant without
    ``w``), the matrices as constants.

    Parameters
    ----------
    a, g : array_like, shape (n, n)
        Drift and input matrices (1/s and state units per input unit per second).
    c : array_like, shape (n,)
        Constant drift, state units per second.

    Returns
    -------
    casadi.Function
        ``plant_rhs(x, u) -> x_dot``, each (n,); ``x_dot`` in state units per second.
    """
    a, g, c = (np.array(m, dtype=float) for m in (a, g, c))
    n = c.size
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", n)
    rows = []
    for i in range(n):
        # a_i x + c_i + g_i u, summed left to right as numpy's a @ x + c + g @ u for small n
        ax = sum((a[i, j] * x[j] for j in range(1, n)), a[i, 0] * x[0])
        gu = sum((g[i, j] * u[j] for j in range(1, n)), g[i, 0] * u[0])
        rows.append(ax + c[i] + gu)
    return ca.Function("plant_rhs", [x, u], [ca.vertcat(*rows)], ["x", "u"], ["x_dot"])


def plant_function(model: str, n: int, linear=None) -> ca.Function:
    """``plant_rhs(x, u) -> g(x) u`` (``+ a x + c`` for ``linear``) of a spec's ``[plant]``.

    Parameters
    ----------
    model : str
        ``plant.model``: a :data:`NAMED_MODELS` entry or ``"linear"``.
    n : int
        State dimension.
    linear : LinearPlant, optional
        The ``linear`` model's matrices (default ``a = 0``, ``g = I``, ``c = 0``).

    Returns
    -------
    casadi.Function
        ``plant_rhs(x, u) -> x_dot``, each (n,); ``x_dot`` in state units per second.

    Raises
    ------
    ValueError
        As :func:`input_matrix`; a model without equations (``mujoco``).
    """
    if model in INPUT_MATRICES:   # a named model: g(x) is fixed, not from the spec
        return plant_rhs(model, n)
    if plant_entry(model).plant_states is not None:
        raise ValueError(f"the {model} plant's state is not the tube's: its dynamics are "
                         "the variant's own (runtime/differential_drive.py)")
    if plant_entry(model).declared_bounds:
        raise ValueError(f"the {model} plant has no equations here (it runs in its own "
                         "simulator)")
    if linear is None:
        return linear_rhs(np.zeros((n, n)), np.eye(n), np.zeros(n))
    return linear_rhs(linear.a, linear.g, linear.c)
