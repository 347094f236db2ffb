"""Controller backends: one object per way of computing the deployed controller step.

Every backend computes the same step, ``(x, t, dt, alpha) -> (u, alpha_next, status)``,
from a different implementation: the numpy reference, CasADi's own evaluation, or the
generated code. New backends register a factory with :func:`register_backend`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from ..tube import reference
from ..errors import SpecError
from ..tube.parameters import (STATUS_INPUT_CLAMPED, STATUS_INVALID_INPUT, STATUS_OK,
                               STATUS_OUTSIDE_TUBE, TubeDesign)

__all__ = ["STATUS_INPUT_CLAMPED", "STATUS_INVALID_INPUT", "STATUS_OK", "STATUS_OUTSIDE_TUBE",
           "Controller",
           "backend_names", "make_controller", "register_backend"]


class Controller(Protocol):
    """A deployed controller step."""

    name: str

    def step(self, x: np.ndarray, t: float, dt: float,
             alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """Return ``u`` (n,), ``alpha_next`` (2n,) and a status code."""


class ReferenceController:
    """The numpy reference (:func:`stt_codegen.tube.reference.controller_status`)."""

    name = "reference"

    def __init__(self, design: TubeDesign) -> None:
        self.design = design

    def step(self, x, t, dt, alpha):
        u, alpha_next, status = reference.controller_status(self.design, x, t, dt, alpha)
        return u[0], alpha_next[0], int(status[0])


class CasadiController:
    """CasADi's own evaluation of the model's ``controller_step`` function."""

    name = "casadi"

    def __init__(self, design: TubeDesign) -> None:
        from ..tube.model import build_model
        self.function = build_model(design)["controller_step"]

    def step(self, x, t, dt, alpha):
        # a design with an actuator bound has a fourth output, within_bound
        u, alpha_next, inside, *within = self.function(x, t, dt, alpha)
        status = (STATUS_OUTSIDE_TUBE if not float(inside) else
                  STATUS_INPUT_CLAMPED if within and not float(within[0]) else STATUS_OK)
        return np.array(u).ravel(), np.array(alpha_next).ravel(), status


def _generated_c(design: TubeDesign) -> Controller:
    from .compiled import CController
    return CController(design)


def _generated_python(design: TubeDesign) -> Controller:
    from .compiled import GeneratedPythonController
    return GeneratedPythonController(design)


_FACTORIES: dict[str, Callable[[TubeDesign], Controller]] = {
    "reference": ReferenceController,
    "casadi": CasadiController,
    "c": _generated_c,
    "python": _generated_python,
}


def register_backend(name: str, factory: Callable[[TubeDesign], Controller]) -> None:
    """Make ``factory(design)`` available as backend ``name``.

    Parameters
    ----------
    name : str
        The backend's name (``--backend``); an existing name is replaced.
    factory : callable
        ``factory(design)`` builds the :class:`Controller` for a
        :class:`~stt_codegen.tube.parameters.TubeDesign`.
    """
    _FACTORIES[name] = factory


def backend_names() -> list[str]:
    """The registered backend names, in registration order.

    Returns
    -------
    list of str
        ``"reference"``, ``"casadi"``, ``"c"``, ``"python"``, then any registered later.
    """
    return list(_FACTORIES)


def make_controller(name: str, design: TubeDesign) -> Controller:
    """The controller of backend ``name`` for a design.

    Parameters
    ----------
    name : str
        A name of :func:`backend_names`.
    design : TubeDesign
        The tube and gain the controller runs.

    Returns
    -------
    Controller
        ``step(x, t, dt, alpha) -> (u, alpha_next, status)``: ``x`` (n,) state units, ``t``
        and ``dt`` in s, ``alpha`` (2n,); ``u`` (n,) input units by law (13), ``alpha_next``
        (2n,) by the implicit step of the adaptive law (11), ``status`` a ``STATUS_*`` code.

    Raises
    ------
    SpecError
        Unknown backend (field ``backend``).
    """
    if name not in _FACTORIES:
        raise SpecError("backend", f"unknown backend {name!r} "
                                     f"(known: {', '.join(_FACTORIES)})")
    return _FACTORIES[name](design)
