"""The peak input of law (13) along a tube, and the prover the design asks for it.

Law (13) gives, per input, ``|u_i| = 4 k phi(|e_i|) / gamma_d_i`` with
``phi(s) = 2 atanh(s) / (1 - s^2)`` (``epsilon_i = 2 atanh(e_i)``,
``xi_i = 4 / (gamma_d_i (1 - e_i^2))``). ``phi`` is increasing on ``[0, 1)``, so a bound
``E_k,i`` of ``|e_i(t_k)|`` at each sample and a lower bound ``W_k,i`` of the width there
bound the input the deployed controller asks for at that sample:

    |u_k,i| <= 4 k phi(E_k,i) / max(W_k,i, GAMMA_D_MIN)          (input_peak)

(the deployed law divides by the width floored at ``GAMMA_D_MIN``, and ``e`` is clamped
to ``E_MAX``). ``docs/sampled-data.md`` ("The input bound") has the argument.

The bound on ``e`` is the sampled-data check's (:mod:`.certificate.sampled`); its prover,
:func:`~.certificate.actuator.prove_input_bound`, builds on this module, and the design
(:mod:`.actuator`) calls it. This module imports nothing heavy at import time (numpy inside
its functions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..tube.parameters import E_MAX, GAMMA_D_MIN

if TYPE_CHECKING:
    import numpy as np

    from ..spec.loader import Spec

__all__ = ["InputProof", "input_peak", "phi"]


@dataclass(frozen=True)
class InputProof:
    """The proved peak of every input of law (13) along a tube, for the spec's plants.

    Attributes
    ----------
    proved : bool
        The sampled-data check passed, so ``peak`` bounds ``|u_i|`` at every sample of
        its horizon for every plant of ``[assumptions]``.
    peak : tuple of float
        Per input, input units (``inf`` when not proved).
    time : tuple of float
        Per input, the sample instant of the peak, seconds.
    horizon : float
        End of the samples covered, seconds (the sampled check's, ``1.1 t_c``).
    reason : str
        When not proved: why (the sampled check's failure).
    max_abs_e : float
        The bound of ``|e_i(t_k)|`` the peak is proved from, largest over the samples and
        dimensions (``inf`` when not proved); ``design_tube`` reads it to refuse a paper
        tube one gain cannot follow (:mod:`.tracking`).
    speed : float
        A bound of the input vector's Euclidean norm ``|u(t_k)|`` at every sample, the
        largest over the samples of ``sqrt(sum_i bound_k,i^2)`` (input units), at most
        ``hypot(*peak)`` and smaller where the inputs peak at different samples; ``inf``
        when not proved or not computed (a proof built from peaks alone).
    speed_time : float
        The sample instant of :attr:`speed`, seconds.
    complete : bool
        The peaks are over the whole horizon; false for a proof that stopped at the first
        sample over a caller's limit (``prove_input_bound``'s ``limit``): its peaks are
        those up to that sample, lower bounds of the whole proof's, and it meets no bound.
    backward : float
        A differential-drive base's: a bound of the speed ``max(0, -v)`` it may be asked to
        back up at, m/s (docs/differential-drive.md, "Backing up"); 0 for the other
        variants.
    backward_time : float
        The sample instant of :attr:`backward`, seconds.
    reverse_limit : float
        The ``[actuator] reverse_speed`` :attr:`backward` is judged against (``inf``: none,
        the bound of ``|v|`` covers it).
    """

    proved: bool
    peak: tuple[float, ...]
    time: tuple[float, ...]
    horizon: float
    reason: str = ""
    max_abs_e: float = math.inf
    speed: float = math.inf
    speed_time: float = 0.0
    complete: bool = True
    backward: float = 0.0
    backward_time: float = 0.0
    reverse_limit: float = math.inf

    @property
    def backs_up_within(self) -> bool:
        """:attr:`backward` within :attr:`reverse_limit`."""
        return self.backward <= self.reverse_limit

    def _reverse_ratio(self) -> float:
        """``backward / reverse_limit`` (0 without a limit or when 0, ``inf`` for a positive
        ``backward`` over a limit of 0)."""
        if self.backward == 0.0 or math.isinf(self.reverse_limit):
            return 0.0
        return math.inf if self.reverse_limit == 0.0 else self.backward / self.reverse_limit

    def ratio(self, bound: tuple[float, ...]) -> float:
        """``max_i peak_i / bound_i`` and ``backward / reverse_limit`` (``inf`` when not
        proved): at most 1 meets the bound."""
        if not self.proved:
            return math.inf
        return max(max(p / b for p, b in zip(self.peak, bound)), self._reverse_ratio())

    def meets(self, bound: tuple[float, ...]) -> bool:
        """Proved over the whole horizon, ``peak_i <= bound_i`` for every input, and
        ``backward <= reverse_limit``."""
        return (self.proved and self.complete and self.backs_up_within
                and all(p <= b for p, b in zip(self.peak, bound)))

    def margin(self, bound: tuple[float, ...]) -> float:
        """``min_i (bound_i - peak_i) / bound_i``, and ``1 - backward / reverse_limit``: the
        relative room left (negative: exceeded; ``-inf`` when not proved)."""
        if not self.proved:
            return -math.inf
        return min(min((b - p) / b for p, b in zip(self.peak, bound)),
                   1.0 - self._reverse_ratio())


def phi(s: "np.ndarray") -> "np.ndarray":
    """``|u_i| gamma_d_i / (4 k)`` of law (13) at ``|e_i| = s``: ``2 atanh(s) / (1 - s^2)``.

    Parameters
    ----------
    s : ndarray
        ``|e_i|`` in ``[0, 1)``, any shape; clamped at ``E_MAX`` as the deployed law is.

    Returns
    -------
    ndarray, the shape of ``s``
        ``2 atanh(s) / (1 - s^2)``, non-negative.
    """
    import numpy as np
    s = np.minimum(np.asarray(s, dtype=float), E_MAX)
    return 2.0 * np.arctanh(s) / (1.0 - s * s)


def input_peak(gain: float, abs_e: "np.ndarray", width: "np.ndarray", t: "np.ndarray",
               horizon: float) -> InputProof:
    """The peak of each input of law (13), from bounds of ``|e|`` and of the width.

    Parameters
    ----------
    gain : float
        ``k`` of law (13).
    abs_e : ndarray, shape (K, n)
        A bound of ``|e_i(t_k)|`` at each sample, below 1.
    width : ndarray, shape (K, n)
        A lower bound of ``gamma_d_i(t_k)`` at each sample, state units.
    t : ndarray, shape (K,)
        The sample instants, seconds.
    horizon : float
        Seconds, for the report.

    Returns
    -------
    InputProof
        ``peak_i = max_k 4 k phi(abs_e_k,i) / max(width_k,i, GAMMA_D_MIN)``, proved;
        ``max_abs_e = max abs_e``; ``speed = max_k sqrt(sum_i (4 k phi(abs_e_k,i) /
        max(width_k,i, GAMMA_D_MIN))^2)``, the bound of ``|u(t_k)|`` sample by sample.
    """
    import numpy as np
    u = 4.0 * gain * phi(abs_e) / np.maximum(width, GAMMA_D_MIN)
    where = np.argmax(u, axis=0)
    norm = np.sqrt(np.sum(u * u, axis=1))
    fastest = int(np.argmax(norm))
    return InputProof(True, tuple(float(v) for v in u.max(axis=0)),
                      tuple(float(t[k]) for k in where), float(horizon),
                      max_abs_e=float(np.max(abs_e)), speed=float(norm[fastest]),
                      speed_time=float(t[fastest]))
