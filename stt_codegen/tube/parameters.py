"""A designed spatiotemporal tube: every number the controller needs, and nothing else.

:class:`TubeDesign` is what :func:`stt_codegen.design.search.design_tube` produces from a spec
and what every backend consumes: the numpy reference (:mod:`stt_codegen.tube.reference`),
the CasADi model (:mod:`stt_codegen.tube.model`) and through it the generated code.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["CRUISE", "CRUISE_RAMP", "Circumvent", "E_MAX", "GAMMA_D_MIN", "GLIDE", "GLIDE_RAMP",
           "GLIDE_TURN", "LOWER", "NEWTON_ITERATIONS", "NEWTON_TINY",
           "PERIOD_TOLERANCE", "ReachSegment", "SCURVE", "SCURVE_TURN", "SMOOTHSTEP",
           "STATUS_INPUT_CLAMPED", "STATUS_INVALID_INPUT", "STATUS_OFF_PERIOD", "STATUS_OK",
           "STATUS_OUTSIDE_TUBE", "STATUS_OUTSIDE_VELOCITY_TUBE", "Status", "TANH", "TubeDesign", "UPPER",
           "off_period", "paper_segments", "peak_acceleration_factor", "peak_rate_factor",
           "step_status"]

#: Largest ``|e_i|`` used to compute ``u`` in the deployed controller step: ``e`` is
#: clamped to ``[-E_MAX, E_MAX]`` so that ``u`` is finite everywhere (1 - 2**-20, exact in
#: float32 and float64).
E_MAX = 1.0 - 2.0 ** -20
#: Smallest tube width ``gamma_d`` used to compute ``u`` in the deployed controller step.
GAMMA_D_MIN = 1e-6
#: Newton iterations of the implicit ``alpha`` step (fixed, so the step's cost is fixed):
#: the fewest that solve the adversarial batch of ``tests/test_alpha_step.py`` to 1e-12
#: (4 leave errors of 2.6e-8; see docs/codegen.md).
NEWTON_ITERATIONS = 5
#: Floor used in the Newton start point to avoid 0/0 (representable in float32).
NEWTON_TINY = 1e-30

class Status(enum.IntEnum):
    """Status code of one controller step, for both orders, in every backend and in the
    generated code (``<PREFIX>_STATUS_<NAME>`` in C, ``STATUS_<NAME>`` in Python).

    Attributes
    ----------
    OK : 0
        The state is strictly inside its tube(s); ``u`` is the law's output.
    OUTSIDE_TUBE : 1
        ``x`` (the position ``x1`` for a second-order plant) is not strictly inside the
        designed tube, or the tube is empty: ``u`` is still finite.
    INVALID_INPUT : 2
        An input of the step is outside its domain: ``u = 0``, ``alpha`` kept.
    INPUT_CLAMPED : 3
        Inside the tube(s), but the law asked for more than the actuator bound
        (``[actuator] input_bound``) in some input: ``u`` was clamped to
        ``+-input_bound``. Only designs with an input bound return it; ``OUTSIDE_TUBE``,
        ``OUTSIDE_VELOCITY_TUBE`` and the step's ``OFF_PERIOD`` take precedence.
    OUTSIDE_VELOCITY_TUBE : 4
        Second order only: the position is inside its tube, the velocity error
        ``x2 - r`` is not inside ``(-rho2, rho2)``.
    OFF_PERIOD : 5
        The step was called with ``dt`` not equal to ``PERIOD`` (``1 / rate_hz``), to a
        relative ``2^-20``: ``u`` and ``alpha_next`` are computed as usual for that ``dt``,
        but the certificate does not cover the call. Only the step (which takes ``dt``)
        returns it; ``INVALID_INPUT``, ``OUTSIDE_TUBE`` and ``OUTSIDE_VELOCITY_TUBE`` take
        precedence, and it takes precedence over ``INPUT_CLAMPED``.
    """

    OK = 0
    OUTSIDE_TUBE = 1
    INVALID_INPUT = 2
    INPUT_CLAMPED = 3
    OUTSIDE_VELOCITY_TUBE = 4
    OFF_PERIOD = 5


#: Aliases of :class:`Status` members (the names the generated code uses).
STATUS_OK = Status.OK
STATUS_OUTSIDE_TUBE = Status.OUTSIDE_TUBE
STATUS_INVALID_INPUT = Status.INVALID_INPUT
STATUS_INPUT_CLAMPED = Status.INPUT_CLAMPED
STATUS_OUTSIDE_VELOCITY_TUBE = Status.OUTSIDE_VELOCITY_TUBE
STATUS_OFF_PERIOD = Status.OFF_PERIOD

#: Relative tolerance of the step's period check: ``|dt - PERIOD| > PERIOD * PERIOD_TOLERANCE``
#: is :attr:`Status.OFF_PERIOD` (``2^-20``: a ``dt`` rounded to float32 from ``PERIOD`` passes,
#: exact in float32 and float64, and ``PERIOD * PERIOD_TOLERANCE`` is exact too).
PERIOD_TOLERANCE = 2.0 ** -20


def off_period(dt, rate_hz: float):
    """Whether a step's ``dt`` is not the period ``1 / rate_hz`` to a relative
    :data:`PERIOD_TOLERANCE`, as the generated step decides it.

    Parameters
    ----------
    dt : float or array_like
        The steps' ``dt``, s.
    rate_hz : float
        The design's rate, Hz: ``PERIOD = 1 / rate_hz`` (the generated code's ``PERIOD``).

    Returns
    -------
    bool or ndarray of bool
        ``|dt - PERIOD| > PERIOD * PERIOD_TOLERANCE``, in double precision (the shape of
        ``dt``).
    """
    period = 1.0 / rate_hz
    return np.abs(np.asarray(dt, dtype=float) - period) > period * PERIOD_TOLERANCE


def step_status(status, dt, rate_hz: float):
    """The step's status from the law's: :attr:`Status.OFF_PERIOD` where ``dt`` is off the
    period (:func:`off_period`) and the law's status is ``OK`` or ``INPUT_CLAMPED``, else
    the law's (``INVALID_INPUT``, ``OUTSIDE_TUBE`` and ``OUTSIDE_VELOCITY_TUBE`` take
    precedence). ``P_control``, ``P_alpha_step`` and ``P_tube`` take no period and keep the
    law's status.

    Parameters
    ----------
    status : Status or int or array_like of int
        The law's status (the step's without the period check).
    dt : float or array_like
        The step's ``dt``, s (broadcast with ``status``).
    rate_hz : float
        The design's rate, Hz.

    Returns
    -------
    Status or ndarray of int
        A :class:`Status` for a scalar ``status``, else an array of the codes.
    """
    code = np.asarray(status)
    timed = np.where(off_period(dt, rate_hz) & ((code == Status.OK)
                                                | (code == Status.INPUT_CLAMPED)),
                     int(Status.OFF_PERIOD), code)
    return Status(int(timed)) if timed.ndim == 0 else timed

LOWER = "lower"
UPPER = "upper"

#: Profile of a reach-tube segment: the paper's eq. (4), ``s = tanh(tau / (1 - tau))``.
TANH = "tanh"
#: Profile of a reach-tube segment: the quintic smooth step
#: ``sigma(tau) = tau^3 (10 - 15 tau + 6 tau^2)`` (value and first two derivatives
#: continuous, zero slope and curvature at both ends).
SMOOTHSTEP = "smoothstep"
#: Profile of a reach-tube segment: a cruise between two smooth ramps. Over the first
#: :data:`CRUISE_RAMP` of the segment ``p_dot`` rises from 0 to its peak by the cubic
#: smooth step ``x^2 (3 - 2 x)`` (``x = tau / CRUISE_RAMP``), stays at the peak, and falls
#: the same way over the last :data:`CRUISE_RAMP`: ``p``, ``p_dot``, ``p_ddot`` continuous,
#: zero slope and curvature at both ends, and a peak rate ``1 / (1 - CRUISE_RAMP)`` times
#: the mean (the quintic smooth step's is 15/8).
CRUISE = "cruise"
#: The cruise profile's ramps, each this share of the segment's duration.
CRUISE_RAMP = 0.2
#: Profile of a reach-tube segment: a jerk-limited S-curve, the profile of least peak
#: acceleration among ours (one of the two that via points timed for a force try, after the
#: smooth step: ``design/actuator.py``). Its acceleration
#: ``p_ddot`` rises linearly from 0 to ``A`` over the first :data:`SCURVE_TURN` of the
#: segment, holds ``A``, turns linearly to ``-A`` over the :data:`SCURVE_TURN` on each side
#: of the middle, holds ``-A``, and returns to 0 over the last :data:`SCURVE_TURN`:
#: ``p``, ``p_dot``, ``p_ddot`` continuous, zero slope and curvature at both ends, a peak
#: rate of 2 times the mean at the middle (the quintic smooth step's 15/8) and a peak
#: acceleration ``A = 4 / (1 - 2 SCURVE_TURN)`` times ``1 / duration^2`` (4.76; the quintic's
#: ``10 / sqrt(3)`` = 5.77, the cruise's 9.38).
SCURVE = "scurve"
#: The S-curve's turns of the acceleration, each this share of the segment's duration: the
#: largest jerk, ``A / SCURVE_TURN`` = 59.5, is then within the quintic smooth step's 60.
SCURVE_TURN = 0.08
#: Profile of a reach-tube segment: a jerk-limited glide, the S-curve with a cruise between
#: its two halves. Over the first :data:`GLIDE_RAMP` of the segment the acceleration
#: ``p_ddot`` rises linearly from 0 to ``A`` over :data:`GLIDE_TURN`, holds ``A``, and returns
#: linearly to 0 over :data:`GLIDE_TURN`, so the rate reaches ``V = 1 / (1 - GLIDE_RAMP)``
#: times the mean; the rate holds ``V``, and the last :data:`GLIDE_RAMP` mirrors the first.
#: ``p``, ``p_dot``, ``p_ddot`` continuous, zero slope and curvature at both ends; peak rate
#: 5/3 times the mean and peak acceleration ``A = V / (GLIDE_RAMP - GLIDE_TURN)`` (5.38) times
#: ``1 / duration^2``: both below the quintic smooth step's (15/8 and 5.77), so a move bound
#: by a velocity bound is shorter with it for less force (docs/design.md, "Glides").
GLIDE = "glide"
#: The glide's ramps, each this share of the segment's duration.
GLIDE_RAMP = 0.4
#: The glide's turns of the acceleration, each this share of the segment's duration: the
#: largest jerk, ``A / GLIDE_TURN`` = 59.7, is then within the quintic smooth step's 60.
GLIDE_TURN = 0.09
PROFILES = (TANH, SMOOTHSTEP, CRUISE, SCURVE, GLIDE)


#: ``(sup dp/dtau, sup |d^2p/dtau^2|)`` of each smooth profile (docstrings below).
_PEAKS = {SMOOTHSTEP: (1.875, 10.0 / math.sqrt(3.0)),
          CRUISE: (1.0 / (1.0 - CRUISE_RAMP), 1.5 / (CRUISE_RAMP * (1.0 - CRUISE_RAMP))),
          SCURVE: (2.0, 4.0 / (1.0 - 2.0 * SCURVE_TURN)),
          GLIDE: (1.0 / (1.0 - GLIDE_RAMP),
                  1.0 / ((1.0 - GLIDE_RAMP) * (GLIDE_RAMP - GLIDE_TURN)))}


def _peaks(profile: str, what: str) -> tuple[float, float]:
    if profile not in _PEAKS:
        raise ValueError(f"no fixed peak {what} for the reach segment profile {profile!r}")
    return _PEAKS[profile]


def peak_rate_factor(profile: str) -> float:
    """``sup_tau dp/dtau`` of a smooth profile: the peak of ``|rho_dot|`` on a segment is
    this times ``|to - from| / (end - start)``.

    Parameters
    ----------
    profile : {"smoothstep", "cruise", "scurve", "glide"}

    Returns
    -------
    float
        ``15/8`` for ``"smoothstep"`` (``30 tau^2 (1 - tau)^2`` at ``tau = 1/2``);
        ``1 / (1 - CRUISE_RAMP)`` for ``"cruise"`` (the cruise's rate: the two ramps
        together cover half their length at the mean rate's ``1 / (1 - CRUISE_RAMP)``
        multiple, the cruise the rest); 2 for ``"scurve"`` (``A (1/2 - SCURVE_TURN)`` at
        ``tau = 1/2``, whatever the turn); ``1 / (1 - GLIDE_RAMP)`` (5/3) for ``"glide"``
        (its cruise's rate, as the cruise's).

    Raises
    ------
    ValueError
        ``"tanh"`` (its peak depends on the segment: ``verify.lemma.reach_rate_bound``) or
        an unknown profile.
    """
    return _peaks(profile, "rate")[0]


def peak_acceleration_factor(profile: str) -> float:
    """``sup_tau |d^2p/dtau^2|``, as :func:`peak_rate_factor` for the rate: the peak of
    ``|rho_ddot|`` on a segment is this times ``|to - from| / (end - start)^2``. It is
    ``10 / sqrt(3)`` (5.77) for ``"smoothstep"`` (at ``tau = 1/2 -+ sqrt(3)/6``), ``1.5 / (a
    (1 - a))`` (9.38) for ``"cruise"`` (the cubic smooth step's slope 3/2 over a ramp of
    share ``a = CRUISE_RAMP`` up to the rate ``1 / (1 - a)``), ``4 / (1 - 2 q)`` (4.76) for
    ``"scurve"`` (``q = SCURVE_TURN``), ``1 / ((1 - r) (r - q))`` (5.38) for ``"glide"`` (``r =
    GLIDE_RAMP``, ``q = GLIDE_TURN``); ``ValueError`` for ``"tanh"`` (unbounded near its
    end) or an unknown profile.
    """
    return _peaks(profile, "acceleration")[1]


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
    sharpness : float
        ``k^j`` of eqs. (7)-(8), dimensionless, positive: the larger, the wider the bump's
        shoulders (the bound moves more slowly and stays near its peak for less of the
        window).
    """

    obstacle: int
    dimension: int
    side: str
    start: float
    end: float
    height: float
    base: float
    sharpness: float

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
class ReachSegment:
    """One piece of the reachability tube ``rho`` (eq. (4) generalized to several pieces).

    On ``[start, end]`` every bound moves from its ``*_from`` value to its ``*_to`` value by
    the same scalar profile ``p(tau)`` in ``[0, 1]``, ``tau = (t - start) / (end - start)``:
    ``rho = from + (to - from) p(tau)``; before ``start`` the bound is ``from``, after ``end``
    it is ``to``. The paper's tube is one ``"tanh"`` segment from the initial box at
    ``t = 0`` to the target box at ``t_c``.

    Attributes
    ----------
    start, end : float
        Seconds, ``start < end``.
    lower_from, upper_from, lower_to, upper_to : tuple of float
        The boxes at ``start`` and ``end``, state units, length ``n`` each.
    profile : {"tanh", "smoothstep", "cruise"}
        ``"tanh"``: ``p = tanh(tau / (1 - tau))`` for ``tau < 1``, 1 after (eq. (4));
        ``"smoothstep"``: ``p = tau^3 (10 - 15 tau + 6 tau^2)`` (value, first and second
        derivatives continuous at both ends, where the slope is zero); ``"cruise"``: smooth
        ramps around a constant rate (:data:`CRUISE`; the same continuity, a lower peak
        rate).
    """

    start: float
    end: float
    lower_from: tuple[float, ...]
    upper_from: tuple[float, ...]
    lower_to: tuple[float, ...]
    upper_to: tuple[float, ...]
    profile: str = TANH

    @property
    def duration(self) -> float:
        """``end - start``, seconds."""
        return self.end - self.start


