"""Second-order plants written once in CasADi (runtime/second_order_plants.py), checked
against physics written independently here (docs/second-order.md)."""

from __future__ import annotations

import numpy as np
import pytest

from stt_codegen.codegen.emit import python_function
from stt_codegen.runtime.second_order_plants import (MODELS, SECOND_ORDER_MODELS,
                                                     input_matrix, model_info,
                                                     second_order_rhs)


def _call(model, n, x1, x2, u, w, params):
    out = second_order_rhs(model, n)(x1, x2, u, w, params)
    return np.array(out[0]).ravel(), np.array(out[1]).ravel()


def test_unknown_model_and_wrong_dimension_are_refused() -> None:
    with pytest.raises(ValueError, match="unknown second-order model"):
        model_info("unicycle", 2)
    with pytest.raises(ValueError, match="3 positions"):
        second_order_rhs("quadrotor", 2)
    assert set(MODELS) == set(SECOND_ORDER_MODELS)


def test_double_integrator_is_newton() -> None:
    rng = np.random.default_rng(0)
    for n in (1, 2, 3):
        x1, x2, u, w = (rng.normal(size=n) for _ in range(4))
        d1, d2 = _call("double-integrator", n, x1, x2, u, w, [2.5])
        np.testing.assert_allclose(d1, x2)
        np.testing.assert_allclose(d2, u / 2.5 + w, rtol=1e-15)


def test_quadrotor_hovers_on_m_g_and_drag_opposes_velocity() -> None:
    m, c, g0 = 1.3, 0.25, 9.81
    _, acc = _call("quadrotor", 3, [1, 2, 1], [0, 0, 0], [0, 0, m * g0], [0, 0, 0], [m, c, g0])
    np.testing.assert_allclose(acc, 0.0, atol=1e-14)
    v = np.array([1.0, -2.0, 0.5])
    _, acc = _call("quadrotor", 3, [0, 0, 0], v, [0, 0, m * g0], [0, 0, 0], [m, c, g0])
    np.testing.assert_allclose(acc, -c / m * v, rtol=1e-14)


def _arm_energy(q, dq, p):
    """Kinetic + potential energy of the two-link arm from the links' centres of mass
    (written here from the geometry, not from the Euler-Lagrange matrices)."""
    m1, m2, l1, l2, i1, i2, g0 = p
    c1, c2 = l1 / 2, l2 / 2
    v1 = c1 * dq[0] * np.array([-np.sin(q[0]), np.cos(q[0])])
    v2 = (l1 * dq[0] * np.array([-np.sin(q[0]), np.cos(q[0])])
          + c2 * (dq[0] + dq[1]) * np.array([-np.sin(q[0] + q[1]), np.cos(q[0] + q[1])]))
    kinetic = 0.5 * (m1 * v1 @ v1 + m2 * v2 @ v2 + i1 * dq[0] ** 2 + i2 * (dq[0] + dq[1]) ** 2)
    potential = g0 * (m1 * c1 * np.sin(q[0]) + m2 * (l1 * np.sin(q[0]) + c2 * np.sin(q[0] + q[1])))
    return kinetic + potential


@pytest.mark.parametrize("gravity", [0.0, 9.81])
def test_two_link_arm_conserves_energy_without_torque(gravity) -> None:
    p = [1.2, 0.8, 1.0, 0.7, 0.1, 0.05, gravity]
    rhs = python_function(second_order_rhs("two-link-arm", 2))

    def f(s):
        d1, d2 = rhs(s[:2].tolist(), s[2:].tolist(), [0.0, 0.0], [0.0, 0.0], p)
        return np.array(d1 + d2)

    s = np.array([0.3, 0.9, 1.5, -2.0])
    start = _arm_energy(s[:2], s[2:], p)
    h = 1e-3
    for _ in range(1000):
        k1 = f(s)
        k2 = f(s + h / 2 * k1)
        k3 = f(s + h / 2 * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert abs(_arm_energy(s[:2], s[2:], p) - start) < 1e-8 * max(1.0, abs(start))
    assert abs(s[2]) > 0.1           # it moved: the test is not vacuous


def test_two_link_arm_power_balance_with_torque() -> None:
    """d/dt energy = tau . q_dot (the input enters through M(q)^-1, symmetric)."""
    p = [1.0, 1.0, 1.0, 1.0, 1 / 12, 1 / 12, 9.81]
    q, dq, tau = np.array([0.2, 1.1]), np.array([0.7, -0.4]), np.array([2.0, -1.0])
    _, ddq = _call("two-link-arm", 2, q, dq, tau, [0, 0], p)
    h = 1e-6
    power = (_arm_energy(q + h * dq, dq + h * ddq, p)
             - _arm_energy(q - h * dq, dq - h * ddq, p)) / (2 * h)
    assert power == pytest.approx(tau @ dq, rel=1e-6)


@pytest.mark.parametrize("model,n", [("double-integrator", 2), ("quadrotor", 3),
                                     ("two-link-arm", 2)])
def test_input_matrix_is_symmetric_positive_definite(model, n) -> None:
    """Assumption 2 for the second stage, on random states and parameters near nominal."""
    rng = np.random.default_rng(1)
    g = input_matrix(model, n)
    nominal = np.array(model_info(model, n).nominal)
    for _ in range(200):
        params = nominal * rng.uniform(0.5, 2.0, nominal.size)
        matrix = np.array(g(rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), params))
        np.testing.assert_allclose(matrix, matrix.T, atol=1e-12)
        assert np.linalg.eigvalsh(matrix).min() > 0
