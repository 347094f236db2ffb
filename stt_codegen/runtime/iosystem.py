"""A design's sampled controller, and its plant held over a period, as discrete-time
python-control systems (``ct.interconnect``, ``ct.input_output_response``)."""

from __future__ import annotations

import numpy as np

import control as ct

from .backends import make_controller
from ..design.prediction import delay_predictor
from ..design.result import Design, require_design
from ..errors import SpecError
from .plants import check_seed, spec_plant
from .simulate import RungeKutta, hold_period
from .state_split import initial_state

__all__ = ["controller_system", "sampled_plant"]


class _LastStep:
    """The controller step memoized on its arguments, for the last few argument sets:
    python-control asks for the output and the update of a sample separately, and
    resolves an interconnection's signals by evaluating the outputs more than once (first
    with the inputs not yet known)."""

    #: Argument sets kept (python-control evaluates about four per sample).
    KEPT = 4

    def __init__(self, controller, dt: float) -> None:
        self.controller, self.dt = controller, dt
        self.values: dict[tuple, tuple] = {}

    def __call__(self, t: float, alpha: np.ndarray, x: np.ndarray) -> tuple:
        alpha = np.asarray(alpha, dtype=float).reshape(-1)
        x = np.asarray(x, dtype=float).reshape(-1)
        key = (float(t), alpha.tobytes(), x.tobytes())
        if key not in self.values:
            if len(self.values) >= self.KEPT:
                del self.values[next(iter(self.values))]     # the oldest
            self.values[key] = self.controller.step(x, float(t), self.dt, alpha)
        return self.values[key]


def controller_system(design: Design, backend: str = "reference",
                      name: str = "stt") -> ct.NonlinearIOSystem:
    """The design's sampled controller as a discrete-time python-control system.

    At ``t_k = k dt`` (``dt = 1 / rate_hz``) the system reads the plant's state ``x_k`` and
    outputs the command ``u_k`` of law (13) (the cascade's or the base's for those
    variants) and its status; its state is the adaptive state ``alpha`` of law (11),
    updated by the implicit step. It is the step that :func:`stt_codegen.simulate` calls,
    of the same backend: interconnected with :func:`sampled_plant` it gives the same run.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`.
    backend : str
        ``"reference"`` (the numpy oracle), ``"casadi"``, ``"c"`` (the generated double C,
        compiled) or ``"python"`` (the generated Python), as :func:`stt_codegen.simulate`.
    name : str
        The system's name (prefix of its signals in ``ct.interconnect``).

    Returns
    -------
    control.NonlinearIOSystem
        ``dt = 1 / rate_hz``. States ``alpha[0] .. alpha[2n-1]`` (``[alpha_L, alpha_U]``,
        state units, zero at ``t = 0``), then with ``[controller] compensate_delay`` its
        previous output ``u_held[0] .. u_held[m-1]`` (zero at ``t = 0``), from which it
        predicts the state law (13) reads (docs/sampled-data.md, "Compensating a delay");
        inputs ``x[0] ..`` the plant's state (``n``
        positions, ``2 n`` positions then velocities for a second-order plant,
        ``(x, y, theta)`` for a differential-drive base); outputs ``u[0] .. u[m-1]`` (input
        units) and ``status`` (a :class:`~stt_codegen.tube.parameters.Status` code as a
        float).

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.
    SpecError
        Unknown backend (field ``backend``).
    ToolchainError
        Backend ``"c"``: no C compiler, or it failed.

    Examples
    --------
    >>> import numpy as np
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> controller = stt.controller_system(design)
    >>> controller.dt, controller.ninputs, controller.noutputs, controller.nstates
    (0.001, 3, 4, 6)
    """
    design = require_design(design, "controller_system")
    spec, tube = design.spec, design.tube
    states = initial_state(spec).size
    inputs = spec.dimension
    dt = 1.0 / tube.rate_hz
    step = _LastStep(make_controller(backend, tube, design.stage), dt)
    predict = delay_predictor(spec, tube, design.stage)
    held = [f"u_held[{j}]" for j in range(inputs)] if predict is not None else []

    def seen(memory, x):
        """alpha and the state law (13) reads: x, or its prediction from the held u."""
        memory = np.asarray(memory, dtype=float).reshape(-1)
        if predict is None:
            return memory, x
        x = np.asarray(predict(np.asarray(x, dtype=float).reshape(-1),
                               memory[2 * inputs:]), dtype=float).ravel()
        return memory[:2 * inputs], x

    def update(t, memory, x, params):
        u, alpha_next, _ = step(t, *seen(memory, x))
        return np.concatenate([np.asarray(alpha_next, dtype=float).ravel(),
                               np.asarray(u, dtype=float).ravel() if held else []])

    def output(t, memory, x, params):
        u, _, status = step(t, *seen(memory, x))
        return np.append(np.asarray(u, dtype=float), float(status))

    return ct.nlsys(update, output, dt=dt, name=name,
                    states=[*(f"alpha[{i}]" for i in range(2 * inputs)), *held],
                    inputs=[f"x[{i}]" for i in range(states)],
                    outputs=[*(f"u[{j}]" for j in range(inputs)), "status"])


