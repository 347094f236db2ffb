"""Closed loop of the cascade law on a second-order plant, judged by Definition 2.1.

At each sampling instant ``t_k = k dt`` the controller (:mod:`.cascade_controllers`) reads
``x1(t_k)``, ``x2(t_k)`` and returns ``u_k`` and the next ``alpha``; ``u_k`` is held while
the plant (:mod:`.second_order_plants`, printed to Python by the emitter, with a seeded,
bounded disturbance :class:`~stt_codegen.runtime.plants.Disturbance` on ``x2_dot``) is
integrated by the classical Runge-Kutta method, :data:`SUBSTEPS` steps per period.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ..codegen.emit import python_function
from ..design.result import Design
from ..design.samples import check_step_budget
from ..errors import SpecError
from ..spec.loader import Spec
from ..tube import reference
from ..tube.parameters import TubeDesign
from ..tube.parameters import Status
from ..tube.second_stage import SecondStage
from .cascade_controllers import CascadeController
from .plants import Disturbance
from .second_order_plants import model_info, second_order_rhs

__all__ = ["CascadeResult", "CascadeTrajectory", "SUBSTEPS", "simulate_cascade",
           "simulate_second_order"]

#: Runge-Kutta steps per sampling period.
SUBSTEPS = 2


@dataclass
class CascadeTrajectory:
    """Sampled signals of the cascade's closed loop, ``N`` instants.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sampling instants, s.
    x1 : ndarray, shape (N, n)
        Positions, state units.
    x2 : ndarray, shape (N, n)
        Velocities, state units per second.
    u : ndarray, shape (N, n)
        Inputs of the cascade law, held over each sampling interval, input units.
    r : ndarray, shape (N, n)
        The velocity reference of the first stage (the centre of the velocity tube), state
        units per second.
    alpha : ndarray, shape (N, 2n)
        The adaptive law's ``alpha`` (eq. (11)) at each instant.
    status : ndarray of int, shape (N,)
        The step's status code (``Status.OK``: inside both tubes).
    """

    t: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    u: np.ndarray
    r: np.ndarray
    alpha: np.ndarray
    status: np.ndarray


@dataclass
class CascadeResult:
    """Outcome of a second-order closed loop (Definition 2.1 on the positions ``x1``).

    Attributes
    ----------
    spec, backend, model : str
        The spec's name, the backend and the second-order plant model.
    satisfied : bool
        ``reached`` and not ``collision`` and not ``left_state_space``.
    reached : bool
        ``x1`` entered the target no later than ``t_c``.
    reach_time : float or None
        First sampled instant with ``x1`` in the target, seconds.
    collision : bool
        ``x1`` met an obstacle on ``[0, t_c]``.
    min_obstacle_clearance : float or None
        Smallest signed distance of ``x1`` to an obstacle over ``[0, t_c]`` (every
        integration point), state units.
    left_state_space : bool
        ``x1`` left the state space on ``[0, t_c]``.
    stayed_in_tube : bool
        Every step had ``x1`` strictly inside the position tube.
    stayed_in_velocity_tube : bool
        Every step had ``|x2 - r| < rho2`` too (status ``Status.OK`` throughout).
    max_abs_e : float
        ``max |e1|``, the normalized position error in the tube (1: the wall).
    max_abs_u : list of float
        Peak ``|u_i|``, input units.
    max_abs_x2 : list of float
        Peak ``|x2_i|``, velocity units.
    steps : int
        Controller steps taken.
    exceeded_velocity_bound : bool
        Some sampled ``|x2_i|`` reached the spec's ``state_space.velocity_bound`` (then
        not ``satisfied``); ``False`` without a bound.
    prescribed_time : float
        ``t_c``, s.
    trajectory : CascadeTrajectory or None
        The sampled signals.
    tasks : list
        Always empty (a second-order spec takes no ``[[tasks]]``).
    """

    spec: str
    backend: str
    model: str
    satisfied: bool
    reached: bool
    reach_time: float | None
    prescribed_time: float
    collision: bool
    min_obstacle_clearance: float | None
    left_state_space: bool
    stayed_in_tube: bool
    stayed_in_velocity_tube: bool
    max_abs_e: float
    max_abs_u: list[float]
    max_abs_x2: list[float]
    steps: int
    exceeded_velocity_bound: bool = False
    trajectory: CascadeTrajectory | None = field(default=None, repr=False)
    #: As :attr:`SimulationResult.tasks`; always empty: a second-order spec takes no
    #: ``[[tasks]]`` (the loader refuses them).
    tasks: list = field(default_factory=list)

    def to_json(self) -> dict:
        """The result as a JSON-ready dict (without the trajectory and the empty tasks)."""
        data = asdict(self)
        data.pop("trajectory")
        data.pop("tasks")
        return data


def simulate_second_order(spec: Spec, tube: TubeDesign, stage: SecondStage, *,
                          model: str = "double-integrator", params=None,
                          initial_velocity=None, disturbance_amplitude: float | None = None,
                          backend: str = "reference", seed: int = 0,
                          horizon: float | None = None,
                          velocity_bound=None, controller=None) -> CascadeResult:
    """Run the sampled cascade on a second-order plant; judge Definition 2.1 on ``x1``.

    Parameters
    ----------
    spec : Spec
        The task (sets, ``t_c``); its positions are ``x1``.
    tube : TubeDesign
        The position tube designed for ``spec``.
    stage : SecondStage
        The second stage (e.g. :func:`stt_codegen.design.cascade_gain.derived_second_stage`).
    model : str
        A :data:`~stt_codegen.runtime.second_order_plants.SECOND_ORDER_MODELS` entry.
    params : sequence of float, optional
        The model's parameters (default its nominal ones).
    initial_velocity : sequence of float, optional
        ``x2(0)``, default 0.
    disturbance_amplitude : float, optional
        Bound on ``|w_i|`` added to ``x2_dot``, velocity units per second; default the
        spec's ``disturbance_amplitude``.
    backend : str
        ``"reference"``, ``"casadi"``, ``"python"`` or ``"c"``.
    seed : int
        Seed of the disturbance.
    horizon : float, optional
        Seconds, default ``t_c``.
    velocity_bound : sequence of float, optional
        ``|x2_i|`` must stay below it (else not satisfied).
    controller : object, optional
        Another controller with the step of
        :class:`~stt_codegen.runtime.cascade_controllers.CascadeController` (a baseline
        judged by the same loop); ``backend`` is then only its label.

    Returns
    -------
    CascadeResult
        Definition 2.1 judged on ``x1``, both tubes' status, peaks of ``|u|`` and ``|x2|``, and
        the trajectory.

    Raises
    ------
    SpecError
        Unknown backend or model (fields ``backend``, ``plant.model``), wrong lengths
        (``params``, ``initial.velocity``), a bad horizon or seed, too many steps.
    """
    n = spec.dimension
    try:
        info = model_info(model, n)
    except ValueError as exc:
        raise SpecError("plant.model", str(exc)) from None
    params = np.array(info.nominal if params is None else params, dtype=float)
    if params.shape != (len(info.parameters),):
        raise SpecError("params", f"model {model!r} takes {len(info.parameters)} parameters "
                                  f"({', '.join(info.parameters)})")
    x2 = np.zeros(n) if initial_velocity is None else np.array(initial_velocity, dtype=float)
    if x2.shape != (n,) or not np.all(np.isfinite(x2)):
        raise SpecError("initial.velocity", f"needs {n} finite entries")
    t_c = spec.prescribed_time
    horizon = t_c if horizon is None else float(horizon)
    if not math.isfinite(horizon) or horizon <= 0:
        raise SpecError("horizon", f"must be a positive number of seconds, got {horizon!r}")
    steps = int(math.ceil(horizon * tube.rate_hz - 1e-9))
    check_step_budget(steps, horizon, tube.rate_hz)
    amplitude = (spec.disturbance_amplitude if disturbance_amplitude is None
                 else float(disturbance_amplitude))
    w = Disturbance(n, amplitude, seed)
    if controller is None:
        controller = CascadeController(backend, tube, stage)
    rhs_fn = python_function(second_order_rhs(model, n))
    p_list = params.tolist()

    def rhs(t, s, u):
        d1, d2 = rhs_fn(s[:n].tolist(), s[n:].tolist(), u.tolist(), w(t).tolist(), p_list)
        return np.concatenate([d1, d2])

    dt = 1.0 / tube.rate_hz
    ts = np.arange(steps + 1) * dt
    x1s, x2s, us, rs = (np.zeros((steps + 1, n)) for _ in range(4))
    alphas = np.zeros((steps + 1, 2 * n))
    status = np.zeros(steps + 1, dtype=int)
    s = np.concatenate([np.array(spec.initial_state, dtype=float), x2])
    alpha = np.zeros(2 * n)
    dense = [s[None, :n]]
    dense_t = [np.zeros(1)]
    h = dt / SUBSTEPS
    for k in range(steps + 1):
        t = ts[k]
        x1s[k], x2s[k], alphas[k] = s[:n], s[n:], alpha
        u, alpha_next, r, code = controller.step(s[:n], s[n:], t, dt, alpha)
        us[k], rs[k], status[k] = u, r, code
        if k == steps:
            break
        points = []
        for m in range(SUBSTEPS):
            tm = t + m * h
            k1 = rhs(tm, s, u)
            k2 = rhs(tm + h / 2, s + h / 2 * k1, u)
            k3 = rhs(tm + h / 2, s + h / 2 * k2, u)
            k4 = rhs(tm + h, s + h * k3, u)
            s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            points.append(s[:n])
        dense.append(np.array(points))
        dense_t.append(t + h * np.arange(1, SUBSTEPS + 1))
        alpha = alpha_next
    path, path_t = np.vstack(dense), np.concatenate(dense_t)
    within = path[path_t <= t_c + 1e-12]
    lo, hi = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    t_lo, t_hi = np.array(spec.target_set.lower), np.array(spec.target_set.upper)
    in_target = np.all((x1s >= t_lo) & (x1s <= t_hi), axis=1) & (ts <= t_c + 1e-12)
    reached = bool(in_target.any())
    if spec.unsafe_sets:
        min_clear = float(np.min([o.signed_clearance(within) for o in spec.unsafe_sets]))
        collision = min_clear <= 0.0
    else:
        min_clear, collision = None, False
    left = bool(np.any((within < lo) | (within > hi)))
    with reference.numpy_math():
        g_l, g_u, _, _ = reference.adaptive_tube(tube, ts, alphas)
    max_e = float(np.max(np.abs(2.0 * x1s - (g_u + g_l)) / (g_u - g_l)))
    fast = (velocity_bound is not None
            and bool(np.any(np.abs(x2s[ts <= t_c + 1e-12]) >= np.array(velocity_bound))))
    return CascadeResult(
        spec=spec.name, backend=backend, model=model,
        satisfied=reached and not collision and not left and not fast and horizon >= t_c,
        reached=reached, reach_time=float(ts[int(np.argmax(in_target))]) if reached else None,
        prescribed_time=t_c, collision=collision, min_obstacle_clearance=min_clear,
        left_state_space=left, stayed_in_tube=bool(np.all(status != 1) and np.all(status != 2)),
        stayed_in_velocity_tube=bool(np.all(status == Status.OK)), max_abs_e=max_e,
        max_abs_u=[float(v) for v in np.abs(us).max(axis=0)],
        max_abs_x2=[float(v) for v in np.abs(x2s).max(axis=0)], steps=steps,
        exceeded_velocity_bound=fast,
        trajectory=CascadeTrajectory(ts, x1s, x2s, us, rs, alphas, status))


def simulate_cascade(design: Design, backend: str = "reference", horizon: float | None = None,
                     seed: int = 0) -> CascadeResult:
    """The closed loop of a design whose spec has a second-order ``plant.model``: the default second
    stage (:attr:`stt_codegen.design.result.Design.second_stage`) on the spec's model,
    parameters, initial velocity and velocity bound.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`, its spec with a second-order ``plant.model``.
    backend, horizon, seed
        As :func:`simulate_second_order`.

    Returns
    -------
    CascadeResult
        As :func:`simulate_second_order`.

    Raises
    ------
    SpecError
        As :func:`simulate_second_order`; a first-order spec (field ``plant.model``).
    """
    stage, _ = design.second_stage
    order = design.spec.second_order
    return simulate_second_order(design.spec, design.tube, stage, model=order.model,
                                 params=order.parameters,
                                 initial_velocity=order.initial_velocity, backend=backend,
                                 seed=seed, horizon=horizon,
                                 velocity_bound=order.velocity_bound)
