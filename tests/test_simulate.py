"""Closed loop: Definition 2.1 on the paper's cases, the plant integration, and the judging."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import design_of
from scipy.integrate import solve_ivp

from stt_codegen.runtime import backends
from stt_codegen.errors import SpecError
from stt_codegen.runtime.plants import Disturbance, check_seed, make_plant
from stt_codegen.runtime.simulate import RungeKutta, simulate
from stt_codegen.tube import reference as R


# the numpy reference runs the 9000 steps in about 10 s: its loop is slow-tier, and
# test_reference_and_casadi_loops_agree keeps it in the fast tier over 3 s
@pytest.mark.parametrize("backend", [pytest.param("reference", marks=pytest.mark.slow), "casadi"])
def test_paper_cases_are_satisfied(case, backend):
    design = design_of(case)
    spec = design.spec
    result = simulate(design, backend=backend)
    assert result.satisfied, result.to_json()
    assert result.reached and result.reach_time < spec.prescribed_time
    assert not result.collision and not result.left_state_space and result.stayed_in_tube
    assert result.min_obstacle_clearance > 0
    assert result.steps == 9000 and len(result.max_abs_u) == 3
    # the state keeps off the tube's wall (with a gain from a loose bound of the tube's
    # width it rode it at |e| = 0.81 on S2)
    assert 0.0 < result.max_abs_e <= 0.7, result.max_abs_e


@pytest.mark.slow
def test_reference_and_casadi_loops_agree():
    design = design_of("omnirobot-s2")
    a = simulate(design, backend="reference", horizon=3.0)
    b = simulate(design, backend="casadi", horizon=3.0)
    np.testing.assert_allclose(a.trajectory.x, b.trajectory.x, rtol=0, atol=1e-10)


def test_disturbance_is_bounded_deterministic_and_seeded():
    t = np.linspace(0, 50, 20001)
    w = Disturbance(3, 0.1, seed=4)
    values = np.array([w(s) for s in t])
    assert np.abs(values).max() <= 0.1 + 1e-15
    assert np.abs(values).max() > 0.05
    assert np.array_equal(values[:100], np.array([Disturbance(3, 0.1, seed=4)(s) for s in t[:100]]))
    assert not np.allclose(values[:100], [Disturbance(3, 0.1, seed=5)(s) for s in t[:100]])


def test_disturbance_kept_for_the_same_instant_is_the_value_computed_afresh():
    """Runge-Kutta asks w at each midpoint twice: the kept value is the fresh one, bit for
    bit, and cannot be changed by a caller."""
    w = Disturbance(3, 0.1, seed=4)
    for t in (0.25, 0.25, 0.5, 0.25):
        value = w(t)
        assert np.array_equal(value, Disturbance(3, 0.1, seed=4)(t))
        with pytest.raises(ValueError):
            value += 1.0


@pytest.mark.parametrize("model", ["omnidirectional", "single-integrator"])
def test_runge_kutta_step_equals_the_one_through_plant_dynamics(model):
    """The stepper calls the plant's update function directly: the same floats as RK4
    written with python-control's ``dynamics``, over several holds."""
    n = 3 if model == "omnidirectional" else 2
    plant = make_plant(model, n, 0.1, seed=3)
    stepper = RungeKutta(plant)
    x = stepper.reset(np.linspace(0.5, 1.5, n))
    rng = np.random.default_rng(1)
    dt, steps = 1e-3, 2
    for k in range(20):
        t, u = k * dt, rng.normal(0, 2, n)
        points, _ = stepper.advance(t, u, dt)
        h = dt / steps
        for m in range(steps):
            tm = t + m * h
            k1 = plant.dynamics(tm, x, u)
            k2 = plant.dynamics(tm + h / 2, x + h / 2 * k1, u)
            k3 = plant.dynamics(tm + h / 2, x + h / 2 * k2, u)
            k4 = plant.dynamics(tm + h, x + h * k3, u)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            assert np.array_equal(points[m], x)


