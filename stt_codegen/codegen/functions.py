"""The CasADi Functions that are deployed, in a fixed order, from the model's.

The generated code exposes four functions (C: ``<prefix>_tube``, ``_control``,
``_alpha_step``, ``_step``; Python: ``tube``, ``control``, ``alpha_step``, ``step``). Their
numeric bodies are these CasADi SX Functions:

=================  ========================  ======================================
name               inputs                    outputs
=================  ========================  ======================================
``tube``           t, alpha (2n)             gamma_L, gamma_U, gamma_L_dot, gamma_U_dot
``control``        x (n), t, alpha (2n)      u (n), inside (1)
``alpha_step``     t, dt, alpha (2n)         alpha_next (2n)
``controller_step`` x (n), t, dt, alpha (2n)  u (n), alpha_next (2n), inside (1)
=================  ========================  ======================================

``tube``, ``alpha_step`` and ``controller_step`` are the model's Functions unchanged.
``control`` is the model's ``controller_step`` restricted to its ``u`` and ``inside``
outputs (its SX graph, so the same operations as the step: ``e`` clamped to
``[-E_MAX, E_MAX]``, ``gamma_d`` floored, finite outside the tube), not the model's
unclamped ``control``, which is NaN outside the tube.
"""

from __future__ import annotations

import casadi as ca

from ..tube.model import TubeModel
from .errors import CodegenError

#: Deployed Function names, in generation order.
DEPLOYED = ("tube", "control", "alpha_step", "controller_step")


def clamped_control(model: TubeModel) -> ca.Function:
    """``control(x, t, alpha) -> (u, inside)``: the ``u`` and ``inside`` of ``controller_step``.

    Raises
    ------
    CodegenError
        If ``u`` or ``inside`` of the step depended on ``dt`` (they must not).
    """
    step = model["controller_step"]
    n = model.design.dimension
    x = ca.SX.sym("x", n)
    t = ca.SX.sym("t")
    dt = ca.SX.sym("dt")
    alpha = ca.SX.sym("alpha", 2 * n)
    u, _, inside = step(x, t, dt, alpha)
    if ca.depends_on(ca.vertcat(u, inside), dt):
        raise CodegenError("controller_step's u depends on dt")
    return ca.Function("control", [x, t, alpha], [u, inside], ["x", "t", "alpha"],
                       ["u", "inside"])


def deployed_functions(model: TubeModel) -> list[ca.Function]:
    """The deployed SX Functions, in the order of :data:`DEPLOYED`."""
    return [model["tube"], clamped_control(model), model["alpha_step"],
            model["controller_step"]]
