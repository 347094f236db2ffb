"""A designed spatiotemporal tube: every number the controller needs, and nothing else.

:class:`TubeDesign` is what :func:`stt_codegen.design.search.design_tube` produces from a spec
and what every backend consumes: the numpy reference (:mod:`stt_codegen.tube.reference`),
the CasADi model (:mod:`stt_codegen.tube.model`) and through it the generated code.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Largest ``|e_i|`` used to compute ``u`` in the deployed controller step: ``e`` is
#: clamped to ``[-E_MAX, E_MAX]`` so that ``u`` is finite everywhere (1 - 2**-20, exact in
#: float32 and float64).
E_MAX = 1.0 - 2.0 ** -20
#: Smallest tube width ``gamma_d`` used to compute ``u`` in the deployed controller step.
GAMMA_D_MIN = 1e-6
#: Newton iterations of the implicit ``alpha`` step (fixed, so the step's cost is fixed).
NEWTON_ITERATIONS = 8
#: Floor used in the Newton start point to avoid 0/0 (representable in float32).
NEWTON_TINY = 1e-30

#: Status codes of one controller step, in every backend and in the generated code.
STATUS_OK = 0
#: ``x`` is not strictly inside the tube (or the tube is empty): ``u`` is still finite.
STATUS_OUTSIDE_TUBE = 1
#: An input is outside the step's domain: ``u = 0``, ``alpha`` kept.
STATUS_INVALID_INPUT = 2

LOWER = "lower"
UPPER = "upper"


@dataclass(frozen=True)
class Circumvent:
    """One circumvent function ``beta^j`` of eqs. (7)-(8).

    Attributes
    ----------
    obstacle : int
        Index ``j`` of the obstacle it avoids.
    dimension : int
        ``i^j``, the state dimension whose tube bound it moves.
    side : {"lower", "upper"}
        ``"lower"`` raises the lower bound above the obstacle (eq. (7)), ``"upper"``
        lowers the upper bound below it (eq. (8)).
    start, end : float
        The active window ``T_act = [t^j, t-bar^j]``, seconds; ``start`` may be negative.
    height : float
        ``B^j``, state units, positive.
    base : float
        ``X_i`` (lower side) or ``X-bar_i`` (upper side), the state-space bound the
        circumvent departs from.
    """

    obstacle: int
    dimension: int
    side: str
    start: float
    end: float
    height: float
    base: float

    @property
    def center(self) -> float:
        """``m^j = (t^j + t-bar^j) / 2``, seconds."""
        return 0.5 * (self.start + self.end)

    @property
    def radius(self) -> float:
        """``|r^j| = (t-bar^j - t^j) / 2``, seconds."""
        return 0.5 * (self.end - self.start)

    @property
    def peak(self) -> float:
        """The bound's value at the window centre, state units."""
        return self.base + self.height if self.side == LOWER else self.base - self.height


@dataclass(frozen=True)
class TubeDesign:
    """All parameters of one spatiotemporal tube and its controller.

    Vectors are tuples of length ``n`` (the state dimension).

    Attributes
    ----------
    name : str
        The spec's name.
    prescribed_time : float
        ``t_c``, seconds.
    state_lower, state_upper : tuple of float
        ``X`` and ``X-bar``, the state-space box.
    initial_lower, initial_upper : tuple of float
        The box ``X-hat_0`` of eq. (2): ``x(0) -+ d_0``.
    target_lower, target_upper : tuple of float
        The box ``T-hat`` of eq. (3): ``eta -+ d_T``.
    initial_state : tuple of float
        ``x(0)``.
    circumvents : tuple of Circumvent
        In a deterministic order (by dimension, side, then obstacle index).
    circumvent_sharpness : float
        ``k^j`` of eqs. (7)-(8) (the same for every obstacle).
    smoothness : float
        ``nu`` of the smooth max/min, 1/state units.
    theta0, kappa, mu : float
        Parameters of the adaptive law (11).
    gain : float
        ``k`` of the control law (13).
    rate_hz : float
        Sampling rate of the deployed controller, Hz.
    """

    name: str
    prescribed_time: float
    state_lower: tuple[float, ...]
    state_upper: tuple[float, ...]
    initial_lower: tuple[float, ...]
    initial_upper: tuple[float, ...]
    target_lower: tuple[float, ...]
    target_upper: tuple[float, ...]
    initial_state: tuple[float, ...]
    circumvents: tuple[Circumvent, ...]
    circumvent_sharpness: float
    smoothness: float
    theta0: float
    kappa: float
    mu: float
    gain: float
    rate_hz: float

    @property
    def dimension(self) -> int:
        """State dimension ``n``."""
        return len(self.state_lower)

    def circumvents_on(self, dimension: int, side: str) -> tuple[Circumvent, ...]:
        """The circumvents acting on one bound, in design order."""
        return tuple(c for c in self.circumvents if c.dimension == dimension and c.side == side)
