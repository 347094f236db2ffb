"""The controller variants, registered once: what differs between law (13), the cascade and
the look-ahead law, and the one place that decides it.

A plant model names its variant (:attr:`~.plants.PlantModel.variant`, ``Spec.variant``):

* ``"first-order"``: law (13) on the plant's state (system (1));
* ``"cascade"``: a second-order plant, the cascade law on the tube of the positions
  (docs/second-order.md);
* ``"look-ahead"``: law (13) on the point ahead of a differential-drive base's axle, then the
  base's command (docs/differential-drive.md).

Each is one :class:`ControllerVariant` of :data:`CONTROLLER_VARIANTS`: its words for
messages, its state layout, and its behaviour in the layers below ``spec`` (the stage the
controller takes beyond the tube, the state split, the backends, the generated files, the
firmware loop, the ``verify`` checks, ...) as *roles*. A role is a dotted reference
``"package.module:function"`` resolved on first use with :mod:`importlib`, like an entry
point, since ``spec`` may not import those layers; the three variants give one signature per
role (:data:`ROLES`). A module resolves only roles whose functions live in its own layer or
in layers above it (``tests/test_code_structure.py`` checks this, and that every reference
resolves to a callable). Nothing else in the package compares ``order``, ``variant``,
``drive`` or ``stage`` to decide a variant: it asks the variant object.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from ..errors import SpecError
from .plants import VARIANTS

__all__ = ["CONTROLLER_VARIANTS", "ControllerVariant", "ROLES", "require_variant",
           "resolve_reference", "variant_named", "variant_of", "variant_of_order",
           "variant_of_stage"]

#: Each role a variant fills, with the one signature its three functions share.
ROLES: Mapping[str, str] = MappingProxyType({
    "plant_terms": "(doc, linear, drive) -> (reference offset m, disturbance amplitude, "
                   "the [plant] data of [assumptions])",
    "stage_class": "the class of Design.stage (NoneType: no stage)",
    "stage": "(design) -> Design.stage",
    "casadi_step": "(tube, stage) -> casadi.Function (x, t, dt, alpha) -> (u, alpha_next, "
                   "...), the deployed step",
    "oracle_step": "(tube, stage, x (N, m), t (N,), dt (N,), alpha (N, 2n)) -> (u, "
                   "alpha_next, ...), the numpy oracle's step",
    "status": "(outputs of casadi_step, dt, rate_hz) -> (u, alpha_next, Status), the step's "
              "status (OFF_PERIOD off the period)",
    "stage_json": "(design) -> dict of the design document's variant fields",
    "summary_rows": "(design) -> list of (label, text), the variant's rows of "
                    "Design.summary()",
    "within_bound": "(spec, design_free) -> Design within [actuator] input_bound",
    "initial_state": "(spec) -> ndarray, the plant's state at t = 0",
    "positions": "(spec, states (N, m)) -> ndarray (N, n), the points the tube holds",
    "backends": "() -> the variant's dict of backend name to controller factory",
    "controller": "(name, tube design, stage) -> the backend's Controller",
    "plant": "(spec, seed) -> the simulated plant with equations",
    "mujoco_plant": "(spec) -> the plant stepped by MuJoCo",
    "run_fields": "(spec, tube, stage, ts, states, alphas, status, dt) -> dict of "
                  "SimulationResult's variant fields",
    "velocity_reference": "(tube, stage, states, ts, dt, alphas) -> r along a run, or None",
    "generation": "(design, options) -> dict of file name to bytes",
    "data_controller": "(design) -> TubeDataController, the variant's C with the tube as "
                       "data compiled once (SpecError where tube_data has no 'c')",
    "data_module": "(design) -> TubeDataModule, the variant's Python with the tube as "
                   "data generated once (SpecError where tube_data has no 'python')",
    "firmware": "(design, *, seed) -> report dict of the closed loop on the Cortex-M4F",
    "embedded_command": "(design, args, seed) -> exit code of stt-codegen embedded",
    "model_checks": "(spec, model) -> list of Check on the plant model",
    "sampled_checks": "(spec, design, tube_check, progress) -> list of Check of the "
                      "sampled loop",
    "plant_within": "(spec, model) -> Check, the plant within the certified class",
    "input_proof": "(design, spec, initial_error=None) -> InputProof, the proved peak of "
                   "each physical input along the design for the spec's plants "
                   "([actuator]); from a box of e(0) where initial_error is given (a "
                   "variant that replans, replans_sensed)",
    "output_limits": "(design) -> OutputLimits of its command without [actuator] (the "
                     "proved peak and the clamp's bound), or None: no warning",
    "predictor": "(tube, stage, delay, mid_gain) -> casadi.Function (x, u_held) -> x_hat, "
                 "the state the variant's law is evaluated at with [controller] "
                 "compensate_delay",
    "input_gain": "(spec) -> (g_min, g_max) of the plant class its certificate covers (the "
                  "prediction moves the state at their middle)",
})


@dataclass(frozen=True)
class ControllerVariant:
    """One controller variant: its words, its state layout and its roles.

    Attributes
    ----------
    name : str
        The variant's name (:data:`~.plants.VARIANTS`), as ``Spec.variant``.
    plant_words : str
        The plants it drives, for messages (``"a second-order plant"``).
    input_words : str
        What computes the input, for messages (``"law (13)"``).
    state_blocks : int
        The plant state's layout for a plant of joints (MuJoCo): 1, the joints'
        positions; 2, positions then velocities (``2 n`` states).
    state_words : str
        The layout in words, appended to messages about the state (``""`` when the state
        is the tube's ``n`` coordinates).
    roles : mapping of str to str
        Each role of :data:`ROLES` to its ``"module:function"`` reference.
    replay_context : mapping of str to bool
        Extra variables of the firmware replay program's template
        (``embedded_replay.c.j2``).
    predicts_delay : bool
        ``[controller] compensate_delay`` is available: its ``predictor`` role predicts the
        state over the delay and its sampled-data certificate proves the predicted law
        (docs/sampled-data.md, "Compensating a delay").
    replans_sensed : bool
        ``[sensing]`` is available: tubes are replanned around obstacles sensed at run time
        and switched at a sample (:mod:`stt_codegen.design.sensed`, docs/sensing.md): law
        (13)'s variant and the base's (its look-ahead point's tube).
    actuator_inputs : bool
        On a MuJoCo plant, ``[actuator] input_bound`` bounds the MuJoCo actuators (law
        (13)'s inputs, the cascade's forces), and they name the inputs; ``False``: it bounds
        the base's ``(v, omega)``, which its driver turns into wheel speeds.
    tube_data : tuple of str
        Where ``generate --tube-data`` is available (the generated code takes its tube as
        data and switches tubes at run time, :mod:`stt_codegen.codegen.tube_data`,
        docs/sensing.md): ``"c"``, ``"python"`` (the generated module) and ``"embedded"``
        (``stt-codegen embedded --tube-data``); empty: nowhere. Law (13)'s variant and the
        base's: all three; the cascade's: none.
    tracking_in_stage : bool
        Whether the tube can be followed is judged by the certificate of its stage (the
        cascade's, which bounds ``|e1|``); else the paper's method refuses a tube with
        circumvents whose law (13) sampled-data proof bounds ``|e|`` above
        ``TRACKING_ERROR`` (``design/tracking.py``, ``unfollowable``).
    via_timing : {"length", "acceleration"}
        How the design within ``[actuator]`` times a via tube for this variant's input
        (:mod:`stt_codegen.design.via`): ``"length"`` where the input is a velocity (law
        (13), the base's command), ``"acceleration"`` where it is a force (the cascade):
        the design then also tries via segments timed for the acceleration.
    turns : bool
        The design within ``[actuator]`` also times a via tube's moves for the turn into
        each (``tube.via_timing = "turn"``, ``via_turn = v_max / omega_max`` of the input
        bound; :mod:`stt_codegen.design.via`): the base's, whose limits are a speed and a
        turn rate.
    timing_in_stage : bool
        The certificate of its stage (:attr:`~stt_codegen.design.result.Design.stage`)
        proves ``[controller] delay`` and ``jitter`` (the cascade's); else the design's
        sampled-data proof of law (13) must hold with them (:mod:`~stt_codegen.design.timing`).

    Examples
    --------
    The differential-drive base's variant, and its role that writes the generated files:

    >>> from stt_codegen.spec.variants import CONTROLLER_VARIANTS
    >>> variant = CONTROLLER_VARIANTS["look-ahead"]
    >>> variant.plant_words, variant.input_words
    ('a differential-drive base', "the base's command (v, omega)")
    >>> variant.entry("generation").__name__
    'look_ahead_generation'
    """

    name: str
    plant_words: str
    input_words: str
    state_blocks: int
    state_words: str
    roles: Mapping[str, str]
    replay_context: Mapping[str, bool] = field(default_factory=lambda: MappingProxyType({}))
    timing_in_stage: bool = False
    tracking_in_stage: bool = False
    via_timing: str = "length"
    turns: bool = False
    predicts_delay: bool = False
    replans_sensed: bool = False
    actuator_inputs: bool = True
    tube_data: tuple[str, ...] = ()

    def entry(self, role: str) -> Callable[..., Any]:
        """The variant's function (or class) for one role, imported on first use.

        Parameters
        ----------
        role : str
            A key of :data:`ROLES`.

        Returns
        -------
        callable
            The object the role's reference names, with the role's signature.

        Raises
        ------
        KeyError
            ``role`` is not a role of the variant.
        """
        return resolve_reference(self.roles[role])


def resolve_reference(reference: str) -> Callable[..., Any]:
    """The object a ``"package.module:name"`` reference names.

    Parameters
    ----------
    reference : str
        Module path, a colon, the attribute's name.

    Returns
    -------
    callable
        The module's attribute.

    Raises
    ------
    ImportError
        The module does not exist.
    AttributeError
        The module has no such name.
    """
    module, name = reference.split(":")
    return getattr(importlib.import_module(module), name)


def _roles(**names: str) -> Mapping[str, str]:
    """The roles of one variant, checked to be exactly :data:`ROLES`."""
    assert set(names) == set(ROLES), set(names) ^ set(ROLES)
    return MappingProxyType({role: names[role] for role in ROLES})


_P = "stt_codegen."
#: The one registry of the controller variants, by name (:data:`~.plants.VARIANTS` order).
CONTROLLER_VARIANTS: Mapping[str, ControllerVariant] = MappingProxyType({
    "first-order": ControllerVariant(
        "first-order", "a first-order plant", "law (13)", 1, "",
        _roles(plant_terms=_P + "spec.loader:law13_plant_terms",
               stage_class="types:NoneType",
               stage=_P + "design.result:no_stage",
               casadi_step=_P + "tube.variant_steps:law13_casadi_step",
               oracle_step=_P + "tube.variant_steps:law13_oracle_step",
               status=_P + "tube.variant_steps:law13_status",
               stage_json=_P + "design.result:no_stage_json",
               summary_rows=_P + "design.result:no_summary_rows",
               within_bound=_P + "design.actuator:design_within_bound",
               initial_state=_P + "runtime.state_split:tube_state_start",
               positions=_P + "runtime.state_split:leading_positions",
               backends=_P + "runtime.backends:first_order_backends",
               data_controller=_P + "runtime.data_controller:first_order_data_controller",
               data_module=_P + "runtime.data_module:first_order_data_module",
               controller=_P + "runtime.backends:first_order_controller",
               plant=_P + "runtime.plants:first_order_spec_plant",
               mujoco_plant=_P + "runtime.plants:joint_mujoco_plant",
               run_fields=_P + "runtime.simulate:no_velocity_fields",
               velocity_reference=_P + "runtime.simulate:no_velocity_reference",
               generation=_P + "codegen.generate:first_order_generation",
               firmware=_P + "embedded.deploy:run_embedded",
               embedded_command=_P + "cli.embedded:law13_command",
               model_checks=_P + "verification.command:first_order_model_checks",
               sampled_checks=_P + "verification.command:first_order_sampled_checks",
               plant_within=_P + "verification.plant_within:first_order_within",
               input_proof=_P + "design.actuator:law13_input_proof",
               output_limits=_P + "design.output_bound:no_output_limits",
               predictor=_P + "tube.variant_steps:law13_predictor",
               input_gain=_P + "spec.input_gains:declared_input_gain"),
        predicts_delay=True, replans_sensed=True, tube_data=("c", "python", "embedded")),
    "cascade": ControllerVariant(
        "cascade", "a second-order plant", "the cascade's input u", 2,
        " (positions, then velocities)",
        _roles(plant_terms=_P + "spec.loader:law13_plant_terms",
               stage_class=_P + "tube.second_stage:SecondStage",
               stage=_P + "design.result:cascade_stage",
               casadi_step=_P + "tube.cascade:cascade_step",
               oracle_step=_P + "tube.cascade_reference:cascade_step",
               status=_P + "tube.variant_steps:cascade_status",
               stage_json=_P + "design.result:cascade_stage_json",
               summary_rows=_P + "design.result:cascade_summary_rows",
               within_bound=_P + "design.search:cascade_within_bound",
               initial_state=_P + "runtime.state_split:cascade_start",
               positions=_P + "runtime.state_split:leading_positions",
               backends=_P + "runtime.backends:cascade_backends",
               data_controller=_P + "runtime.data_controller:no_data_controller",
               data_module=_P + "runtime.data_module:no_data_module",
               controller=_P + "runtime.backends:cascade_controller",
               plant=_P + "runtime.plants:cascade_spec_plant",
               mujoco_plant=_P + "runtime.plants:joint_mujoco_plant",
               run_fields=_P + "runtime.simulate:velocity_fields",
               velocity_reference=_P + "runtime.simulate:cascade_velocity_reference",
               generation=_P + "codegen.cascade_source:cascade_generation",
               firmware=_P + "embedded.cascade_loop:run_cascade_embedded",
               embedded_command=_P + "cli.embedded:variant_loop_command",
               model_checks=_P + "verification.command:no_model_checks",
               sampled_checks=_P + "verification.command:cascade_sampled_checks",
               plant_within=_P + "verification.plant_within:cascade_within",
               input_proof=_P + "design.cascade_gain:cascade_design_proof",
               output_limits=_P + "design.output_bound:cascade_output_limits",
               predictor=_P + "tube.cascade:cascade_predictor",
               input_gain=_P + "spec.input_gains:cascade_input_gain"),
        MappingProxyType({"cascade": True}), timing_in_stage=True, tracking_in_stage=True,
        via_timing="acceleration", predicts_delay=True),
    "look-ahead": ControllerVariant(
        "look-ahead", "a differential-drive base", "the base's command (v, omega)", 1, "",
        _roles(plant_terms=_P + "spec.loader:look_ahead_plant_terms",
               stage_class=_P + "tube.look_ahead:LookAhead",
               stage=_P + "design.result:look_ahead_stage",
               casadi_step=_P + "tube.look_ahead:look_ahead_step",
               oracle_step=_P + "tube.variant_steps:look_ahead_oracle_step",
               status=_P + "tube.variant_steps:law13_status",
               stage_json=_P + "design.result:no_stage_json",
               summary_rows=_P + "design.result:look_ahead_summary_rows",
               within_bound=_P + "design.look_ahead:look_ahead_within_bound",
               initial_state=_P + "runtime.state_split:look_ahead_start",
               positions=_P + "runtime.state_split:look_ahead_positions",
               backends=_P + "runtime.backends:look_ahead_backends",
               data_controller=_P + "runtime.data_controller:look_ahead_data_controller",
               data_module=_P + "runtime.data_module:look_ahead_data_module",
               controller=_P + "runtime.backends:look_ahead_controller",
               plant=_P + "runtime.plants:drive_spec_plant",
               mujoco_plant=_P + "runtime.plants:drive_mujoco_plant",
               run_fields=_P + "runtime.simulate:no_velocity_fields",
               velocity_reference=_P + "runtime.simulate:no_velocity_reference",
               generation=_P + "codegen.look_ahead_source:look_ahead_generation",
               firmware=_P + "embedded.look_ahead_loop:run_look_ahead_embedded",
               embedded_command=_P + "cli.embedded:variant_loop_command",
               model_checks=_P + "verification.command:look_ahead_model_checks",
               sampled_checks=_P + "verification.command:look_ahead_sampled_checks",
               plant_within=_P + "verification.plant_within:first_order_within",
               input_proof=_P + "design.look_ahead:look_ahead_design_proof",
               output_limits=_P + "design.output_bound:look_ahead_output_limits",
               predictor=_P + "tube.look_ahead:look_ahead_predictor",
               input_gain=_P + "spec.input_gains:declared_input_gain"),
        predicts_delay=True, replans_sensed=True, actuator_inputs=False, turns=True,
        tube_data=("c", "python", "embedded")),
})
assert tuple(CONTROLLER_VARIANTS) == VARIANTS

#: The variant of each plant order (the ``order`` keyword of the backends' registry).
_ORDERS = {1: "first-order", 2: "cascade"}


def variant_named(name: str) -> ControllerVariant:
    """The registered variant of a name.

    Parameters
    ----------
    name : str
        A name of :data:`~.plants.VARIANTS`.

    Returns
    -------
    ControllerVariant

    Raises
    ------
    SpecError
        Unknown name (field ``variant``), naming the known ones.
    """
    if name not in CONTROLLER_VARIANTS:
        raise SpecError("variant", f"unknown controller variant {name!r} (known: "
                                   f"{', '.join(CONTROLLER_VARIANTS)})")
    return CONTROLLER_VARIANTS[name]


def variant_of(owner: Any) -> ControllerVariant:
    """The variant of a spec or a plant model's entry (their ``variant`` name).

    Parameters
    ----------
    owner : Spec or PlantModel or SecondOrderModel
        Anything with a ``variant`` name.

    Returns
    -------
    ControllerVariant

    Raises
    ------
    SpecError
        ``owner.variant`` is not a registered variant (field ``variant``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.spec.variants import variant_of
    >>> variant_of(stt.load_spec("second-order-s1")).name
    'cascade'
    """
    return variant_named(owner.variant)


def variant_of_order(order: int) -> ControllerVariant:
    """The variant of a plant order alone: law (13) for 1, the cascade for 2.

    Parameters
    ----------
    order : {1, 2}
        The plant's order.

    Returns
    -------
    ControllerVariant

    Raises
    ------
    SpecError
        ``order`` is not 1 or 2 (field ``order``).
    """
    if order not in _ORDERS:
        raise SpecError("order", f"a plant's order is 1 or 2, got {order!r}")
    return CONTROLLER_VARIANTS[_ORDERS[order]]


def variant_of_stage(stage: Any) -> ControllerVariant:
    """The variant whose controller takes ``stage`` beyond the tube (``Design.stage``).

    Parameters
    ----------
    stage : SecondStage, LookAhead or None
        ``None`` for law (13) on the plant's state.

    Returns
    -------
    ControllerVariant

    Raises
    ------
    SpecError
        No variant takes a stage of that type (field ``stage``).
    """
    for variant in CONTROLLER_VARIANTS.values():
        if isinstance(stage, variant.entry("stage_class")):
            return variant
    raise SpecError("stage", f"no controller variant takes a {type(stage).__name__} "
                             "(a SecondStage, a LookAhead or None)")


def require_variant(spec: Any, name: str, what: str) -> None:
    """Refuse a spec of another variant than ``name`` for something only it has.

    Parameters
    ----------
    spec : Spec
        The spec.
    name : str
        The variant required (:data:`~.plants.VARIANTS`).
    what : str
        What needs it, for the message (``"the look-ahead point"``).

    Raises
    ------
    SpecError
        The spec's variant is another (field ``plant.model``).
    """
    wanted, found = variant_named(name), variant_of(spec)
    if found is not wanted:
        raise SpecError("plant.model", f"{what} needs {wanted.plant_words} (the "
                                       f"{wanted.name} variant); the spec describes "
                                       f"{found.plant_words} (the {found.name} variant)")
