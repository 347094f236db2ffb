"""The closed loop with a computation delay (``[controller] delay``): the command computed
from ``x(t_k)`` acts from ``t_k + delay`` to ``t_{k+1} + delay``, the previous one before,
zero before the first. ``simulate`` and the python-control systems of ``iosystem`` run it.

The delayed runs take the undelayed design and give its spec a delay (the same tube and
gain, so the difference is the delay's alone)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import design_of

import control as ct

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.simulate import RungeKutta, hold_period
from stt_codegen.runtime.state_split import initial_state, positions

HERE = Path(__file__).resolve().parent
STEPS = 150


def _delayed(design, delay: float):
    """The design with its spec's ``[controller] delay`` set."""
    return dataclasses.replace(design, spec=dataclasses.replace(design.spec, delay=delay))


def _same_run(a, b) -> bool:
    """Two runs with the same floats at every sample."""
    return all(np.array_equal(getattr(a.trajectory, name), getattr(b.trajectory, name))
               for name in ("t", "x", "u", "alpha", "status"))


def test_a_zero_delay_is_the_undelayed_loop() -> None:
    design = design_of("omnirobot-s1")
    plain = stt.simulate(design, backend="reference", horizon=0.1)
    zero = stt.simulate(_delayed(design, 0.0), backend="reference", horizon=0.1)
    assert _same_run(plain, zero) and plain.max_abs_e == zero.max_abs_e


def test_a_fifth_of_a_period_stays_in_the_tube_and_changes_the_run() -> None:
    design = design_of("omnirobot-s1")
    assert design.tube.rate_hz == 1000.0
    plain = stt.simulate(design, backend="reference", horizon=0.3)
    late = stt.simulate(_delayed(design, 0.0002), backend="reference", horizon=0.3)
    assert late.stayed_in_tube and late.max_abs_e < 1.0
    assert np.array_equal(late.trajectory.x[0], plain.trajectory.x[0])
    assert np.max(np.abs(late.trajectory.x[1:] - plain.trajectory.x[1:])) > 1e-6


def test_a_delay_of_a_whole_period_breaks_a_fast_loop_at_a_low_rate() -> None:
    """line-s1 designed at 100 Hz (gain 4): its loop keeps the tube without a delay and with
    half a period of it, and leaves the tube when each command acts a period late."""
    spec = stt.load_spec(HERE / "specs" / "line-s1.toml")
    design = stt.design_tube(dataclasses.replace(spec, rate_hz=100.0))
    runs = {delay: stt.simulate(_delayed(design, delay), backend="reference", horizon=2.0)
            for delay in (0.0, 0.005, 0.01)}
    assert runs[0.0].stayed_in_tube and runs[0.005].stayed_in_tube
    assert runs[0.005].max_abs_e < 1.0
    assert not runs[0.01].stayed_in_tube
    late = runs[0.01].max_abs_e
    assert late is None or late > 10.0 * runs[0.0].max_abs_e


