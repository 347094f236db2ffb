"""The design's controller and its plant as python-control systems: interconnected and run by
``ct.input_output_response``, they give ``simulate``'s run to the last bit."""

from __future__ import annotations

import numpy as np
import pytest

import control as ct

import stt_codegen as stt
from stt_codegen.runtime.state_split import initial_state, positions

STEPS = 150


def _loop(design, backend):
    controller = stt.controller_system(design, backend=backend)
    plant = stt.sampled_plant(design)
    states, inputs = plant.nstates, plant.ninputs
    loop = ct.interconnect(
        [controller, plant], inplist=[],
        connections=[*([f"stt.x[{i}]", f"plant.x[{i}]"] for i in range(states)),
                     *([f"plant.u[{j}]", f"stt.u[{j}]"] for j in range(inputs))],
        outlist=[*(f"plant.x[{i}]" for i in range(states)),
                 *(f"stt.u[{j}]" for j in range(inputs)), "stt.status"])
    return loop, controller, states, inputs


@pytest.mark.parametrize("case, backend", [
    ("omnirobot-s1", "c"),
    ("second-order-s1", "reference"),
    ("office-base", "python"),
    pytest.param("omnirobot-s1", "reference", marks=pytest.mark.slow),
    pytest.param("second-order-s1", "c", marks=pytest.mark.slow),
    pytest.param("office-base", "c", marks=pytest.mark.slow),
])
def test_the_interconnected_loop_gives_simulates_run(case, backend) -> None:
    design = stt.design_tube(stt.load_spec(case))
    loop, controller, states, inputs = _loop(design, backend)
    dt = controller.dt
    assert dt == 1.0 / design.tube.rate_hz
    times = np.arange(STEPS + 1) * dt
    x0 = np.concatenate([np.zeros(controller.nstates), initial_state(design.spec)])
    response = ct.input_output_response(loop, times, 0, X0=x0)
    run = stt.simulate(design, backend=backend, horizon=STEPS * dt)
    x = response.outputs[:states].T
    u = response.outputs[states:states + inputs].T
    status = response.outputs[-1]
    alpha = response.states[:controller.nstates].T
    # the same floats: the loop is simulate's, step for step (no tolerance to hide behind;
    # 1e-12 is the bound, and the runs agree far below it)
    assert np.max(np.abs(positions(design.spec, x) - run.trajectory.x)) <= 1e-12
    assert np.max(np.abs(u - run.trajectory.u)) <= 1e-12
    assert np.max(np.abs(alpha - run.trajectory.alpha)) <= 1e-12
    assert np.array_equal(status, run.trajectory.status.astype(float))
    assert np.any(alpha > 0) or np.any(u != 0)      # the loop did something


def test_a_plant_of_other_sizes_is_refused_naming_the_field() -> None:
    design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    wrong = ct.nlsys(lambda t, x, u, p: -x, None, states=2, inputs=2, outputs=2)
    with pytest.raises(stt.SpecError, match="plant"):
        stt.sampled_plant(design, plant=wrong)


def test_a_spec_is_not_a_design() -> None:
    with pytest.raises(TypeError, match="design_tube"):
        stt.controller_system(stt.load_spec("omnirobot-s1"))
