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

The spec's ``linear`` plant (``x_dot = A x + c + G u + w``) has its matrices in the spec;
it is :func:`stt_codegen.runtime.plants.linear_plant`.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

__all__ = ["NAMED_MODELS", "input_matrix", "plant_rhs"]

#: Plants with a fixed model (``plant.model`` values other than ``"linear"``).
NAMED_MODELS = ("omnidirectional", "single-integrator")


def _g(model: str, x):
    if model == "omnidirectional":
        c, s = ca.cos(x[2]), ca.sin(x[2])
        return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
    if model == "single-integrator":
        return ca.SX.eye(x.numel())
    raise ValueError(f"unknown plant model {model!r}; known: {', '.join(NAMED_MODELS)}")


def _dimension(model: str, n: int) -> None:
    if model == "omnidirectional" and n != 3:
        raise ValueError("the omnidirectional robot has 3 states")


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

    Raises
    ------
    ValueError
        As :func:`input_matrix`.
    """
    _dimension(model, n)
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", n)
    return ca.Function("plant_rhs", [x, u], [ca.mtimes(_g(model, x), u)], ["x", "u"],
                       ["x_dot"])
