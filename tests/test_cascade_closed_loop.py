"""The cascade law in closed loop on second-order plants (docs/second-order.md,
"Measured"), and its default gains."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import designed
from second_order_helpers import MASS_RANGE, planar_s1

import stt_codegen as stt
from stt_codegen.design.cascade_gain import SHAPES, derived_second_stage
from stt_codegen.errors import SpecError
from stt_codegen.runtime.cascade_simulate import simulate_second_order
from stt_codegen.tube import cascade_reference

CC = shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (install gcc or clang)")


def test_default_gains_follow_the_declared_bounds() -> None:
    _, tube, check = designed("omnirobot-s1")
    x2 = np.array([0.3, -0.2, 0.0])
    stage, info = derived_second_stage(tube, check.min_width, (0.5, 2.0), 1.0, x2)
    dt = 1.0 / tube.rate_hz
    floor = stage.width_floor[0]
    # the inner loop's linearized step at g_max, and the time-scale separation
    assert 4 * stage.velocity_gain * 2.0 / floor**2 * dt == pytest.approx(SHAPES[0][0])
    assert 16 * stage.position_gain / check.min_width**2 == pytest.approx(info["omega2_min"] / 10)
    # rho2(0) contains the initial velocity error with the floor to spare
    r0 = cascade_reference.cascade_step(tube, stage, [tube.initial_state], [x2], 0.0, dt,
                                        np.zeros((1, 6)))[2][0]
    assert np.all(np.array(stage.width_start) - np.abs(x2 - r0) == pytest.approx(floor))
    assert all(type(v) is float for v in (info["width_floor"], info["tube_speed"]))
    with pytest.raises(ValueError, match="g_min"):
        derived_second_stage(tube, check.min_width, (0.0, 1.0), 1.0, x2)
    with pytest.raises(ValueError, match="3 entries"):
        derived_second_stage(tube, check.min_width, (1.0, 1.0), 1.0, x2[:2])


def test_bad_simulation_input_names_the_field() -> None:
    spec, tube, _ = designed("omnirobot-s1")
    stage, _ = derived_second_stage(tube, 0.05, (1.0, 1.0), 0.1, np.zeros(3))
    for kwargs, field in (({"backend": "fortran"}, "backend"), ({"model": "blimp"}, "plant.model"),
                          ({"model": "two-link-arm"}, "plant.model"),
                          ({"params": [1.0, 2.0]}, "params"),
                          ({"initial_velocity": [0.0]}, "initial.velocity"),
                          ({"horizon": -1.0}, "horizon")):
        with pytest.raises(SpecError) as info:
            simulate_second_order(spec, tube, stage, **kwargs)
        assert info.value.field == field


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("mass", MASS_RANGE)
def test_double_integrator_in_the_s1_arena_is_satisfied_with_the_c_backend(mass) -> None:
    spec, design, stage = planar_s1()
    result = simulate_second_order(spec, design.tube, stage, model="double-integrator",
                                   params=[mass], backend="c", seed=3)
    assert result.satisfied, result.to_json()
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    assert result.reach_time <= spec.prescribed_time
    assert result.min_obstacle_clearance > 0


@pytest.mark.slow
@needs_cc
def test_backends_agree_on_the_closed_loop() -> None:
    spec, design, stage = planar_s1()
    runs = {b: simulate_second_order(spec, design.tube, stage, params=[1.0], backend=b,
                                     horizon=0.3)
            for b in ("reference", "casadi", "python", "c")}
    base = runs["casadi"].trajectory
    for name in ("python", "c"):     # printed from the same Function: the same bits
        assert np.array_equal(runs[name].trajectory.u, base.u), name
    np.testing.assert_allclose(runs["reference"].trajectory.u, base.u, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(runs["reference"].trajectory.x1, base.x1, rtol=0, atol=1e-12)


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("mass", [0.8, 1.6])
def test_quadrotor_among_pillars_is_satisfied(mass) -> None:
    spec = stt.load_spec("second-order-quadrotor")
    design = stt.design_tube(spec)
    drift = 9.81 + 0.4 * 3.0 / 0.8 + 0.2       # gravity, drag at 3 m/s for 0.8 kg, |w|
    stage, _ = derived_second_stage(design.tube, design.check.min_width, (1 / 1.6, 1 / 0.8),
                                    drift, np.zeros(3))
    result = simulate_second_order(spec, design.tube, stage, model="quadrotor",
                                   params=[mass, 0.4, 9.81], disturbance_amplitude=0.2,
                                   backend="c")
    assert result.satisfied and result.stayed_in_velocity_tube, result.to_json()
    # hovering needs m g0 in the vertical thrust
    assert result.max_abs_u[2] >= mass * 9.81
