"""Controller backends: one object per way of computing the deployed controller step.

Every backend computes the same step, ``(x, t, dt, alpha) -> (u, alpha_next, status)``,
from a different implementation: the numpy reference, CasADi's own evaluation, or the
generated code. The step is the same for both orders of plant: for a first-order plant
``x`` is its state (n) and the step is law (13); for a second-order plant ``x`` is
``[x1; x2]`` (2n) and the step is the cascade law (docs/second-order.md), whose factories
also take the second stage. New backends register a factory with :func:`register_backend`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from ..tube import reference
from ..errors import SpecError
from ..spec.variants import variant_named, variant_of_order, variant_of_stage
from ..tube.parameters import (STATUS_INPUT_CLAMPED, STATUS_INVALID_INPUT, STATUS_OK,
                               STATUS_OUTSIDE_TUBE, TubeDesign)
from ..tube.look_ahead import LookAhead
from ..tube.second_stage import SecondStage

__all__ = ["STATUS_INPUT_CLAMPED", "STATUS_INVALID_INPUT", "STATUS_OK", "STATUS_OUTSIDE_TUBE",
           "Controller",
           "backend_names", "default_backend", "cascade_backends", "cascade_controller", "first_order_backends",
           "first_order_controller", "look_ahead_backends", "look_ahead_controller",
           "make_controller", "register_backend"]


class Controller(Protocol):
    """A deployed controller step."""

    name: str

    def step(self, x: np.ndarray, t: float, dt: float,
             alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """Return ``u`` (n,), ``alpha_next`` (2n,) and a status code
        (:class:`~stt_codegen.tube.parameters.Status`); ``x`` is the plant's state (n, or
        2n for a second-order plant)."""


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
        law13 = variant_named("first-order")
        self.function = law13.entry("casadi_step")(design, None)
        self._decode = law13.entry("status")
        self.rate_hz = design.rate_hz

    def step(self, x, t, dt, alpha):
        # a design with an actuator bound has a fourth output, within_bound
        return self._decode(self.function(x, t, dt, alpha), dt, self.rate_hz)


def _generated_c(design: TubeDesign) -> Controller:
    from .compiled import CController
    return CController(design)


def _generated_python(design: TubeDesign) -> Controller:
    from .compiled import GeneratedPythonController
    return GeneratedPythonController(design)


def _cascade(backend: str) -> Callable[[TubeDesign, SecondStage], Controller]:
    def factory(design: TubeDesign, stage: SecondStage) -> Controller:
        from .cascade_controllers import CascadeController
        return CascadeController(backend, design, stage)
    return factory


def _look_ahead(backend: str) -> Callable[[TubeDesign, LookAhead], Controller]:
    def factory(design: TubeDesign, look_ahead: LookAhead) -> Controller:
        from .look_ahead_controllers import LookAheadController
        return LookAheadController(backend, design, look_ahead)
    return factory


#: The backends of law (13) on the plant's state, by name: ``factory(design)``.
_FIRST_ORDER: dict[str, Callable[..., Controller]] = {
    "reference": ReferenceController, "casadi": CasadiController,
    "c": _generated_c, "python": _generated_python}
#: The cascade's backends: ``factory(design, stage)`` with its :class:`SecondStage`.
_CASCADE = {name: _cascade(name) for name in ("reference", "casadi", "c", "python")}
#: The look-ahead law's backends: ``factory(design, look_ahead)`` with its
#: :class:`LookAhead`.
_LOOK_AHEAD = {name: _look_ahead(name) for name in ("reference", "casadi", "c", "python")}


def first_order_backends() -> dict[str, Callable[..., Controller]]:
    """The first-order variant's registry of backends (role ``backends`` of
    :mod:`~stt_codegen.spec.variants`): ``factory(design)`` by name.

    Returns
    -------
    dict of str to callable
        The registry itself (:func:`register_backend` adds to it).
    """
    return _FIRST_ORDER


def cascade_backends() -> dict[str, Callable[..., Controller]]:
    """The cascade's registry of backends (role ``backends``): ``factory(design, stage)``
    by name, ``stage`` the :class:`SecondStage`.

    Returns
    -------
    dict of str to callable
        The registry itself.
    """
    return _CASCADE


def look_ahead_backends() -> dict[str, Callable[..., Controller]]:
    """The look-ahead law's registry of backends (role ``backends``):
    ``factory(design, look_ahead)`` by name, with the :class:`LookAhead`.

    Returns
    -------
    dict of str to callable
        The registry itself.
    """
    return _LOOK_AHEAD


def first_order_controller(name: str, design: TubeDesign, stage: None) -> Controller:
    """The first-order variant's controller of backend ``name`` (role ``controller`` of
    :mod:`~stt_codegen.spec.variants`): law (13) takes no stage.

    Parameters
    ----------
    name : str
        A name of :func:`first_order_backends`.
    design : TubeDesign
    stage : None

    Returns
    -------
    Controller
    """
    return _FIRST_ORDER[name](design)


def cascade_controller(name: str, design: TubeDesign, stage: SecondStage) -> Controller:
    """The cascade's controller of backend ``name`` (role ``controller``).

    Parameters
    ----------
    name : str
        A name of :func:`cascade_backends`.
    design : TubeDesign
    stage : SecondStage

    Returns
    -------
    Controller
    """
    return _CASCADE[name](design, stage)


def look_ahead_controller(name: str, design: TubeDesign, stage: LookAhead) -> Controller:
    """The look-ahead law's controller of backend ``name`` (role ``controller``).

    Parameters
    ----------
    name : str
        A name of :func:`look_ahead_backends`.
    design : TubeDesign
    stage : LookAhead

    Returns
    -------
    Controller
    """
    return _LOOK_AHEAD[name](design, stage)


def _factories(order: int, variant: str | None = None) -> dict[str, Callable[..., Controller]]:
    chosen = variant_of_order(order) if variant is None else variant_named(variant)
    return chosen.entry("backends")()


def register_backend(name: str, factory: Callable[..., Controller], *, order: int = 1,
                     variant: str | None = None) -> None:
    """Make ``factory`` available as backend ``name`` for plants of one order.

    Parameters
    ----------
    name : str
        The backend's name (``--backend``); an existing name of that order is replaced.
    factory : callable
        Order 1: ``factory(design)`` builds the :class:`Controller` for a
        :class:`~stt_codegen.tube.parameters.TubeDesign`. Order 2: ``factory(design,
        stage)``, with the cascade's :class:`~stt_codegen.tube.second_stage.SecondStage`.
    order : {1, 2}, optional
        The plant order the backend serves (default 1).
    variant : {"first-order", "cascade", "look-ahead"}, optional
        The controller variant instead of ``order`` (``"look-ahead"``: ``factory(design,
        look_ahead)`` with the differential drive's
        :class:`~stt_codegen.tube.look_ahead.LookAhead`).

    Raises
    ------
    SpecError
        ``order`` is not 1 or 2 (field ``order``), or an unknown ``variant``.

    Examples
    --------
    A backend that logs each step around the reference, registered for first-order plants
    (``stt.simulate(design, backend="logged")`` then runs it):

    >>> from stt_codegen.runtime.backends import (ReferenceController, backend_names,
    ...                                           register_backend)
    >>> class Logged(ReferenceController):
    ...     name = "logged"
    ...     def step(self, x, t, dt, alpha):
    ...         self.last_t = t
    ...         return super().step(x, t, dt, alpha)
    >>> register_backend("logged", Logged)
    >>> backend_names()[-1]
    'logged'
    """
    _factories(order, variant)[name] = factory


def backend_names(order: int = 1, variant: str | None = None) -> list[str]:
    """The registered backend names of one plant order, in registration order.

    Parameters
    ----------
    order : {1, 2}, optional
        The plant order (default 1).
    variant : str, optional
        The controller variant instead of ``order`` (:data:`~stt_codegen.spec.plants.VARIANTS`).

    Returns
    -------
    list of str
        ``"reference"``, ``"casadi"``, ``"c"``, ``"python"``, then any registered later.

    Raises
    ------
    SpecError
        ``order`` is not 1 or 2 (field ``order``), or an unknown ``variant``.

    Examples
    --------
    >>> from stt_codegen.runtime.backends import backend_names
    >>> backend_names()
    ['reference', 'casadi', 'c', 'python']
    """
    return list(_factories(order, variant))


def default_backend() -> str:
    """The backend :func:`stt_codegen.simulate` and the command line use unless told:
    ``"c"`` (the generated double C, compiled: the fastest, bit-identical to the CasADi
    model) where a C compiler is found (``$CC``, ``cc``, ``gcc`` or ``clang``), else
    ``"reference"`` (the numpy oracle: 30 s against 4.3 s for the C on a 4-state arm).

    Returns
    -------
    str
        ``"c"`` or ``"reference"``.
    """
    from .compiled import compiler
    from ..errors import ToolchainError
    try:
        compiler()
    except ToolchainError:
        return "reference"
    return "c"


def make_controller(name: str, design: TubeDesign,
                    stage: SecondStage | LookAhead | None = None) -> Controller:
    """The controller of backend ``name`` for a design.

    Parameters
    ----------
    name : str
        A name of :func:`backend_names` of the plant's order.
    design : TubeDesign
        The tube and gain the controller runs.
    stage : SecondStage or LookAhead, optional
        The variant's data: the cascade's second stage for a second-order plant, the
        look-ahead point of a differential-drive base; ``None`` for law (13) on the
        plant's state.

    Returns
    -------
    Controller
        ``step(x, t, dt, alpha) -> (u, alpha_next, status)``: ``x`` (n,) state units, or
        ``[x1; x2]`` (2n,) for a second-order plant, ``(x, y, theta)`` for a
        differential-drive base (``u = (v, omega)``); ``t`` and ``dt`` in s, ``alpha``
        (2n,); ``u`` (n,) input units, ``alpha_next`` (2n,) by the implicit step of the
        adaptive law (11), ``status`` a :class:`~stt_codegen.tube.parameters.Status`.

    Raises
    ------
    SpecError
        Unknown backend for the plant's order (field ``backend``).
    ToolchainError
        Backend ``"c"``: no C compiler, or it failed.

    Examples
    --------
    One step of the numpy reference at ``x(0)``, ``alpha = 0``:

    >>> import numpy as np
    >>> import stt_codegen as stt
    >>> from stt_codegen.runtime.backends import make_controller
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> controller = make_controller("reference", design.tube)
    >>> u, alpha_next, status = controller.step(np.array(design.tube.initial_state), 0.0,
    ...                                         1e-3, np.zeros(6))
    >>> u.shape, alpha_next.shape, status
    ((3,), (6,), 0)
    """
    variant = variant_of_stage(stage)
    factories = variant.entry("backends")()
    if name not in factories:
        raise SpecError("backend", f"unknown backend {name!r} for {variant.plant_words} "
                                   f"(known: {', '.join(factories)})")
    return variant.entry("controller")(name, design, stage)
