"""The cascade law in closed loop on second-order plants (docs/second-order.md,
"Measured"), and its default gains."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import designed
from second_order_helpers import MASS_RANGE, as_double_integrator, planar_s1

import stt_codegen as stt
from stt_codegen.design.cascade_gain import SHAPES, derived_second_stage
from stt_codegen.errors import SpecError
from stt_codegen.runtime.plants import make_plant, second_order_plant
from stt_codegen.runtime.simulate import run_closed_loop
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
    r0 = cascade_reference.cascade_step(tube, stage, [[*tube.initial_state, *x2]], 0.0, dt,
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
    second = as_double_integrator(spec)
    for call, field in (
            (lambda: run_closed_loop(second, tube, stage=stage, backend="fortran"), "backend"),
            (lambda: run_closed_loop(second, tube, stage=stage, horizon=-1.0), "horizon"),
            (lambda: run_closed_loop(second, tube), "stage"),            # no second stage
            (lambda: run_closed_loop(spec, tube, stage=stage), "stage"),  # first order
            (lambda: run_closed_loop(second, tube, stage=stage,          # n states, not 2n
                                     plant=make_plant(
                                         "single-integrator", 3, 0.1)), "plant"),
            (lambda: second_order_plant("blimp", 3, [1.0], 0.1), "plant.model"),
            (lambda: second_order_plant("two-link-arm", 3, [1.0] * 7, 0.1), "plant.model"),
            (lambda: second_order_plant("double-integrator", 3, [1.0, 2.0], 0.1),
             "plant.parameters")):
        with pytest.raises(SpecError) as info:
            call()
        assert info.value.field == field


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("mass", MASS_RANGE)
def test_double_integrator_in_the_s1_arena_is_satisfied_with_the_c_backend(mass) -> None:
    spec, design, stage = planar_s1()
    result = run_closed_loop(as_double_integrator(spec, mass), design.tube, stage=stage,
                             backend="c", seed=3)
    assert result.satisfied, result.to_json()
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    assert result.reach_time <= spec.prescribed_time
    assert result.min_obstacle_clearance > 0


@pytest.mark.slow
@needs_cc
def test_backends_agree_on_the_closed_loop() -> None:
    spec, design, stage = planar_s1()
    runs = {b: run_closed_loop(as_double_integrator(spec), design.tube, stage=stage,
                               backend=b, horizon=0.3)
            for b in ("reference", "casadi", "python", "c")}
    base = runs["casadi"].trajectory
    for name in ("python", "c"):     # printed from the same Function: the same bits
        assert np.array_equal(runs[name].trajectory.u, base.u), name
    np.testing.assert_allclose(runs["reference"].trajectory.u, base.u, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(runs["reference"].trajectory.x, base.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(runs["reference"].trajectory.velocity, base.velocity, rtol=0,
                               atol=1e-9)


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("mass", [0.8, 1.6])
def test_quadrotor_among_pillars_is_satisfied(mass) -> None:
    spec = stt.load_spec("second-order-quadrotor")
    design = stt.design_tube(spec)
    drift = 9.81 + 0.4 * 3.0 / 0.8 + 0.2       # gravity, drag at 3 m/s for 0.8 kg, |w|
    stage, _ = derived_second_stage(design.tube, design.check.min_width, (1 / 1.6, 1 / 0.8),
                                    drift, np.zeros(3))
    plant = second_order_plant("quadrotor", 3, [mass, 0.4, 9.81], 0.2)
    result = run_closed_loop(spec, design.tube, stage=stage, plant=plant, backend="c")
    assert result.satisfied and result.stayed_in_velocity_tube, result.to_json()
    # hovering needs m g0 in the vertical thrust
    assert result.max_abs_u[2] >= mass * 9.81


@needs_cc
def test_the_c_backend_of_the_cascade_is_built_once_into_the_cache(tmp_path, monkeypatch) -> None:
    """The cascade's ``c`` backend compiles through the first order's build cache: a second
    controller of the same design loads the same library, without compiling again."""
    from stt_codegen.runtime.backends import make_controller
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path))
    _, design, stage = planar_s1()
    first = make_controller("c", design.tube, stage)
    built = sorted(tmp_path.glob("*.so"))
    assert len(built) == 1
    stamp = built[0].stat().st_mtime_ns
    second = make_controller("c", design.tube, stage)
    assert sorted(tmp_path.glob("*.so")) == built and built[0].stat().st_mtime_ns == stamp
    x = np.array([*design.tube.initial_state, 0.0, 0.0])
    a, b = (c.step(x, 0.0, 1e-3, np.zeros(4)) for c in (first, second))
    assert np.array_equal(a[0], b[0]) and a[2] == b[2]
