"""Plant models for closed-loop simulation, as python-control ``NonlinearIOSystem``s.

The controller never sees these: they only stand in for the unknown system (1),
``x_dot = f(x) + g(x) u + w``, in simulation. The named plants' ``g(x) u`` is the one
definition in :mod:`.dynamics` (and so is the spec's ``linear`` plant), printed to Python
by the emitter (the same Functions are printed to C for the embedded closed loop, and
``g(x)`` to SymPy for Assumption 2).
"""

from __future__ import annotations

import operator
from typing import Any

import control as ct
import numpy as np

from ..codegen.emit import python_function
from ..errors import SpecError
from ..spec.differential_drive import DifferentialDrive
from ..spec.loader import LinearPlant
from ..spec.plants import PLANTS, MissingPlantBehaviour, dimension_mismatch, model_behaviour
from ..spec.variants import variant_of
from .differential_drive import base_rhs
from .dynamics import linear_rhs, plant_rhs
from .mujoco_plant import DriveMujocoPlant, MujocoPlant
from .second_order_plants import model_info, second_order_rhs

__all__ = ["Disturbance", "cascade_spec_plant", "check_seed", "differential_drive_plant",
           "drive_mujoco_plant", "drive_spec_plant", "first_order_spec_plant",
           "joint_mujoco_plant", "make_plant", "second_order_plant", "spec_plant"]

#: Number of sinusoids summed in each disturbance component.
DISTURBANCE_TERMS = 3

#: Disturbance seeds are integers in ``[0, SEED_LIMIT)``: 32 bits, the range numpy's legacy
#: ``RandomState`` accepts too, so a seed can be passed to any generator.
SEED_LIMIT = 2**32


def check_seed(seed: object) -> int:
    """``seed`` as an ``int``, if it is a disturbance seed: an integer (Python or numpy) in
    ``[0, 2**32)``.

    Parameters
    ----------
    seed : object
        The seed to check.

    Returns
    -------
    int
        ``seed`` as a Python ``int``.

    Raises
    ------
    SpecError
        Field ``seed``: not an integer (a float, a bool, a string...), negative, or too
        large.
    """
    try:
        value = None if isinstance(seed, bool) else operator.index(seed)
    except TypeError:
        value = None
    if value is None or not 0 <= value < SEED_LIMIT:
        raise SpecError("seed", f"must be an integer in [0, 2**32), got {seed!r}")
    return value


class Disturbance:
    """A bounded, smooth, deterministic disturbance ``w(t)``, seeded.

    Each component is ``A sum_k c_k sin(omega_k t + phi_k)`` with ``sum_k c_k = 1``,
    so ``|w_i(t)| <= A`` for all ``t``; frequencies are drawn in [0.5, 5] rad/s.

    Parameters
    ----------
    dimension : int
        ``n``.
    amplitude : float
        ``A >= 0``, the bound on every ``|w_i|``, state units per second.
    seed : int
        Seed of ``numpy.random.default_rng``, in ``[0, 2**32)`` (:func:`check_seed`).

    Raises
    ------
    SpecError
        Field ``seed``: not an integer in ``[0, 2**32)``.
    """

    def __init__(self, dimension: int, amplitude: float, seed: int = 0) -> None:
        rng = np.random.default_rng(check_seed(seed))
        weights = rng.uniform(0.2, 1.0, (dimension, DISTURBANCE_TERMS))
        self.amplitude = float(amplitude)
        self.weights = weights / weights.sum(axis=1, keepdims=True)
        self.frequencies = rng.uniform(0.5, 5.0, (dimension, DISTURBANCE_TERMS))
        self.phases = rng.uniform(0.0, 2.0 * np.pi, (dimension, DISTURBANCE_TERMS))
        self._last: tuple[float, np.ndarray] | None = None

    def __call__(self, t: float) -> np.ndarray:
        """``w(t)``, shape (n,), read-only; the last instant's value is kept, as Runge-Kutta
        asks for each midpoint twice."""
        if self._last is not None and self._last[0] == t:
            return self._last[1]
        w = self.amplitude * (self.weights * np.sin(self.frequencies * t + self.phases)
                              ).sum(axis=1)
        w.flags.writeable = False
        self._last = (t, w)
        return w


