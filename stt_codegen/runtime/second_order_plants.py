"""Second-order plants for simulation, written once as CasADi SX Functions.

``x1_dot = x2``, ``x2_dot = f(x1, x2) + g(x1, x2) u + w`` (docs/second-order.md). Each
model is one Function ``second_order_rhs(x1, x2, u, w, params) -> (x1_dot, x2_dot)`` whose
physical numbers are the input ``params`` (names and nominal values:
:data:`stt_codegen.spec.plants.SECOND_ORDER_PLANTS`) (so one Function serves a whole
family of plants, e.g. the random plants of a study), printed to Python by the emitter for
the simulation. The controller never sees them.

=====================  =====  ================================================  =============
model                  n      x2_dot                                            params
=====================  =====  ================================================  =============
``double-integrator``  any    ``u / m + w``                                     m (kg)
``quadrotor``          3      ``u / m - (c / m) x2 - g0 e3 + w`` (thrust        m, c, g0
                              vector ``u`` in N, linear drag ``c``, gravity)
``two-link-arm``       2      ``M(q)^-1 (tau - C(q, q_dot) q_dot - G(q)) + w``  m1, m2, l1,
                              (joint angles ``q = x1``, Euler-Lagrange,          l2, I1, I2,
                              links' centres of mass at half length)            g0
=====================  =====  ================================================  =============

In every model ``g(x1, x2)`` is symmetric positive definite (``I / m``, ``M(q)^-1``), which
is Assumption 2 for the second stage.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from ..spec.plants import model_behaviour
from ..spec.second_order import MODELS, SECOND_ORDER_MODELS, SecondOrderModel

__all__ = ["ACCELERATIONS", "MODELS", "SECOND_ORDER_MODELS", "input_matrix", "model_info",
           "second_order_rhs"]


def model_info(model: str, n: int) -> SecondOrderModel:
    """The :class:`SecondOrderModel` of a name, checked against the dimension.

    Parameters
    ----------
    model : str
        A name of :data:`SECOND_ORDER_MODELS`.
    n : int
        Number of positions (= velocities = inputs).

    Returns
    -------
    SecondOrderModel
        The model's description (dimension, parameters and their nominal values).

    Raises
    ------
    ValueError
        Unknown model, or a dimension it does not have.
    """
    if model not in MODELS:
        raise ValueError(f"unknown second-order model {model!r}; known: "
                         f"{', '.join(SECOND_ORDER_MODELS)}")
    info = MODELS[model]
    if info.dimension is not None and info.dimension != n:
        raise ValueError(f"model {model!r} has {info.dimension} positions, not {n}")
    return info


def _arm(q, dq, tau, p):
    m1, m2, l1, l2, i1, i2, g0 = (p[k] for k in range(7))
    c1, c2 = l1 / 2.0, l2 / 2.0
    cos2, sin2 = ca.cos(q[1]), ca.sin(q[1])
    m11 = i1 + i2 + m1 * c1 * c1 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cos2)
    m12 = i2 + m2 * (c2 * c2 + l1 * c2 * cos2)
    m22 = i2 + m2 * c2 * c2
    h = m2 * l1 * c2 * sin2
    coriolis = ca.vertcat(-h * (2.0 * dq[0] * dq[1] + dq[1] * dq[1]), h * dq[0] * dq[0])
    gravity = ca.vertcat((m1 * c1 + m2 * l1) * g0 * ca.cos(q[0])
                         + m2 * c2 * g0 * ca.cos(q[0] + q[1]),
                         m2 * c2 * g0 * ca.cos(q[0] + q[1]))
    rhs = tau - coriolis - gravity
    det = m11 * m22 - m12 * m12
    return ca.vertcat((m22 * rhs[0] - m12 * rhs[1]) / det, (m11 * rhs[1] - m12 * rhs[0]) / det)


#: ``f + g u`` (the acceleration ``x2_dot`` without ``w``) of each second-order model,
#: ``(x1, x2, u, params) -> x2_dot``, parameters in :data:`SECOND_ORDER_PLANTS`'s order.
ACCELERATIONS = {
    "double-integrator": lambda x1, x2, u, p: u / p[0],
    "quadrotor": lambda x1, x2, u, p: u / p[0] - (p[1] / p[0]) * x2
    - ca.vertcat(0.0, 0.0, p[2]),
    "two-link-arm": _arm,
}


@lru_cache(maxsize=None)
def second_order_rhs(model: str, n: int) -> ca.Function:
    """``second_order_rhs(x1, x2, u, w, params) -> (x1_dot, x2_dot)`` of a named model.

    Parameters
    ----------
    model : str
        One of :data:`SECOND_ORDER_MODELS` (the table of the module docstring).
    n : int
        Positions (= velocities = inputs).

    Returns
    -------
    casadi.Function
        Inputs ``x1``, ``x2``, ``u``, ``w`` (n each; ``w`` in velocity units per second)
        and ``params`` (the model's parameters, :data:`MODELS`).

    Raises
    ------
    ValueError
        As :func:`model_info`.
    """
    info = model_info(model, n)
    x1, x2, u, w = (ca.SX.sym(name, n) for name in ("x1", "x2", "u", "w"))
    p = ca.SX.sym("params", len(info.parameters))
    acc = model_behaviour(ACCELERATIONS, model, "acceleration f + g u")(x1, x2, u, p)
    return ca.Function("second_order_rhs", [x1, x2, u, w, p], [x2, acc + w],
                       ["x1", "x2", "u", "w", "params"], ["x1_dot", "x2_dot"])


@lru_cache(maxsize=None)
def input_matrix(model: str, n: int) -> ca.Function:
    """``second_order_input_matrix(x1, x2, params) -> g``: ``d x2_dot / d u``, (n, n),
    exact (algorithmic differentiation of :func:`second_order_rhs`), for Assumption 2.

    Parameters
    ----------
    model : str
        A name of :data:`SECOND_ORDER_MODELS`.
    n : int
        Number of positions (= velocities = inputs).

    Returns
    -------
    casadi.Function
        ``second_order_input_matrix(x1, x2, params) -> g``: ``x1``, ``x2`` (n,), ``params``
        the model's parameters, ``g`` (n, n).

    Raises
    ------
    ValueError
        Unknown model, or a dimension it does not have (:func:`model_info`).
    """
    rhs = second_order_rhs(model, n)
    x1, x2, u, w = (ca.SX.sym(name, n) for name in ("x1", "x2", "u", "w"))
    p = ca.SX.sym("params", rhs.numel_in(4))
    g = ca.jacobian(rhs(x1, x2, u, w, p)[1], u)
    return ca.Function("second_order_input_matrix", [x1, x2, p], [ca.densify(g)],
                       ["x1", "x2", "params"], ["g"])