def paper_segments(initial_lower, initial_upper, target_lower, target_upper,
                   prescribed_time: float) -> tuple[ReachSegment, ...]:
    """The paper's reach tube (eq. (4)): one ``"tanh"`` segment from ``X-hat_0`` at 0 to ``T-hat`` at ``t_c``.

    Parameters
    ----------
    initial_lower, initial_upper : sequence of float, length n
        ``x(0) -+ d_0`` (eq. (2)).
    target_lower, target_upper : sequence of float, length n
        ``eta -+ d_T`` (eq. (3)).
    prescribed_time : float
        ``t_c``, seconds.

    Returns
    -------
    tuple of ReachSegment
        One segment.
    """
    return (ReachSegment(0.0, float(prescribed_time), tuple(initial_lower),
                         tuple(initial_upper), tuple(target_lower), tuple(target_upper),
                         TANH),)


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
    segments : tuple of ReachSegment
        The reachability tube ``rho``, in time order, contiguous in box (each starts from
        the box where the previous ends), each starting when the previous ends or, to
        blend a corner, before (:attr:`blends_corners`; at most two at once); its first
        box is ``X-hat_0`` of eq. (2), its last the target box ``T-hat`` of eq. (3) (see
        :attr:`initial_lower`, :attr:`target_lower`).
    initial_state : tuple of float
        ``x(0)``.
    circumvents : tuple of Circumvent
        In a deterministic order (by dimension, side, then obstacle index); each carries
        its own sharpness ``k^j``.
    smoothness : float
        ``nu`` of the smooth max/min, 1/state units.
    theta0, kappa, mu : float
        Parameters of the adaptive law (11).
    gain : float
        ``k`` of the control law (13).
    rate_hz : float
        Sampling rate of the deployed controller, Hz.
    input_bound : tuple of float or None
        ``[actuator] input_bound``, one per entry of ``u`` (input units): the deployed step
        clamps ``u_i`` to ``[-input_bound_i, input_bound_i]`` and reports
        ``STATUS_INPUT_CLAMPED`` when it did; ``None`` (default): no clamp, and the
        generated code is that of a design without actuator limits.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> tube = stt.design_tube(stt.load_spec("omnirobot-s1")).tube
    >>> tube.prescribed_time, tube.rate_hz, tube.initial_state
    (9.0, 1000.0, (0.25, 4.75, 0.0))
    >>> [(c.obstacle, c.dimension, c.side) for c in tube.circumvents]
    [(0, 1, 'upper')]
    """

    name: str
    prescribed_time: float
    state_lower: tuple[float, ...]
    state_upper: tuple[float, ...]
    segments: tuple[ReachSegment, ...]
    initial_state: tuple[float, ...]
    circumvents: tuple[Circumvent, ...]
    smoothness: float
    theta0: float
    kappa: float
    mu: float
    gain: float
    rate_hz: float
    input_bound: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if not self.segments:
            raise ValueError("a tube design needs at least one reach segment")
        if self.input_bound is not None and (
                len(self.input_bound) != len(self.state_lower)
                or not all(b > 0 for b in self.input_bound)):
            raise ValueError("input_bound needs one positive entry per state dimension")
        for a, b in zip(self.segments, self.segments[1:]):
            if (b.lower_from != a.lower_to or b.upper_from != a.upper_to
                    or not a.start < b.start <= a.end):
                raise ValueError("reach segments must be contiguous in box and each start "
                                 "after the previous one starts, at or before it ends")
        for a, c in zip(self.segments, self.segments[2:]):
            if c.start < a.end:
                raise ValueError("at most two reach segments may move the tube at once: a "
                                 "segment must start after the one two before it ends")

    @property
    def blends_corners(self) -> bool:
        """Whether some reach segment starts before the previous one ends (blended corners).

        Then on ``[start_{k+1}, end_k]`` both move the box: ``rho = from_k + (to_k - from_k)
        p_k + (to_{k+1} - from_{k+1}) p_{k+1}``, the tube passing the via box ``B_{k+1}``
        without stopping at it (docs/design.md, "Blended corners").
        """
        return any(b.start < a.end for a, b in zip(self.segments, self.segments[1:]))

    @property
    def dimension(self) -> int:
        """State dimension ``n``."""
        return len(self.state_lower)

    @property
    def initial_lower(self) -> tuple[float, ...]:
        """Lower corner of ``X-hat_0`` (eq. (2)), the first box of the reach tube."""
        return self.segments[0].lower_from

    @property
    def initial_upper(self) -> tuple[float, ...]:
        """Upper corner of ``X-hat_0`` (eq. (2))."""
        return self.segments[0].upper_from

    @property
    def target_lower(self) -> tuple[float, ...]:
        """Lower corner of ``T-hat`` (eq. (3)), the last box of the reach tube."""
        return self.segments[-1].lower_to

    @property
    def target_upper(self) -> tuple[float, ...]:
        """Upper corner of ``T-hat`` (eq. (3))."""
        return self.segments[-1].upper_to

    @property
    def reach_end(self) -> float:
        """Time at which the reach tube arrives in the target box, seconds (``<= t_c``)."""
        return self.segments[-1].end

    def circumvents_on(self, dimension: int, side: str) -> tuple[Circumvent, ...]:
        """The circumvents acting on one bound, in design order."""
        return tuple(c for c in self.circumvents if c.dimension == dimension and c.side == side)