def omnidirectional_robot(disturbance: Disturbance) -> ct.NonlinearIOSystem:
    """The omnidirectional robot of eq. (14): ``x_dot = R(x3) u + w(t)``.

    States ``[x1, x2, x3]`` (position in m, heading in rad); inputs ``[v1, v2, omega]``
    in the robot frame (m/s, rad/s); outputs the state. ``R(x3) u`` is
    :func:`.dynamics.plant_rhs` (``"omnidirectional"``).
    """
    robot = PLANTS["omnidirectional"]
    states = [f"x{i + 1}" for i in range(robot.states)]
    return _plant(plant_rhs(robot.name, robot.states), disturbance, inputs=list(robot.inputs),
                  states=states, outputs=states, name="omnidirectional_robot")


def single_integrator(dimension: int, disturbance: Disturbance) -> ct.NonlinearIOSystem:
    """``x_dot = u + w(t)`` in ``dimension`` states; outputs the state
    (:func:`.dynamics.plant_rhs`, ``"single-integrator"``)."""
    return _plant(plant_rhs("single-integrator", dimension), disturbance, inputs=dimension,
                        states=dimension, outputs=dimension, name="single_integrator")


def _plant(function, disturbance: Disturbance, **io) -> ct.NonlinearIOSystem:
    """A python-control plant ``x_dot = function(x, u) + w(t)``, ``function`` a
    :mod:`.dynamics` Function printed to Python."""
    g_u = python_function(function)

    def rhs(t, x, u, params):
        return np.array(g_u(x, u)[0]) + disturbance(t)

    return ct.nlsys(rhs, None, **io)


def linear_plant(a, g, c, disturbance: Disturbance) -> ct.NonlinearIOSystem:
    """``x_dot = a x + c + g u + w(t)``: the spec's ``model = "linear"``; outputs the state.

    ``a x + c + g u`` is :func:`.dynamics.linear_rhs`, printed to Python.

    Parameters
    ----------
    a, g : array_like, shape (n, n)
        Drift and input matrices.
    c : array_like, shape (n,)
        Constant drift, state units per second.
    disturbance : Disturbance
    """
    n = np.asarray(c).size
    return _plant(linear_rhs(a, g, c), disturbance, inputs=n, states=n, outputs=n,
                  name="linear_plant")


def make_plant(model: str, dimension: int, amplitude: float, seed: int = 0,
               linear: LinearPlant | None = None) -> ct.NonlinearIOSystem:
    """The plant named in a spec's ``[plant]`` table.

    Parameters
    ----------
    model : str
        One of :data:`stt_codegen.spec.plants.PLANT_MODELS`.
    dimension : int
        State dimension ``n``.
    amplitude : float
        Bound on every ``|w_i|`` (:class:`Disturbance`), state units per second.
    seed : int
        Seed of the disturbance, in ``[0, 2**32)``.
    linear : LinearPlant, optional
        The matrices of the ``linear`` model (default ``a = 0``, ``g = I``, ``c = 0``).

    Returns
    -------
    control.NonlinearIOSystem
        ``x_dot = f(x, u) + w(t)`` with ``n`` states, inputs and outputs (the state as
        output), ``w`` the seeded :class:`Disturbance`.

    Raises
    ------
    SpecError
        Unknown model, or a dimension the model does not have.
    """
    disturbance = Disturbance(dimension, amplitude, seed)
    try:
        build = model_behaviour(SIMULATION_PLANTS, model, "simulation plant")
    except MissingPlantBehaviour:
        raise SpecError("plant.model", f"unknown model {model!r}") from None
    if dimension_mismatch(model, dimension):
        raise SpecError("plant.model", dimension_mismatch(model, dimension))
    return build(dimension, disturbance, linear)


def _spec_linear_plant(dimension: int, disturbance: Disturbance,
                       linear: LinearPlant | None) -> ct.NonlinearIOSystem:
    """The ``linear`` model with the spec's matrices (default ``a = 0``, ``g = I``,
    ``c = 0``)."""
    if linear is None:
        eye = np.eye(dimension)
        return linear_plant(0 * eye, eye, np.zeros(dimension), disturbance)
    if len(linear.c) != dimension:
        raise SpecError("plant.c", f"has {len(linear.c)} entries for {dimension} states")
    return linear_plant(linear.a, linear.g, linear.c, disturbance)


