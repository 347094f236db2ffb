"""Closed-loop simulation: a sampled controller on a continuous plant, and Definition 2.1.

One loop for both orders of plant. The controller runs at ``rate_hz``: at each sampling
instant ``t_k`` it reads the plant's state ``x(t_k)`` (a first-order plant's ``n``
states, or a second-order plant's positions and velocities ``[x1; x2]``), computes ``u_k``
and its next ``alpha`` (law (13), or the cascade law of docs/second-order.md); ``u_k`` is
held until ``t_{k+1}`` (with a ``[controller] delay`` ``d``, from ``t_k + d`` to
``t_{k+1} + d``: :func:`hold_period`). The plant, a python-control ``NonlinearIOSystem``
(:func:`~stt_codegen.runtime.plants.spec_plant`), is integrated over each hold interval by
the classical Runge-Kutta method with :data:`SUBSTEPS` steps (its accuracy against an
adaptive solver at tight tolerance is tested). Definition 2.1 is judged on the positions
(the spec's state space), the same way for both orders: target, obstacles (moving ones
where they are), state space, ``[[tasks]]``; a second-order run also on its velocities.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

import control as ct

from .backends import Controller, default_backend, make_controller
from ..design.prediction import delay_predictor
from ..design.result import Design, require_design
from ..design.samples import check_step_budget
from ..display import Rows, markdown, text
from ..errors import SpecError
from .mujoco_plant import MujocoPlant
from .plants import check_seed, spec_plant
from .state_split import initial_state, positions
from ..spec.loader import Spec
from ..spec.variants import variant_of, variant_of_stage
from ..tube import cascade_reference, reference
from ..tube.parameters import Status, TubeDesign
from ..tube.look_ahead import LookAhead
from ..tube.second_stage import SecondStage
from .tasks import TaskOutcome, judge_tasks, until_met

__all__ = ["RungeKutta", "SUBSTEPS", "SimulationResult", "Trajectory",
           "cascade_velocity_reference", "hold_period", "no_velocity_fields",
           "no_velocity_reference", "run_closed_loop", "sampling_offsets", "simulate",
           "velocity_fields"]

#: Runge-Kutta steps per sampling period.
SUBSTEPS = 2


@dataclass
class Trajectory:
    """Sampled closed-loop signals, ``N`` instants.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sampling instants ``t_k = k / rate_hz``, s.
    x : ndarray, shape (N, n)
        The positions at ``t_k`` (the spec's state space: a first-order plant's state, a
        second-order plant's ``x1``), state units.
    u : ndarray, shape (N, n)
        The input computed at ``t_k`` and held until ``t_{k+1}`` (with a spec's
        ``delay``, from ``t_k + delay`` to ``t_{k+1} + delay``), input units.
    alpha : ndarray, shape (N, 2n)
        The adaptive law's ``alpha`` (eq. (11)) used at ``t_k``.
    status : ndarray of int, shape (N,)
        The step's :class:`~stt_codegen.tube.parameters.Status` code.
    velocity : ndarray, shape (N, n), or None
        Second-order plant: the velocities ``x2(t_k)``, state units per second; ``None``
        for a first-order plant.
    r : ndarray, shape (N, n), or None
        Second-order plant: the cascade's virtual velocity ``r`` at ``t_k`` (the centre of
        the velocity tube, from the numpy oracle at the run's states), state units per
        second; ``None`` for a first-order plant or a controller without a second stage.
    tube : ndarray of int, shape (N,), or None
        A run with sensed obstacles (:func:`~.sensed.simulate_sensed`): the tube active at
        ``t_k`` (0: the design's, then each tube switched in); ``None`` otherwise.
    gamma_L, gamma_U : ndarray, shape (N, n), or None
        A run with sensed obstacles: the bounds of eq. (10) of the tube active at ``t_k``
        (its own time, the run's ``alpha``; from the numpy oracle), state units; ``None``
        otherwise (the design's tube, computed where needed).
    sensed_positions : ndarray, shape (N, J, m), or None
        A run with sensed obstacles: where each of the ``J`` obstacles of the world is at
        ``t_k``, on the ``m`` dimensions ``[sensing] dims``, state units (seen or not);
        ``None`` otherwise.
    sensed_radii : ndarray, shape (J,), or None
        Their radii, state units.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    alpha: np.ndarray
    status: np.ndarray
    velocity: np.ndarray | None = None
    r: np.ndarray | None = None
    tube: np.ndarray | None = None
    gamma_L: np.ndarray | None = None
    gamma_U: np.ndarray | None = None
    sensed_positions: np.ndarray | None = None
    sensed_radii: np.ndarray | None = None


@dataclass
class SimulationResult:
    """Outcome of a closed-loop run, judged by Definition 2.1 on ``[0, t_c]``.

    Attributes
    ----------
    spec, backend : str
        The spec's name and the backend that ran the controller.
    satisfied : bool
        ``reached`` and not ``collision`` and not ``left_state_space`` and not
        ``exceeded_velocity_bound`` (and every task of ``tasks`` met).
    reached : bool
        The state entered the target set no later than ``t_c``.
    reach_time : float or None
        First sampled instant in the target, seconds.
    prescribed_time : float
        ``t_c``, s.
    collision : bool
        The state met an obstacle on ``[0, t_c]`` (checked at every integration point).
    min_obstacle_clearance : float or None
        Smallest distance from the state to an obstacle on ``[0, t_c]`` (negative: depth
        inside it), state units; exact for boxes and balls, a lower bound for polytopes
        (distance to the nearest facet's plane). ``None`` without obstacles.
    left_state_space : bool
        The state left the state space on ``[0, t_c]``.
    stayed_in_tube : bool
        Every controller step on ``[0, horizon]`` reported the positions inside the tube
        (no ``OUTSIDE_TUBE`` or ``INVALID_INPUT`` status).
    max_abs_e : float or None
        ``max_k max_i |e_i(t_k)|`` over the controller steps on ``[0, horizon]``, the
        normalized error ``e = (2 x - (gamma_U + gamma_L)) / (gamma_U - gamma_L)`` of the
        state in the design's tube (eq. (10) at the step's ``alpha``): 1 is the tube's wall.
        ``None`` where the tube is empty at a step (then ``e`` is not defined).
    max_abs_u : list of float
        Peak ``|u_i|`` per input over the run, input units.
    steps : int
        Controller steps taken.
    control_effort : float
        ``integral of |u(t)|^2 dt`` over ``[0, horizon]`` (Euclidean norm; ``u`` held
        between samples, so exactly ``sum_k |u_k|^2 dt`` over the ``steps`` hold
        intervals), input units squared times seconds.
    clamped_steps : int
        Steps whose status was ``STATUS_INPUT_CLAMPED`` (the actuator clamp acted; only a
        design with ``[actuator]`` has it).
    tasks : list of TaskOutcome
        Each ``[[tasks]]`` entry judged on the run (:mod:`~.tasks`: met, when, margin);
        ``satisfied`` also needs every one met. Empty without tasks.
    trajectory : Trajectory or None
        The sampled signals.
    stayed_in_velocity_tube : bool or None
        Second-order plant: every step also had the velocity error inside its tube,
        ``|x2 - r| < rho2`` (status ``OK`` or ``INPUT_CLAMPED`` throughout); ``None`` for a
        first-order plant.
    max_abs_velocity : list of float or None
        Second-order plant: peak sampled ``|x2_i|``, state units per second; ``None`` for a
        first-order plant.
    exceeded_velocity_bound : bool
        Some sampled ``|x2_i|`` on ``[0, t_c]`` reached the spec's
        ``state_space.velocity_bound`` (then not ``satisfied``); ``False`` without a bound.
    contacts : int or None
        A MuJoCo plant (:class:`~stt_codegen.runtime.mujoco_plant.MujocoPlant`): the MuJoCo
        steps with a contact other than with a ground plane (then not ``satisfied``);
        ``None`` for the other plants.
    first_contact : list or None
        ``[t, geom1, geom2]`` of the first such contact (s, geom names), else ``None``.
    sensing : SensingRecord or None
        A run with sensed obstacles (:func:`~.sensed.simulate_sensed`): the replanning's
        events, the spans no certificate covered, the replanner's times and the
        envelope's violations (:class:`~.sensed.SensingRecord`); ``None`` otherwise.

    Examples
    --------
    Half a second of the closed loop: still in the tube, the target not yet reached (so
    Definition 2.1, judged on ``[0, t_c]``, is not satisfied):

    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> result = stt.simulate(design, backend="reference", horizon=0.5)
    >>> result.stayed_in_tube, result.collision, result.reach_time, result.satisfied
    (True, False, None, False)
    >>> result.trajectory.x.shape                # 0.5 s at 1 kHz, states x1, x2, x3
    (501, 3)
    >>> result                                   # doctest: +ELLIPSIS
    SimulationResult(spec='omnirobot-s1', backend='reference', satisfied=False, reached=False, stayed_in_tube=True, collision=False, steps=500, max_abs_e=0...)
    >>> print(result.summary())                  # doctest: +ELLIPSIS
    Run of omnirobot-s1 (backend reference, 500 steps): Definition 2.1 not satisfied
      target: not reached by t_c = 9 s
      tube:   stayed inside, max |e| = 0.5...
      safety: no collision, stayed in the state space, clearance 0.5... to the nearest obstacle
      input:  peak |u| = [0.61..., 7.0..., 0.038...], effort 2.8...
    """

    spec: str
    backend: str
    satisfied: bool
    reached: bool
    reach_time: float | None
    prescribed_time: float
    collision: bool
    min_obstacle_clearance: float | None
    left_state_space: bool
    stayed_in_tube: bool
    max_abs_e: float | None
    max_abs_u: list[float]
    steps: int
    control_effort: float = 0.0
    clamped_steps: int = 0
    trajectory: Trajectory | None = field(default=None, repr=False)
    tasks: list[TaskOutcome] = field(default_factory=list)
    stayed_in_velocity_tube: bool | None = None
    max_abs_velocity: list[float] | None = None
    exceeded_velocity_bound: bool = False
    contacts: int | None = None
    first_contact: list | None = None
    sensing: Any = None

    def summary_rows(self) -> Rows:
        """The rows of :meth:`summary`: ``(label, value)`` in words.

        Returns
        -------
        list of (str, str)
            The target, the tube, safety, the input, and where the run has them the
            velocity tube, the tasks and the MuJoCo contacts.
        """
        rows = [("target", f"reached at t = {self.reach_time:.4g} s (t_c = "
                           f"{self.prescribed_time:g} s)" if self.reached else
                           f"not reached by t_c = {self.prescribed_time:g} s")]
        error = "" if self.max_abs_e is None else f", max |e| = {self.max_abs_e:.3g}"
        rows.append(("tube", ("stayed inside" if self.stayed_in_tube else "LEFT it") + error))
        clearance = ("" if self.min_obstacle_clearance is None else
                     f", clearance {self.min_obstacle_clearance:.3g} to the nearest obstacle")
        rows.append(("safety", ("COLLISION" if self.collision else "no collision") + ", "
                     + ("LEFT the state space" if self.left_state_space
                        else "stayed in the state space") + clearance))
        peaks = ", ".join(f"{u:.4g}" for u in self.max_abs_u)
        clamped = f", clamped at {self.clamped_steps} steps" if self.clamped_steps else ""
        rows.append(("input", f"peak |u| = [{peaks}], effort {self.control_effort:.4g}"
                              f"{clamped}"))
        if self.max_abs_velocity is not None:
            rows.append(("velocity", ("stayed in its tube" if self.stayed_in_velocity_tube
                                      else "LEFT its tube") + ", peak |x2| = ["
                         + ", ".join(f"{v:.4g}" for v in self.max_abs_velocity) + "]"
                         + (", EXCEEDED the bound" if self.exceeded_velocity_bound else "")))
        if self.tasks:
            rows.append(("tasks", f"{sum(t.met for t in self.tasks)} of {len(self.tasks)} met"
                         + "".join(f"; {t.task} NOT met" for t in self.tasks if not t.met)))
        if self.contacts is not None:
            rows.append(("contacts", f"{self.contacts} MuJoCo steps in contact"))
        if self.sensing is not None:
            rows.append(("sensing", self.sensing.summary()))
        return rows

    def summary(self) -> str:
        """The run in a few lines: Definition 2.1's verdict, the target, the tube, safety,
        the input (and the velocity tube, the tasks, the contacts where the run has them).

        Returns
        -------
        str
            A title line, then one line a row of :meth:`summary_rows`.
        """
        return text(self._title(), self.summary_rows())

    def _title(self) -> str:
        return (f"Run of {self.spec} (backend {self.backend}, {self.steps} steps): "
                f"Definition 2.1 {'satisfied' if self.satisfied else 'not satisfied'}")

    def _repr_markdown_(self) -> str:
        """The summary as a Markdown table (Jupyter's rich display)."""
        return markdown(self._title(), self.summary_rows())

    def __repr__(self) -> str:
        error = "None" if self.max_abs_e is None else f"{self.max_abs_e:.3g}"
        return (f"SimulationResult(spec={self.spec!r}, backend={self.backend!r}, "
                f"satisfied={self.satisfied}, reached={self.reached}, "
                f"stayed_in_tube={self.stayed_in_tube}, collision={self.collision}, "
                f"steps={self.steps}, max_abs_e={error})")

    def to_json(self) -> dict:
        """The result as a JSON-ready dict (without the trajectory; ``tasks`` only for a
        spec with ``[[tasks]]``; the velocity fields only for a second-order plant, the
        contact fields only for a MuJoCo plant)."""
        data = asdict(self)
        data.pop("trajectory")
        if not data["tasks"]:
            data.pop("tasks")
        if data["contacts"] is None:
            data.pop("contacts")
            data.pop("first_contact")
        if data["sensing"] is None:
            data.pop("sensing")
        if data["max_abs_velocity"] is None:
            for key in ("stayed_in_velocity_tube", "max_abs_velocity",
                        "exceeded_velocity_bound"):
                data.pop(key)
        return data


def _seconds(horizon: object) -> float:
    """``horizon`` as a positive, finite float (a Python or numpy number)."""
    try:
        value = float(horizon)
    except (TypeError, ValueError):
        raise SpecError("horizon", f"must be a positive number of seconds, got {horizon!r}") \
            from None
    if not math.isfinite(value) or value <= 0:
        raise SpecError("horizon", f"must be a positive number of seconds, got {value!r}")
    return value


class RungeKutta:
    """A python-control plant integrated over each hold interval by the classical
    Runge-Kutta method, :data:`SUBSTEPS` steps (the stepping interface of
    :class:`~stt_codegen.runtime.mujoco_plant.MujocoPlant`)."""

    contact_count = None

    def __init__(self, plant: ct.NonlinearIOSystem) -> None:
        self.plant = plant
        self.x = None
        # ``plant.dynamics(t, x, u)`` without its per-call checks and copies (the states and
        # the input are flat float arrays here): the same update function, the same values
        update, params = plant.updfcn, dict(plant.params)
        self._rhs = lambda t, x, u: np.asarray(update(t, x, u, params)).reshape(-1)

    def reset(self, x0: np.ndarray) -> np.ndarray:
        self.x = np.array(x0, dtype=float)
        return self.x

    def advance(self, t: float, u: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        h = dt / SUBSTEPS
        x, f = self.x, self._rhs
        points = np.empty((SUBSTEPS, x.size))
        for m in range(SUBSTEPS):
            tm = t + m * h
            k1 = f(tm, x, u)
            k2 = f(tm + h / 2, x + h / 2 * k1, u)
            k3 = f(tm + h / 2, x + h / 2 * k2, u)
            k4 = f(tm + h, x + h * k3, u)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            points[m] = x
        self.x = x
        return points, t + h * np.arange(1, SUBSTEPS + 1)


def hold_period(stepper: RungeKutta | MujocoPlant, t: float, u_prev: np.ndarray, u: np.ndarray,
                dt: float, delay: float) -> tuple[np.ndarray, np.ndarray]:
    """Advance a plant over one sampling period ``[t, t + dt]``, the command computed at
    ``t`` acting after a computation delay.

    Parameters
    ----------
    stepper : RungeKutta or MujocoPlant
        The plant, at its state ``x(t)`` (its ``advance`` is called).
    t : float
        The sampling instant ``t_k``, s.
    u_prev : ndarray, shape (m,)
        The previous command ``u_{k-1}`` (zeros before the first), held on
        ``[t, t + delay)``; unused without a delay.
    u : ndarray, shape (m,)
        The command ``u_k`` computed at ``t``, held from ``t + delay`` to ``t + dt``.
    dt : float
        The sampling period, s.
    delay : float
        ``[controller] delay``, s, in ``[0, dt]``. 0: ``stepper.advance(t, u, dt)`` alone.

    Returns
    -------
    points : ndarray, shape (p, nstates)
        The plant's states at the dense points of the period, in time order (those of
        the delay's part first).
    times : ndarray, shape (p,)
        Their times, s.
    """
    if delay == 0.0:
        return stepper.advance(t, u, dt)
    early, early_t = stepper.advance(t, u_prev, delay)
    late, late_t = stepper.advance(t + delay, u, dt - delay)
    return np.vstack([early, late]), np.concatenate([early_t, late_t])


def sampling_offsets(jitter: float, steps: int, seed: int) -> np.ndarray:
    """The offsets ``o_k = s_k - k dt`` of a run's sampling instants under ``[controller]
    jitter``: uniform in ``[-jitter, jitter]``, ``o_0 = 0``, from their own seeded stream.

    Parameters
    ----------
    jitter : float
        ``[controller] jitter``, s; 0 gives zeros.
    steps : int
        The run's steps (``steps + 1`` samples).
    seed : int
        The run's seed.

    Returns
    -------
    ndarray, shape (steps + 1,)
        Seconds.

    Examples
    --------
    >>> offsets = sampling_offsets(1e-4, 3, 0)
    >>> float(offsets[0]), bool(abs(offsets).max() <= 1e-4)
    (0.0, True)
    """
    offsets = np.zeros(steps + 1)
    if jitter > 0.0:
        offsets[1:] = np.random.default_rng([seed, 0x6A17]).uniform(-jitter, jitter, steps)
    return offsets


def simulate(design: Design, *positional: object, backend: str | None = None,
             horizon: float | None = None, seed: int = 0,
             plant: ct.NonlinearIOSystem | None = None) -> SimulationResult:
    """Run the sampled controller of a design against its spec's plant; judge Definition 2.1.

    At each sampling instant ``t_k = k / rate_hz`` the controller reads ``x(t_k)`` and
    computes ``u_k`` by law (13), ``u = -k xi(x, t) epsilon(x, t)``, and the next
    ``alpha`` by the implicit step of the adaptive law (11); ``u_k`` is held until
    ``t_{k+1}`` while the plant (eq. (14), ``x_dot = u + w`` or the spec's linear plant,
    with the spec's seeded, bounded disturbance ``w``) is integrated by Runge-Kutta. The
    run starts at ``x(0)`` (``initial.state``) with ``alpha = 0``. For a spec with a
    second-order ``plant.model`` the same loop runs the cascade law (docs/second-order.md)
    with the design's second stage (:attr:`~stt_codegen.design.result.Design.second_stage`)
    on ``[x1; x2]``, from ``x2(0) = initial.velocity``.

    A spec with ``[sensing]`` runs here on its design's tube alone, among the spec's own
    obstacles: :func:`~.sensed.simulate_sensed` runs it among obstacles sensed at run time,
    replanning its tube (``stt-codegen simulate`` does, docs/sensing.md).

    With a spec's ``[controller] delay`` ``d > 0`` the command ``u_k`` computed from
    ``x(t_k)`` acts from ``t_k + d`` to ``t_{k+1} + d`` (the previous command acts on
    ``[t_k, t_k + d)``, the input is zero before ``u_0`` acts); the trajectory's ``u`` at
    ``t_k`` is still ``u_k``, and ``control_effort`` still sums the commands. With a
    ``jitter`` ``j > 0`` the state is read at ``s_k = t_k + o_k``, the offsets ``o_k``
    drawn uniformly in ``[-j, j]`` (``o_0 = 0``; seeded by ``seed``, apart from the
    disturbance's draw), the controller still called with the nominal ``t_k`` and ``dt``,
    and the command acting from ``s_k + d`` to ``s_{k+1} + d`` (:func:`sampling_offsets`);
    the trajectory's ``x`` at ``t_k`` is ``x(s_k)``. A MuJoCo plant steps a fixed timestep:
    it runs without jitter. With ``compensate_delay`` the controller is called with the
    state predicted over ``d`` from the command acting at the read
    (:func:`~stt_codegen.design.prediction.delay_predictor`).

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`: the tube and gain, and (``design.spec``) the
        task: sets, ``t_c``, plant and disturbance bound. The design is the one positional
        argument; the others are keywords.
    *positional
        Nothing: a second positional argument (``simulate(spec, design)``, or a backend
        name by position) is refused with a ``TypeError`` saying how to call.
    backend : str, optional
        Implementation of the controller step: ``"reference"`` (the numpy oracle),
        ``"casadi"`` (the CasADi model), ``"c"`` (the generated C, compiled with the
        system's C compiler) or ``"python"`` (the generated Python); see
        :func:`stt_codegen.runtime.backends.backend_names`. Default: the fastest,
        ``"c"`` where a C compiler is found, else ``"reference"``
        (:func:`~stt_codegen.runtime.backends.default_backend`); the result names it
        (``result.backend``).
    horizon : float, optional
        Simulated time, seconds (a Python or numpy number); default ``t_c``.
        Definition 2.1 is judged on ``[0, min(horizon, t_c)]``; a horizon shorter than
        ``t_c`` cannot satisfy it.
    seed : int, optional
        Seed of the disturbance ``w``: an integer (Python or numpy) in ``[0, 2**32)``.
    plant : control.NonlinearIOSystem, optional
        The plant to control instead of the spec's ``[plant]``, of the spec's order
        (``n`` states, or ``2 n`` for a second-order spec: positions then velocities;
        ``n`` inputs; the state as output); it must include its own disturbance.

    Returns
    -------
    SimulationResult
        ``satisfied`` (reach the target by ``t_c``, avoid every obstacle, stay in the
        state space), the reach time (s), the clearance (state units), ``max |u|`` per
        input, the control effort ``integral |u|^2 dt``, the steps the actuator clamp
        acted, and ``trajectory``: ``t`` (N,), ``x`` (N, n), ``u`` (N, n), ``alpha``
        (N, 2n), ``status`` (N,), with ``N = ceil(horizon * rate_hz) + 1`` (and, for a
        second-order plant, ``velocity`` (N, n) and ``r`` (N, n), with the velocity
        tube's verdict and the peak ``|x2|``).

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design` (a ``TubeDesign``
        or a ``Spec``, say): call :func:`stt_codegen.design_tube` first; or more than one
        positional argument.
    SpecError
        Unknown backend (field ``backend``), a ``plant`` without the spec's states and
        inputs (field ``plant``), a horizon that is not a positive number of
        seconds (``horizon``), a seed that is not an integer in ``[0, 2**32)``
        (``seed``), a run of more than
        :data:`~stt_codegen.design.samples.STEP_BUDGET` steps, or a MuJoCo plant with a
        ``delay`` that is not a whole number of its timesteps (``controller.delay``).
    ToolchainError
        Backend ``"c"``: no C compiler, or it failed.

    See Also
    --------
    stt_codegen.design_tube : the design to run.
    stt_codegen.plot_run : a figure of the run.
    stt_codegen.verify : the proof that the sampled loop stays in the tube.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> result = stt.simulate(design, backend="casadi")
    >>> result.satisfied, result.reach_time < design.spec.prescribed_time
    (True, True)
    >>> result.trajectory.x.shape                # 9 s at 1 kHz, states x1, x2, x3
    (9001, 3)
    >>> stt.simulate(design, backend="casadi", horizon=2.0).satisfied   # before t_c
    False
    """
    if positional:
        raise TypeError("simulate() takes the design alone, which carries its spec "
                        "(design.spec), and every other argument by keyword: "
                        "simulate(design, backend=..., horizon=..., seed=..., plant=...)")
    design = require_design(design, "simulate")
    stage = design.stage
    backend = default_backend() if backend is None else backend
    return run_closed_loop(design.spec, design.tube, backend=backend, horizon=horizon,
                           seed=seed, plant=plant, stage=stage)


def run_closed_loop(spec: Spec, tube: TubeDesign, *, backend: str = "reference",
                    horizon: float | None = None, seed: int = 0,
                    plant: ct.NonlinearIOSystem | None = None,
                    stage: SecondStage | LookAhead | None = None,
                    controller: Controller | None = None) -> SimulationResult:
    """The closed loop of :func:`simulate` for a spec and a tube given apart.

    For tubes that are not a design of their spec: the benchmarks' tracker runs on the
    spec's base parameters, the benchmark passes tubes between processes, and tests run
    altered tubes (another gain, another second stage). Not on the front door: there,
    :func:`simulate` takes a :class:`~stt_codegen.design.result.Design`, which pairs the
    tube with its spec. Parameters, result and errors are those of :func:`simulate`, with
    the spec and the tube (:class:`~stt_codegen.tube.parameters.TubeDesign`) in place of
    the design.

    Parameters
    ----------
    spec : Spec
        The task: sets, ``t_c``, plant (its order: one or two), disturbance bound.
    tube : TubeDesign
        The tube and gain to run.
    backend, horizon, seed, plant
        As :func:`simulate`.
    stage : SecondStage, optional
        The cascade's second stage, for a second-order spec (required unless
        ``controller`` is given); ``None`` for a first-order spec.
    controller : Controller, optional
        Another controller with the step of
        :func:`~stt_codegen.runtime.backends.make_controller` (a baseline judged by the
        same loop); ``backend`` is then only its label.

    Returns
    -------
    SimulationResult
        As :func:`simulate`.

    Raises
    ------
    SpecError
        As :func:`simulate`; a second stage given for a first-order spec, or missing for a
        second-order one (field ``stage``).
    """
    seed = check_seed(seed)
    t_c = spec.prescribed_time
    horizon = t_c if horizon is None else _seconds(horizon)
    steps = int(math.ceil(horizon * tube.rate_hz - 1e-9))
    check_step_budget(steps, horizon, tube.rate_hz)
    n = spec.dimension
    variant = variant_of(spec)
    if controller is None and variant_of_stage(stage) is not variant:
        raise SpecError("stage", f"a spec of the {variant.name} variant runs {variant.input_words}"
                                 f" with its own stage (Design.stage), not a "
                                 f"{type(stage).__name__}")
    x = initial_state(spec)
    if plant is None:
        plant = spec_plant(spec, seed)
    elif (getattr(plant, "nstates", None), getattr(plant, "ninputs", None)) != (x.size, n):
        raise SpecError("plant", f"must be a control.NonlinearIOSystem (or a plant with "
                                 f"advance(), as MujocoPlant) with {x.size} states "
                                 f"and {n} inputs for this spec{variant.state_words}")
    stepper = plant if hasattr(plant, "advance") else RungeKutta(plant)
    dt = 1.0 / tube.rate_hz
    if spec.delay > 0.0 and isinstance(stepper, MujocoPlant):
        stepper.check_delay(spec.delay, dt)
    if controller is None:
        controller = make_controller(backend, tube, stage)
    predict = delay_predictor(spec, tube, stage)      # with [controller] compensate_delay
    x = stepper.reset(x)
    lo, hi = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)

    ts = np.arange(steps + 1) * dt
    jitter = 0.0 if isinstance(stepper, MujocoPlant) else spec.jitter
    reads = ts + sampling_offsets(jitter, steps, seed)
    # each measurement interval's length: dt itself without jitter (not a difference of
    # rounded instants)
    lengths = np.diff(reads) if jitter > 0.0 else np.full(steps, dt)
    states = np.zeros((steps + 1, x.size))
    us = np.zeros((steps + 1, n))
    alphas = np.zeros((steps + 1, 2 * n))
    status = np.zeros(steps + 1, dtype=int)
    alpha, u_prev = np.zeros(2 * n), np.zeros(n)
    dense = [positions(spec, x[None])]
    dense_t = [np.zeros(1)]
    for k in range(steps + 1):
        t = ts[k]
        states[k], alphas[k] = x, alpha
        seen = x if predict is None else np.asarray(predict(x, u_prev), dtype=float).ravel()
        u, alpha_next, code = controller.step(seen, t, dt, alpha)
        us[k], status[k] = u, code
        if k == steps:
            break
        points, times = hold_period(stepper, reads[k], u_prev, u, lengths[k], spec.delay)
        u_prev = us[k]
        x = points[-1]
        dense.append(positions(spec, points))
        dense_t.append(times)
        alpha = alpha_next
    xs = positions(spec, states)
    path = np.vstack(dense)
    path_t = np.concatenate(dense_t)
    judged = path_t <= t_c + 1e-12
    within = path[judged]

    in_target = np.all((xs >= t_lo) & (xs <= t_hi), axis=1) & (ts <= t_c + 1e-12)
    reached = bool(in_target.any())
    reach_time = float(ts[int(np.argmax(in_target))]) if reached else None
    tasks = judge_tasks(spec, path_t, path)
    if spec.unsafe_sets or spec.moving_obstacles:
        # a moving obstacle where it is at each instant (inf while not active); one until a
        # task is gone once the run has met the task
        clearance = np.min([u.signed_clearance(within) for u in spec.unsafe_sets]
                           + [ob.signed_clearance(within, path_t[judged])
                              for ob in until_met(spec, tasks)], axis=0)
        min_clear = float(clearance.min())
        collision = bool(min_clear <= 0.0)
        min_clear = min_clear if math.isfinite(min_clear) else None
    else:
        min_clear, collision = None, False
    left = bool(np.any((within < lo) | (within > hi)))
    velocity = variant.entry("run_fields")(spec, tube, stage, ts, states, alphas, status, dt)
    contacts = stepper.contact_count
    satisfied = (reached and not collision and not left and horizon >= t_c
                 and not velocity["exceeded_velocity_bound"] and not contacts
                 and all(task.met for task in tasks))
    with reference.numpy_math():
        g_l, g_u, _, _ = reference.adaptive_tube(tube, ts, alphas)
    width = g_u - g_l
    max_abs_e = (float(np.max(np.abs(2.0 * xs - (g_u + g_l)) / width))
                 if np.all(width > 0.0) else None)
    outside = (status == Status.OUTSIDE_TUBE) | (status == Status.INVALID_INPUT)
    return SimulationResult(
        spec=spec.name, backend=backend, satisfied=satisfied, reached=reached,
        reach_time=reach_time, prescribed_time=t_c, collision=collision,
        min_obstacle_clearance=min_clear, left_state_space=left,
        stayed_in_tube=not bool(np.any(outside)),
        max_abs_e=max_abs_e,
        max_abs_u=[float(v) for v in np.abs(us).max(axis=0)], steps=steps,
        control_effort=float(np.sum(us[:steps] ** 2) * dt),
        clamped_steps=int(np.sum(status == Status.INPUT_CLAMPED)),
        trajectory=Trajectory(ts, xs, us, alphas, status, velocity.pop("velocity"),
                              velocity.pop("r")),
        tasks=tasks, contacts=contacts,
        first_contact=(None if getattr(stepper, "first_contact", None) is None
                       else list(stepper.first_contact)), **velocity)


def no_velocity_fields(spec: Spec, tube: TubeDesign, stage: LookAhead | None,
                       ts: np.ndarray, states: np.ndarray, alphas: np.ndarray,
                       status: np.ndarray, dt: float) -> dict:
    """The second-order fields of a run of a first-order plant or a base (role
    ``run_fields`` of :mod:`~stt_codegen.spec.variants`): none.

    Parameters
    ----------
    spec : Spec
    tube : TubeDesign
    stage : LookAhead or None
    ts : ndarray, shape (N,)
    states : ndarray, shape (N, m)
    alphas : ndarray, shape (N, 2 n)
    status : ndarray, shape (N,)
    dt : float

    Returns
    -------
    dict
        ``velocity``, ``r``, ``stayed_in_velocity_tube``, ``max_abs_velocity``: ``None``;
        ``exceeded_velocity_bound``: ``False``.
    """
    return {"velocity": None, "r": None, "stayed_in_velocity_tube": None,
            "max_abs_velocity": None, "exceeded_velocity_bound": False}


def no_velocity_reference(tube: TubeDesign, stage: LookAhead | None, states: np.ndarray,
                          ts: np.ndarray, dt: float, alphas: np.ndarray) -> None:
    """The velocity reference ``r`` of a run without the cascade's stage (role
    ``velocity_reference`` of the stage's variant, a custom controller's run included):
    none.

    Parameters
    ----------
    tube : TubeDesign
    stage : LookAhead or None
    states : ndarray, shape (N, m)
    ts : ndarray, shape (N,)
    dt : float
    alphas : ndarray, shape (N, 2 n)
    """
    return None


def cascade_velocity_reference(tube: TubeDesign, stage: SecondStage, states: np.ndarray,
                               ts: np.ndarray, dt: float, alphas: np.ndarray) -> np.ndarray:
    """The cascade's velocity reference ``r`` along a run, by the oracle (role
    ``velocity_reference``).

    Parameters
    ----------
    tube : TubeDesign
    stage : SecondStage
    states : ndarray, shape (N, 2 n)
    ts : ndarray, shape (N,)
        Sampling times, s.
    dt : float
        Sampling period, s.
    alphas : ndarray, shape (N, 2 n)

    Returns
    -------
    ndarray, shape (N, n)
    """
    with reference.numpy_math():
        return cascade_reference.cascade_step(tube, stage, states, ts, dt, alphas)[2]


def velocity_fields(spec: Spec, tube: TubeDesign, stage: SecondStage | None,
                    ts: np.ndarray, states: np.ndarray, alphas: np.ndarray,
                    status: np.ndarray, dt: float) -> dict:
    """The second-order fields of a run (velocities, ``r``, the velocity tube's verdict,
    the velocity bound): the cascade's role ``run_fields``.

    Parameters
    ----------
    spec : Spec
    tube : TubeDesign
    stage : SecondStage or None
        ``None`` for a custom controller's run (``r`` is then ``None``).
    ts : ndarray, shape (N,)
    states : ndarray, shape (N, 2 n)
    alphas : ndarray, shape (N, 2 n)
    status : ndarray, shape (N,)
    dt : float

    Returns
    -------
    dict
        ``velocity``, ``r``, ``stayed_in_velocity_tube``, ``max_abs_velocity``,
        ``exceeded_velocity_bound``.
    """
    n = spec.dimension
    r = variant_of_stage(stage).entry("velocity_reference")(tube, stage, states, ts, dt,
                                                            alphas)
    x1, x2 = states[:, :n], states[:, n:]
    bound = spec.second_order.velocity_bound
    exceeded = (bound is not None
                and bool(np.any(np.abs(x2[ts <= spec.prescribed_time + 1e-12])
                                >= np.array(bound))))
    inside = (status == Status.OK) | (status == Status.INPUT_CLAMPED)
    return {"velocity": x2, "r": r, "stayed_in_velocity_tube": bool(np.all(inside)),
            "max_abs_velocity": [float(v) for v in np.abs(x2).max(axis=0)],
            "exceeded_velocity_bound": exceeded}