def test_runge_kutta_hold_matches_an_adaptive_solver():
    """One sampling period of the plant with u held: RK4 against DOP853 at 1e-12."""
    plant = make_plant("omnidirectional", 3, 0.1, seed=1)
    rng = np.random.default_rng(0)
    x = np.array([1.0, 2.0, 0.3])
    dt = 1e-3
    worst = 0.0
    for k in range(200):
        u = rng.normal(0, 5, 3)
        t = k * dt
        stepper = RungeKutta(plant)
        stepper.reset(x)
        got = stepper.advance(t, u, dt)[0][-1]
        exact = solve_ivp(lambda s, y: plant.dynamics(s, y, u), (t, t + dt), x,
                          method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
        worst = max(worst, np.abs(got - exact).max())
        x = exact
    assert worst < 1e-11, worst


class _Stubborn:
    """A controller that outputs a fixed input: used to check the judging, not a controller."""

    name = "stubborn"

    def __init__(self, u):
        self.u = np.asarray(u, dtype=float)

    def step(self, x, t, dt, alpha):
        return self.u, alpha, backends.STATUS_OK


class _Lazy:
    """The reference controller's ``alpha`` and status, but no input."""

    name = "lazy"

    def __init__(self, design):
        self.inner = backends.make_controller("reference", design)

    def step(self, x, t, dt, alpha):
        u, alpha_next, status = self.inner.step(x, t, dt, alpha)
        return np.zeros_like(u), alpha_next, status


@pytest.mark.slow
def test_judging_reports_failures(monkeypatch):
    design = design_of("omnirobot-s1")
    monkeypatch.setitem(backends.first_order_backends(), "idle", lambda d: _Stubborn([0.0, 0.0, 0.0]))
    idle = simulate(design, backend="idle", horizon=1.0)
    assert not idle.satisfied and not idle.reached and idle.reach_time is None
    # straight east from S1 runs into O1 = [1, 2] x [4, 5]
    monkeypatch.setitem(backends.first_order_backends(), "east", lambda d: _Stubborn([1.0, 0.0, 0.0]))
    east = simulate(design, backend="east")
    assert east.collision and not east.satisfied and east.min_obstacle_clearance < 0
    # the normalized error is the state's, in the tube (here alpha follows the deployed
    # step and the state stays put): left behind by the tube, beyond 1
    monkeypatch.setitem(backends.first_order_backends(), "lazy", lambda d: _Lazy(d))
    lazy = simulate(design, backend="lazy", horizon=2.0)
    g_l, g_u, _, _ = R.adaptive_tube(design.tube, lazy.trajectory.t, lazy.trajectory.alpha)
    e = (2 * lazy.trajectory.x - (g_u + g_l)) / (g_u - g_l)
    assert lazy.max_abs_e == pytest.approx(float(np.abs(e).max()), rel=1e-12)
    assert lazy.max_abs_e > 1.0 and not lazy.stayed_in_tube
    # straight north leaves the state space
    monkeypatch.setitem(backends.first_order_backends(), "north", lambda d: _Stubborn([0.0, 1.0, 0.0]))
    north = simulate(design, backend="north", horizon=2.0)
    assert north.left_state_space and not north.satisfied


def test_short_horizon_cannot_satisfy():
    result = simulate(design_of("omnirobot-s3"), backend="casadi", horizon=2.0)
    assert result.steps == 2000 and not result.satisfied


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, True, "3"])
def test_the_seed_is_an_integer_in_32_bits(seed):
    design = design_of("omnirobot-s1")
    with pytest.raises(SpecError) as info:
        simulate(design, backend="casadi", horizon=0.1, seed=seed)
    assert info.value.field == "seed"
    assert info.value.reason == f"must be an integer in [0, 2**32), got {seed!r}"


def test_the_largest_seed_and_numpy_integers_are_seeds():
    design = design_of("omnirobot-s1")
    assert simulate(design, backend="casadi", horizon=0.1, seed=np.uint32(2**32 - 1)).steps == 100
    assert check_seed(np.int64(7)) == 7 and type(check_seed(np.int64(7))) is int