#: The simulated plant of each first-order model: ``(n, disturbance, linear) -> system``.
def _simulator_only(n: int, disturbance: Disturbance, linear) -> ct.NonlinearIOSystem:
    raise SpecError("plant.model", "a MuJoCo plant is built from the spec's [plant] "
                                   "(mjcf, joints, actuators): use spec_plant(spec)")


def _base_only(n: int, disturbance: Disturbance, linear) -> ct.NonlinearIOSystem:
    raise SpecError("plant.model", "a differential-drive base is built from the spec's "
                                   "[plant] parameters: use spec_plant(spec) or "
                                   "differential_drive_plant(spec.drive)")


SIMULATION_PLANTS = {
    "omnidirectional": lambda n, disturbance, _linear: omnidirectional_robot(disturbance),
    "single-integrator": lambda n, disturbance, _linear: single_integrator(n, disturbance),
    "linear": _spec_linear_plant,
    "mujoco": _simulator_only,
    "differential-drive": _base_only,
}


def second_order_plant(model: str, dimension: int, parameters, amplitude: float,
                       seed: int = 0) -> ct.NonlinearIOSystem:
    """A second-order plant ``x1_dot = x2``, ``x2_dot = f + g u + w(t)``, as one system.

    Its state is ``[x1; x2]`` (``2 n`` states: positions, then velocities); ``f + g u`` is
    :func:`.second_order_plants.second_order_rhs`, printed to Python, and the seeded
    disturbance ``w`` acts on ``x2_dot``.

    Parameters
    ----------
    model : str
        One of :data:`stt_codegen.spec.plants.SECOND_ORDER_MODELS`.
    dimension : int
        Positions ``n`` (= velocities = inputs).
    parameters : sequence of float
        The model's physical parameters (:data:`stt_codegen.spec.plants.SECOND_ORDER_PLANTS`).
    amplitude : float
        Bound on every ``|w_i|``, velocity units per second.
    seed : int
        Seed of the disturbance, in ``[0, 2**32)``.

    Returns
    -------
    control.NonlinearIOSystem
        ``2 n`` states, ``n`` inputs, the state as output.

    Raises
    ------
    SpecError
        Unknown model or a dimension it does not have (field ``plant.model``), or a
        parameter count it does not take (``plant.parameters``).
    """
    try:
        info = model_info(model, dimension)
    except ValueError as exc:
        raise SpecError("plant.model", str(exc)) from None
    params = [float(v) for v in parameters]
    if len(params) != len(info.parameters):
        raise SpecError("plant.parameters", f"model {model!r} takes {len(info.parameters)} "
                                            f"parameters ({', '.join(info.parameters)})")
    rhs_fn = python_function(second_order_rhs(model, dimension))
    disturbance = Disturbance(dimension, amplitude, seed)
    n = dimension

    def rhs(t, s, u, _params):
        d1, d2 = rhs_fn(s[:n].tolist(), s[n:].tolist(), np.asarray(u).tolist(),
                        disturbance(t).tolist(), params)
        return np.concatenate([d1, d2])

    states = [f"x1_{i + 1}" for i in range(n)] + [f"x2_{i + 1}" for i in range(n)]
    return ct.nlsys(rhs, None, inputs=n, states=states, outputs=states,
                    name=f"second_order_{model.replace('-', '_')}")


def differential_drive_plant(drive: DifferentialDrive, seed: int = 0) -> ct.NonlinearIOSystem:
    """The simulated base of a spec, as a python-control system.

    Parameters
    ----------
    drive : DifferentialDrive
        The base: its track width, wheel errors and slip amplitudes.
    seed : int
        Seed of the slip, in ``[0, 2**32)``.

    Returns
    -------
    control.NonlinearIOSystem
        States ``x``, ``y``, ``theta`` (m, m, rad); inputs ``v``, ``omega``; the state as
        output.

    Raises
    ------
    SpecError
        Field ``seed``: not an integer in ``[0, 2**32)``.
    """
    rhs_fn = python_function(base_rhs())
    slip = Disturbance(3, 1.0, seed)
    amplitude = np.asarray(drive.slip, dtype=float)
    error, width = list(drive.wheel_radius_error), drive.track_width

    def rhs(t, x, u, _params):
        w = (amplitude * slip(t)).tolist()
        return np.array(rhs_fn(np.asarray(x).tolist(), np.asarray(u).tolist(), error, [width],
                               w)[0], dtype=float)

    states = ["x", "y", "theta"]
    return ct.nlsys(rhs, None, inputs=["v", "omega"], states=states, outputs=states,
                    name="differential_drive")