def sampled_plant(design: Design, seed: int = 0, plant: ct.NonlinearIOSystem | None = None,
                  name: str = "plant") -> ct.NonlinearIOSystem:
    """The plant over one sampling period, its input held, as a discrete-time system.

    The update integrates the continuous plant over ``[t_k, t_k + dt]`` with the input
    held, by the Runge-Kutta steps :func:`stt_codegen.simulate` takes; so
    ``ct.interconnect`` of it with :func:`controller_system` is the closed loop of
    ``simulate`` (the same floats). With a spec's ``[controller] delay`` ``d > 0`` the
    system also keeps the previous input ``u_{k-1}`` as states (zero at ``t = 0``): the
    update holds it on ``[t_k, t_k + d)`` and the input ``u_k`` from ``t_k + d``, as
    ``simulate`` does, then stores ``u_k``. It samples exactly every ``dt``: a spec's
    ``jitter``, which ``simulate`` draws, is not run here.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`; its spec names the plant and its disturbance.
    seed : int
        Seed of the spec plant's disturbance, in ``[0, 2**32)``.
    plant : control.NonlinearIOSystem, optional
        A continuous-time plant of the spec's state and input sizes instead of the spec's
        own (it must include its own disturbance).
    name : str
        The system's name.

    Returns
    -------
    control.NonlinearIOSystem
        ``dt = 1 / rate_hz``; states ``x[0] .. x[s-1]`` (the plant's ``s`` states), then
        with a delay ``u_prev[0] .. u_prev[m-1]`` (``s + m`` states; the initial state
        is ``[x(0), 0]``); inputs ``u[0] .. u[m-1]``; outputs ``x[0] .. x[s-1]`` (the
        plant's state).

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design`.
    SpecError
        A bad ``seed`` (field ``seed``); a plan with a MuJoCo plant (field ``plant``:
        MuJoCo steps its own state); a ``plant`` of other sizes (field ``plant``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> plant = stt.sampled_plant(design)
    >>> plant.dt, plant.nstates, plant.ninputs
    (0.001, 3, 3)
    """
    design = require_design(design, "sampled_plant")
    spec = design.spec
    seed = check_seed(seed)
    continuous = spec_plant(spec, seed) if plant is None else plant
    states, inputs = initial_state(spec).size, spec.dimension
    if not isinstance(continuous, ct.NonlinearIOSystem):
        raise SpecError("plant", "a MuJoCo plant steps its own state; simulate it with "
                                 "stt_codegen.simulate")
    if (continuous.nstates, continuous.ninputs) != (states, inputs):
        raise SpecError("plant", f"must have {states} states and {inputs} inputs for this "
                                 f"spec, not {continuous.nstates} and {continuous.ninputs}")
    stepper = RungeKutta(continuous)
    dt = 1.0 / design.tube.rate_hz
    delay = spec.delay
    held = [f"u_prev[{j}]" for j in range(inputs)] if delay > 0.0 else []

    def update(t, state, u, params):
        state = np.asarray(state, dtype=float).reshape(-1)
        u = np.asarray(u, dtype=float).reshape(-1)
        stepper.reset(state[:states])
        points, _ = hold_period(stepper, float(t), state[states:], u, dt, delay)
        return np.concatenate([points[-1], u]) if held else points[-1]

    def output(t, state, u, params):
        return state[:states]

    return ct.nlsys(update, output, dt=dt, name=name,
                    states=[*(f"x[{i}]" for i in range(states)), *held],
                    inputs=[f"u[{j}]" for j in range(inputs)],
                    outputs=[f"x[{i}]" for i in range(states)])
