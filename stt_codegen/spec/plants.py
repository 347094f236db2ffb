"""The plant models a spec may name (``[plant] model``): the one registry of their facts.

Two families: the first-order models of system (1) (:data:`PLANTS`), driven by law (13),
and the second-order models ``x1_dot = x2``, ``x2_dot = f + g u + w``
(:data:`SECOND_ORDER_PLANTS`), driven by the cascade law of docs/second-order.md. A
second-order model implies order 2; there is no ``order`` key.

Everything that needs a fact about a model reads it here: the schema (the allowed names
and their descriptions), the loader (the state count a model requires, the ``[plant]``
keys only some models take), the simulation's and the embedded loop's dynamics
(:mod:`stt_codegen.runtime.dynamics`, :mod:`stt_codegen.runtime.plants`) and
``stt-codegen verify --plant``. A new model is an entry of :data:`PLANTS` and its
behaviour in the per-model tables (docs/architecture.md, "The plant registry").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, TypeVar

__all__ = ["ALL_PLANT_MODELS", "PLANTS", "PLANT_MODELS", "MODEL_KEYS", "NAMED_MODELS",
           "MissingPlantBehaviour", "MODELS_WITH_EQUATIONS", "PARAMETER_KEYS", "PlantModel",
           "SECOND_ORDER_MODELS", "VARIANTS",
           "SIMULATOR_KEYS",
           "SECOND_ORDER_PLANTS", "SecondOrderModel", "dimension_mismatch",
           "model_behaviour", "plant_entry"]

_Behaviour = TypeVar("_Behaviour")


@dataclass(frozen=True)
class PlantModel:
    """Facts about one plant model of system (1), ``x_dot = f(x) + g(x) u + w``.

    Attributes
    ----------
    name : str
        The ``plant.model`` value.
    summary : str
        One line for the schema and help texts.
    states : int or None
        The state dimension ``n`` the model requires, ``None`` for any.
    inputs : tuple of str or None
        Names of the inputs ``u``, ``None`` for one per state (``u1``, ``u2``, ...).
    keys : tuple of str
        Keys of ``[plant]`` only this model takes (its matrices).
    input_unit : str
        One SI unit of every input, ``""`` when the inputs have the state's units per
        second (they may differ between inputs).
    gain_varies : bool
        ``g(x)`` depends on the state: its bounds over a smaller box (the tube on a
        sampling interval) are tighter than over the state space.
    drift_varies : bool
        ``f(x)`` depends on the state (through matrices of the spec), likewise.
    simulator_keys : tuple of str
        Keys of ``[plant]`` only this model takes that name a simulator's model of the
        plant (a MuJoCo file and its joints), not matrices.
    declared_bounds : bool
        The toolkit has no equations of the model: every bound the design and ``verify``
        use is the declared ``[assumptions]`` (``input_gain`` and ``drift_bound`` are
        required), and nothing proves the plant meets them.
    parameter_keys : tuple of str
        Keys of ``[plant]`` only this model takes that give its physical parameters
        (the differential drive's axle offset, track width, wheel errors and slip).
    variant : str
        The controller that drives it (:data:`VARIANTS`): ``"first-order"``, law (13) on
        the plant's state; ``"look-ahead"``, law (13) on a point ahead of a
        non-holonomic base (docs/differential-drive.md).
    plant_states : int or None
        The plant's own state count when the tube holds a point computed from the
        state (the differential drive: ``x, y, theta``); ``None``: the tube's states are
        the plant's.
    """

    name: str
    summary: str
    states: int | None = None
    inputs: tuple[str, ...] | None = None
    keys: tuple[str, ...] = ()
    input_unit: str = ""
    gain_varies: bool = False
    drift_varies: bool = False
    simulator_keys: tuple[str, ...] = ()
    declared_bounds: bool = False
    parameter_keys: tuple[str, ...] = ()
    variant: str = "first-order"
    plant_states: int | None = None

    #: Order of the model: 1, system (1) driven by law (13).
    order = 1

    def input_count(self, n: int) -> int:
        """Number of inputs for ``n`` states."""
        return n if self.inputs is None else len(self.inputs)

    def input_names(self, n: int) -> tuple[str, ...]:
        """Names of the inputs for ``n`` states (``u1``, ``u2``, ... when the model has none)."""
        return tuple(f"u{i + 1}" for i in range(n)) if self.inputs is None else self.inputs


#: Every model, by ``plant.model`` name, in the schema's order.
PLANTS: dict[str, PlantModel] = {p.name: p for p in (
    PlantModel("omnidirectional", "eq. (14), x_dot = R(x3) u + w, 3 states (x, y, heading)",
               states=3, inputs=("v1", "v2", "omega"), gain_varies=True),
    PlantModel("single-integrator", "x_dot = u + w"),
    PlantModel("linear", "x_dot = a x + c + g u + w, the matrices from [plant]",
               keys=("a", "g", "c"), drift_varies=True),
    PlantModel("mujoco", "an MJCF model stepped by MuJoCo (plant.mjcf, plant.joints, "
               "plant.actuators): the states the joints' positions, the inputs the "
               "actuators' controls (velocity actuators); no equations: [assumptions] "
               "input_gain and drift_bound are required and taken as declared",
               simulator_keys=("mjcf", "joints", "actuators", "timestep"),
               declared_bounds=True),
    PlantModel("differential-drive", "a differential-drive base, x_dot = v cos(theta), "
               "y_dot = v sin(theta), theta_dot = omega (inputs v, omega); the tube holds its "
               "look-ahead point (x, y) + axle_offset (cos theta, sin theta), 2 states "
               "(plant.axle_offset, plant.track_width, plant.wheel_radius_error, plant.slip, "
               "initial.heading)", states=2, inputs=("v", "omega"),
               parameter_keys=("axle_offset", "track_width", "wheel_radius_error", "slip",
                               "wheel_radius"),
               simulator_keys=("mjcf", "joints", "actuators", "timestep"),
               variant="look-ahead", plant_states=3),
)}
#: The ``plant.model`` values.
PLANT_MODELS: tuple[str, ...] = tuple(PLANTS)
#: Models with fixed dynamics (no matrices from the spec).
NAMED_MODELS: tuple[str, ...] = tuple(name for name, p in PLANTS.items()
                                      if not p.keys and not p.declared_bounds
                                      and p.plant_states is None)
#: ``[plant]`` matrix keys that belong to one model, with the model.
MODEL_KEYS: dict[str, str] = {key: name for name, p in PLANTS.items() for key in p.keys}
#: ``[plant]`` parameter keys that belong to one model, with the model.
PARAMETER_KEYS: dict[str, str] = {key: name for name, p in PLANTS.items()
                                  for key in p.parameter_keys}
#: The controller variants a plant model may name: law (13), the cascade law for second
#: order, law (13) on a look-ahead point of a non-holonomic base.
VARIANTS = ("first-order", "cascade", "look-ahead")
#: Models with equations the toolkit knows (their bounds derived, their dynamics simulated).
MODELS_WITH_EQUATIONS: tuple[str, ...] = tuple(name for name, p in PLANTS.items()
                                               if not p.declared_bounds)


@dataclass(frozen=True)
class SecondOrderModel:
    """A named second-order model: its dimension (``None``: any), a summary, parameter
    names and nominal parameter values (SI units), and whether its input matrix ``g`` is
    diagonal for every parameter value and state.

    Attributes
    ----------
    name : str
        The ``plant.model`` name.
    summary : str
        One line describing the model.
    dimension : int or None
        Number of positions ``n`` (the state has ``2 n``); None: any ``n``.
    parameters : tuple of str
        Names of the model's ``plant.parameters``, in order.
    nominal : tuple of float
        Their nominal values, SI units.
    diagonal_input : bool
        ``g`` is diagonal (``I / m``: an input moves its own velocity only), so the sampled
        cascade's certificate takes no coupling between axes.
    inputs : tuple of str or None
        Names of the physical inputs ``u`` (one per position), ``None`` for ``F1``,
        ``F2``, ... (a force per axis).
    input_unit : str
        SI unit of every input (``"N"`` for a force, ``"N m"`` for a torque): the unit of
        ``[actuator] input_bound``.
    simulator_keys : tuple of str
        As :attr:`PlantModel.simulator_keys`.
    declared_bounds : bool
        As :attr:`PlantModel.declared_bounds`: no equations, the declared
        ``[assumptions]`` (``input_gain`` and ``drift_bound`` required) are the class.
    """

    name: str
    summary: str
    dimension: int | None
    parameters: tuple[str, ...]
    nominal: tuple[float, ...]
    diagonal_input: bool = False
    inputs: tuple[str, ...] | None = None
    input_unit: str = "N"
    simulator_keys: tuple[str, ...] = ()
    declared_bounds: bool = False

    #: Order of the model: 2, the cascade law.
    order = 2
    #: The controller variant (:data:`VARIANTS`).
    variant = "cascade"
    #: The plant's state is ``[x1; x2]``, twice the tube's (see :attr:`PlantModel.plant_states`).
    plant_states = None
    #: No ``[plant]`` parameter keys beyond ``parameters`` (see :attr:`PlantModel.parameter_keys`).
    parameter_keys = ()

    def input_count(self, n: int) -> int:
        """Number of physical inputs for ``n`` positions (one per position)."""
        return n if self.inputs is None else len(self.inputs)

    def input_names(self, n: int) -> tuple[str, ...]:
        """Names of the physical inputs for ``n`` positions (``F1``, ``F2``, ... when the
        model has none)."""
        return tuple(f"F{i + 1}" for i in range(n)) if self.inputs is None else self.inputs


#: Every second-order model, by ``plant.model`` name (dynamics:
#: :mod:`stt_codegen.runtime.second_order_plants`).
SECOND_ORDER_PLANTS: dict[str, SecondOrderModel] = {m.name: m for m in (
    SecondOrderModel("double-integrator", "second order, x2_dot = u / mass + w, any n", None,
                     ("mass",), (1.0,), diagonal_input=True),
    SecondOrderModel("quadrotor", "second order, x2_dot = u / mass - (drag / mass) x2 - "
                     "gravity e3 + w, thrust vector u, n = 3", 3, ("mass", "drag", "gravity"),
                     (1.0, 0.3, 9.81), diagonal_input=True,
                     inputs=("thrust_x", "thrust_y", "thrust_z")),
    SecondOrderModel("two-link-arm", "second order, joint space, M(q) q_ddot + C(q, q_dot) "
                     "q_dot + G(q) = u + w, n = 2", 2,
                     ("mass1", "mass2", "length1", "length2", "inertia1", "inertia2",
                      "gravity"),
                     (1.0, 1.0, 1.0, 1.0, 1.0 / 12.0, 1.0 / 12.0, 0.0),
                     inputs=("tau1", "tau2"), input_unit="N m"),
    SecondOrderModel("mujoco-force", "second order, an MJCF model stepped by MuJoCo through "
                     "force or torque actuators (plant.mjcf, plant.joints, plant.actuators): "
                     "the states the joints' positions and velocities, any n; no equations: "
                     "[assumptions] input_gain and drift_bound are required and taken as "
                     "declared", None, (), (), inputs=None, input_unit="",
                     simulator_keys=("mjcf", "joints", "actuators", "timestep"),
                     declared_bounds=True),
)}
#: The second-order ``plant.model`` values, in order.
SECOND_ORDER_MODELS: tuple[str, ...] = tuple(SECOND_ORDER_PLANTS)
#: Every ``plant.model`` value a spec may give: first order, then second order.
ALL_PLANT_MODELS: tuple[str, ...] = PLANT_MODELS + SECOND_ORDER_MODELS
#: ``[plant]`` keys naming a simulator's model of the plant, with the models that take them.
SIMULATOR_KEYS: dict[str, tuple[str, ...]] = {
    key: tuple(name for name, p in (*PLANTS.items(), *SECOND_ORDER_PLANTS.items())
               if key in p.simulator_keys)
    for key in dict.fromkeys(k for p in (*PLANTS.values(), *SECOND_ORDER_PLANTS.values())
                             for k in p.simulator_keys)}


def plant_entry(model: str) -> PlantModel | SecondOrderModel:
    """The registry's entry of a ``plant.model`` name (first or second order).

    Parameters
    ----------
    model : str
        A ``plant.model`` name.

    Returns
    -------
    PlantModel or SecondOrderModel
        Its facts; ``order`` says which family.

    Raises
    ------
    MissingPlantBehaviour
        ``model`` is not a known model.
    """
    if model in SECOND_ORDER_PLANTS:
        return SECOND_ORDER_PLANTS[model]
    return model_behaviour(PLANTS, model, "entry in the plant registry")


class MissingPlantBehaviour(ValueError):
    """A plant model has no entry in a per-model table of behaviour (unknown model, or a
    model added without that behaviour)."""


def model_behaviour(table: Mapping[str, _Behaviour], model: str,
                    what: str) -> _Behaviour:
    """The behaviour ``model`` registered in a per-model ``table``, refused clearly if none.

    Every module that does something per plant model keeps one table keyed by
    ``plant.model`` (its dynamics, its bounds over a box, its Assumption-2 check, its
    input-bound prover) and looks the model up here: a model without an entry is refused
    by name, never handled as another model.

    Parameters
    ----------
    table : mapping of str to object
        The behaviour per ``plant.model`` name.
    model : str
        The ``plant.model`` name.
    what : str
        What the table holds, for the message (e.g. ``"Assumption-2 check"``).

    Returns
    -------
    object
        ``table[model]``.

    Raises
    ------
    MissingPlantBehaviour
        ``model`` has no entry, naming the models that have one.
    """
    try:
        return table[model]
    except KeyError:
        known = ", ".join(table) or "none"
        raise MissingPlantBehaviour(f"plant model {model!r} has no {what} (models with "
                                    f"one: {known})") from None


def dimension_mismatch(model: str, n: int) -> str | None:
    """Why ``model`` cannot have ``n`` states, or ``None`` if it can (or is not a known
    model: the caller reports that).

    Parameters
    ----------
    model : str
        A :data:`ALL_PLANT_MODELS` entry.
    n : int
        State dimension (positions, for a second-order model).

    Returns
    -------
    str or None
        The reason, naming the model's and the state space's dimension, or None.
    """
    if model in SECOND_ORDER_PLANTS:
        positions = SECOND_ORDER_PLANTS[model].dimension
        if positions is None or positions == n:
            return None
        return f"the {model} model has {positions} positions, the state space has {n}"
    required = PLANTS[model].states if model in PLANTS else None
    if required is None or required == n:
        return None
    return f"the {model} robot has {required} states, the state space has {n}"
