"""Backends of the look-ahead variant for differential-drive bases (docs/differential-drive.md).

Every backend computes the controller step ``(x, t, dt, alpha) -> (u, alpha_next,
status)``, here with the base's state ``x = (x, y, theta)`` and ``u = (v, omega)``:
``reference`` (the numpy oracle, :mod:`stt_codegen.tube.look_ahead_reference`), ``casadi``
(CasADi's evaluation of :func:`stt_codegen.tube.look_ahead.look_ahead_step`), ``python``
(the Function printed to Python by the emitter) and ``c`` (the generated C of
:mod:`stt_codegen.codegen.look_ahead_source`, compiled and loaded with ``ctypes``).
"""

from __future__ import annotations

import numpy as np

from ..codegen.emit import python_function
from ..errors import SpecError
from ..tube import look_ahead_reference
from ..tube.look_ahead import LookAhead, look_ahead_step
from ..tube.parameters import Status, TubeDesign
from ..tube.variant_steps import law13_status

__all__ = ["LOOK_AHEAD_BACKENDS", "LookAheadController"]

#: The backends of the look-ahead step, in order.
LOOK_AHEAD_BACKENDS = ("reference", "casadi", "c", "python")


class LookAheadController:
    """One backend of the look-ahead step.

    Parameters
    ----------
    backend : str
        One of :data:`LOOK_AHEAD_BACKENDS`.
    design : TubeDesign
        The look-ahead point's tube and its gain (no ``input_bound`` of its own).
    look_ahead : LookAhead
        The axle offset and the base's limits.

    Raises
    ------
    SpecError
        Unknown backend (field ``backend``).
    ToolchainError, MissingTool
        Backend ``c``: no C compiler, or it failed.
    """

    def __init__(self, backend: str, design: TubeDesign, look_ahead: LookAhead) -> None:
        if backend not in LOOK_AHEAD_BACKENDS:
            raise SpecError("backend", f"unknown backend {backend!r} for a differential-drive "
                                       f"base (known: {', '.join(LOOK_AHEAD_BACKENDS)})")
        self.name, self.design, self.look_ahead = backend, design, look_ahead
        if backend == "reference":
            self._call = self._reference
        elif backend == "c":
            self._call = _compiled(design, look_ahead)
        else:
            function = look_ahead_step(design, look_ahead)
            if backend == "casadi":
                self._call = lambda x, t, dt, alpha: law13_status(
                    [np.array(v, dtype=float).ravel() for v in function(x, t, dt, alpha)],
                    dt, design.rate_hz)
            else:
                printed = python_function(function)
                self._call = lambda x, t, dt, alpha: law13_status(
                    [np.array(v, dtype=float).ravel()
                     for v in printed(*[np.ravel(v).tolist() for v in (x, t, dt, alpha)])],
                    dt, design.rate_hz)

    def _reference(self, x, t, dt, alpha):
        u, alpha_next, status = look_ahead_reference.look_ahead_status(
            self.design, self.look_ahead.axle_offset, self.look_ahead.input_bound, x[None],
            t, dt, alpha[None], self.look_ahead.reverse_speed)
        return u[0], alpha_next[0], Status(int(status[0]))

    def step(self, x: np.ndarray, t: float, dt: float,
             alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """One step of the variant.

        Parameters
        ----------
        x : array_like, shape (3,)
            The base's state: the axle's midpoint (m) and the heading (rad).
        t, dt : float
            The sampling instant and period, s.
        alpha : array_like, shape (4,)
            The adaptive law's ``alpha`` (eq. (11)), m.

        Returns
        -------
        u : ndarray, shape (2,)
            ``v`` (m/s) and ``omega`` (rad/s).
        alpha_next : ndarray, shape (4,)
            ``alpha`` at ``t + dt``.
        status : Status
        """
        return self._call(np.asarray(x, dtype=float), float(t), float(dt),
                          np.asarray(alpha, dtype=float))



def _compiled(design: TubeDesign, look_ahead: LookAhead):
    """The emitted C of the step (double), compiled into the build cache and loaded
    (:func:`~stt_codegen.runtime.compiled.load_variant_step`)."""
    from ..codegen.look_ahead_source import look_ahead_c_files
    from .compiled import load_variant_step

    step = load_variant_step(look_ahead_c_files(design, look_ahead, "stt_look_ahead", "double"),
                             "stt_look_ahead", (2, 4))

    def call(x, t, dt, alpha):
        u, alpha_next, code = step(x, t, dt, alpha)
        return u, alpha_next, Status(code)

    return call