def spec_plant(spec, seed: int = 0) -> Any:
    """The plant a spec names (``[plant]``), of the spec's order.

    Parameters
    ----------
    spec : Spec
        Its ``plant.model`` (and, for a second-order model, ``plant.parameters``) and
        ``disturbance_amplitude``.
    seed : int
        Seed of the disturbance, in ``[0, 2**32)``.

    Returns
    -------
    control.NonlinearIOSystem or MujocoPlant
        :func:`make_plant` (``n`` states), :func:`second_order_plant` (``2 n`` states)
        or :func:`differential_drive_plant` (3 states);
        for ``plant.model = "mujoco"`` the :class:`~.mujoco_plant.MujocoPlant` of
        ``spec.mujoco`` (no disturbance is added: MuJoCo's dynamics are the plant's).

    Raises
    ------
    SpecError
        As :func:`make_plant` and :func:`second_order_plant`.
    """
    variant = variant_of(spec)
    if spec.mujoco is not None:      # [plant] mjcf: MuJoCo steps the plant
        return variant.entry("mujoco_plant")(spec)
    return variant.entry("plant")(spec, seed)


def first_order_spec_plant(spec, seed: int = 0) -> ct.NonlinearIOSystem:
    """The first-order plant of a spec (role ``plant`` of
    :mod:`~stt_codegen.spec.variants`): :func:`make_plant` of its model.

    Parameters
    ----------
    spec : Spec
    seed : int
        Seed of the disturbance.

    Returns
    -------
    control.NonlinearIOSystem
        ``n`` states.
    """
    return make_plant(spec.plant_model, spec.dimension, spec.disturbance_amplitude, seed,
                      spec.linear_plant)


def cascade_spec_plant(spec, seed: int = 0) -> ct.NonlinearIOSystem:
    """The second-order plant of a spec (role ``plant``): :func:`second_order_plant`.

    Parameters
    ----------
    spec : Spec
    seed : int
        Seed of the disturbance.

    Returns
    -------
    control.NonlinearIOSystem
        ``2 n`` states, positions then velocities.
    """
    return second_order_plant(spec.second_order.model, spec.dimension,
                              spec.second_order.parameters, spec.disturbance_amplitude, seed)


def drive_spec_plant(spec, seed: int = 0) -> ct.NonlinearIOSystem:
    """The differential-drive base of a spec (role ``plant``): its own kinematics,
    :func:`differential_drive_plant`.

    Parameters
    ----------
    spec : Spec
    seed : int
        Seed of the slip.

    Returns
    -------
    control.NonlinearIOSystem
        3 states ``(x, y, theta)``.
    """
    return differential_drive_plant(spec.drive, seed)


def joint_mujoco_plant(spec) -> MujocoPlant:
    """A plant of joints stepped by MuJoCo (role ``mujoco_plant``): the state's layout is
    the variant's (``state_blocks``: positions, or positions then velocities).

    Parameters
    ----------
    spec : Spec
        With ``spec.mujoco``.

    Returns
    -------
    MujocoPlant
    """
    m = spec.mujoco
    return MujocoPlant(m.path, m.joints, m.actuators, variant_of(spec).state_blocks,
                       m.timestep)


def drive_mujoco_plant(spec) -> DriveMujocoPlant:
    """A differential-drive base stepped by MuJoCo (role ``mujoco_plant``): its driver
    turns ``(v, omega)`` into wheel speeds.

    Parameters
    ----------
    spec : Spec
        With ``spec.mujoco`` and ``spec.drive``.

    Returns
    -------
    DriveMujocoPlant
    """
    m = spec.mujoco
    return DriveMujocoPlant(m.path, m.joints, m.actuators, spec.drive, m.timestep)