def test_the_first_command_acts_after_the_delay() -> None:
    """An integrator without disturbance: the input is zero on ``[0, d)``, ``u_0`` acts on
    ``[d, dt + d)``; Runge-Kutta is exact for it."""
    design = design_of("omnirobot-s1")
    dt, delay = 1.0 / design.tube.rate_hz, 0.0004
    integrator = ct.nlsys(lambda t, x, u, p: u, lambda t, x, u, p: x,
                          states=3, inputs=3, outputs=3)
    run = stt.simulate(_delayed(design, delay), backend="reference", horizon=3 * dt,
                       plant=integrator).trajectory
    assert np.any(run.u[0] != 0.0)
    np.testing.assert_allclose(run.x[1], run.x[0] + (dt - delay) * run.u[0], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(run.x[2], run.x[1] + delay * run.u[0] + (dt - delay) * run.u[1],
                               rtol=0, atol=1e-12)
    # the dense points of the first period: x(0) until d, then u_0's ramp
    stepper = RungeKutta(integrator)
    stepper.reset(run.x[0])
    points, times = hold_period(stepper, 0.0, np.zeros(3), run.u[0], dt, delay)
    assert np.all(np.diff(times) > 0) and times[-1] == pytest.approx(dt, abs=1e-15)
    early = times <= delay + 1e-15
    assert early.any() and np.all(np.abs(points[early] - run.x[0]) <= 1e-12)
    assert np.array_equal(points[-1], stepper.x)


@pytest.mark.parametrize("case, delay", [("omnirobot-s1", 0.0002), ("office-base", 0.0025)])
def test_the_interconnected_systems_give_the_delayed_run(case, delay) -> None:
    design = _delayed(design_of(case), delay)
    controller = stt.controller_system(design, backend="python")
    plant = stt.sampled_plant(design)
    states, inputs = initial_state(design.spec).size, design.spec.dimension
    assert plant.nstates == states + inputs and plant.noutputs == states
    assert plant.state_labels[states:] == [f"u_prev[{j}]" for j in range(inputs)]
    loop = ct.interconnect(
        [controller, plant], inplist=[],
        connections=[*([f"stt.x[{i}]", f"plant.x[{i}]"] for i in range(states)),
                     *([f"plant.u[{j}]", f"stt.u[{j}]"] for j in range(inputs))],
        outlist=[*(f"plant.x[{i}]" for i in range(states)),
                 *(f"stt.u[{j}]" for j in range(inputs)), "stt.status"])
    times = np.arange(STEPS + 1) * controller.dt
    x0 = np.concatenate([np.zeros(controller.nstates), initial_state(design.spec),
                         np.zeros(inputs)])
    response = ct.input_output_response(loop, times, 0, X0=x0)
    run = stt.simulate(design, backend="python", horizon=STEPS * controller.dt).trajectory
    assert np.array_equal(positions(design.spec, response.outputs[:states].T), run.x)
    assert np.array_equal(response.outputs[states:states + inputs].T, run.u)
    assert np.array_equal(response.states[:controller.nstates].T, run.alpha)
    assert np.array_equal(response.outputs[-1], run.status.astype(float))
    # the kept previous input is the command of the sample before
    assert np.array_equal(response.states[-inputs:, 1:].T, run.u[:-1])


def test_a_mujoco_plant_takes_a_delay_of_whole_timesteps_only() -> None:
    pytest.importorskip("mujoco", reason="MuJoCo is not installed")
    design = design_of("pointmaze-umaze")          # 100 Hz, timestep 1 ms
    with pytest.raises(SpecError) as info:
        stt.simulate(_delayed(design, 0.0015), backend="reference", horizon=0.05)
    assert info.value.field == "controller.delay" and "MuJoCo" in str(info.value)
    plain = stt.simulate(design, backend="reference", horizon=0.05)
    for delay in (0.002, 0.01):                     # two timesteps; a whole period
        late = stt.simulate(_delayed(design, delay), backend="reference", horizon=0.05)
        assert late.stayed_in_tube and not late.contacts
        assert np.array_equal(late.trajectory.u[0], plain.trajectory.u[0])
        assert not np.array_equal(late.trajectory.x, plain.trajectory.x)


@pytest.mark.slow
def test_the_jitter_is_drawn_seeded_within_its_bound_and_the_tube_is_kept() -> None:
    """omnirobot-s1 with 0.2 ms of jitter (certified: the sampled check passes with it):
    the reads move by up to the jitter, the run differs from the exact one and from another
    seed's, and keeps the tube with |e| within the check's bound at the samples."""
    from stt_codegen.design.certificate.sampled import sampled_check_of
    from stt_codegen.runtime.simulate import sampling_offsets
    design = design_of("omnirobot-s1")
    jittery = dataclasses.replace(design, spec=dataclasses.replace(design.spec, jitter=2e-4))
    check = sampled_check_of(design.tube, jittery.spec)[1]
    assert check.passed
    offsets = sampling_offsets(2e-4, 1000, 0)
    assert offsets[0] == 0.0 and np.max(np.abs(offsets)) <= 2e-4
    assert np.max(np.abs(offsets)) > 1.5e-4                  # the bound is reached for
    horizon = 2.0
    run = stt.simulate(jittery, backend="reference", horizon=horizon)
    again = stt.simulate(jittery, backend="reference", horizon=horizon)
    other = stt.simulate(jittery, backend="reference", horizon=horizon, seed=1)
    exact = stt.simulate(design, backend="reference", horizon=horizon)
    assert _same_run(run, again) and not _same_run(run, exact)
    assert not np.array_equal(run.trajectory.x, other.trajectory.x)
    assert run.stayed_in_tube and run.max_abs_e <= check.level
