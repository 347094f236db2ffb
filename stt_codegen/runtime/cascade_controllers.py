"""Backends of the cascade step for second-order plants (docs/second-order.md).

Every backend computes the controller step of both orders, ``(x, t, dt, alpha) -> (u,
alpha_next, status)``, here with the plant's state ``x = [x1; x2]`` (2n: positions, then
velocities), from :func:`stt_codegen.tube.cascade.cascade_step`: ``reference`` (the numpy oracle,
:mod:`stt_codegen.tube.cascade_reference`), ``casadi`` (CasADi's evaluation of the
Function), ``python`` (the Function printed to Python by the emitter) and ``c`` (printed to
C by the emitter, :mod:`stt_codegen.codegen.cascade_source`, compiled with the system's C
compiler and loaded with ``ctypes``).
"""

from __future__ import annotations

import numpy as np

from ..codegen.emit import python_function
from ..errors import SpecError
from ..tube import cascade_reference
from ..tube.parameters import Status, TubeDesign
from ..tube.second_stage import SecondStage
from ..tube.variant_steps import cascade_status

__all__ = ["CascadeController"]

#: The backends of the cascade step, in order.
CASCADE_BACKENDS = ("reference", "casadi", "python", "c")


class CascadeController:
    """One backend of the cascade step.

    Parameters
    ----------
    backend : str
        One of :data:`CASCADE_BACKENDS`.
    design : TubeDesign
        The position tube and its gain.
    stage : SecondStage
        The velocity stage: tube ``rho2`` and gain.

    Raises
    ------
    SpecError
        Unknown backend (field ``backend``).
    ToolchainError, MissingTool
        Backend ``c``: no C compiler, or it failed.
    """

    def __init__(self, backend: str, design: TubeDesign, stage: SecondStage) -> None:
        if backend not in CASCADE_BACKENDS:
            raise SpecError("backend", f"unknown backend {backend!r} for a second-order "
                                       f"plant (known: {', '.join(CASCADE_BACKENDS)})")
        self.name, self.design, self.stage = backend, design, stage
        self._n = design.dimension
        if backend == "reference":
            self._call = self._reference
        else:
            from ..tube.cascade import cascade_step
            function = cascade_step(design, stage)
            if backend == "casadi":
                self._call = lambda *a: [np.array(v, dtype=float).ravel() for v in function(*a)]
            elif backend == "python":
                printed = python_function(function)
                self._call = lambda *a: [np.array(v, dtype=float).ravel()
                                         for v in printed(*[np.ravel(v).tolist() for v in a])]
            else:
                self._call = _compiled(design, stage)

    def _reference(self, x, t, dt, alpha):
        out = cascade_reference.cascade_step(self.design, self.stage, x[None], t, dt,
                                             alpha[None])
        return [np.ravel(v) for v in out]

    def step(self, x: np.ndarray, t: float, dt: float,
             alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """One cascade step.

        Parameters
        ----------
        x : array_like, shape (2n,)
            The plant's state ``[x1; x2]``: positions (state units), then velocities
            (state units per second).
        t, dt : float
            The sampling instant and period, s.
        alpha : array_like, shape (2n,)
            The adaptive law's ``alpha`` (eq. (11)).

        Returns
        -------
        u : ndarray, shape (n,)
            The input, input units.
        alpha_next : ndarray, shape (2n,)
            ``alpha`` at ``t + dt``.
        status : Status
            :class:`~stt_codegen.tube.parameters.Status` of the step.
        """
        x = np.asarray(x, dtype=float)
        out = self._call(x, float(t), float(dt), np.asarray(alpha, dtype=float))
        if len(out) == 3:          # the compiled step returns its status
            return out
        return cascade_status(out, dt, self.design.rate_hz)   # the variant's decoding, once


def _compiled(design: TubeDesign, stage: SecondStage):
    """The emitted C of the cascade step (double), compiled into the build cache and
    loaded (:func:`~stt_codegen.runtime.compiled.load_variant_step`)."""
    from ..codegen.cascade_source import cascade_c_files
    from .compiled import load_variant_step

    n = design.dimension
    step = load_variant_step(cascade_c_files(design, stage, "stt_cascade", "double"),
                             "stt_cascade", (n, 2 * n))

    def call(x, t, dt, alpha):
        u, alpha_next, code = step(x, t, dt, alpha)
        return u, alpha_next, Status(code)

    return call
