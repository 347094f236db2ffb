"""Error transform and Lyapunov identity (stt_codegen.proofs.transform)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

from stt_codegen.proofs import (
    check_epsilon_jacobian,
    check_lyapunov_derivative,
    error_transform_checks,
    outer_product_difference,
    xi_outer_product,
)


@pytest.mark.slow
def test_bundle_passes() -> None:
    checks = error_transform_checks(3)
    assert len(checks) == 7
    assert all(c.passed for c in checks), [str(c) for c in checks if not c.passed]


def test_outer_product_reading_is_not_the_jacobian() -> None:
    c = check_epsilon_jacobian(2, xi_outer_product)
    assert not c.passed
    assert (1, 2) in c.data["nonzero_entries"] and (2, 1) in c.data["nonzero_entries"]
    assert check_epsilon_jacobian(1, xi_outer_product).passed  # same for n = 1


def test_outer_product_difference_explicit() -> None:
    c = outer_product_difference(2)
    assert c.passed and c.data["differs"]
    e1, e2, g1 = sp.symbols("e1 e2 gamma_d1")
    diff = sp.sympify(c.data["difference"])
    # off-diagonal: -4 e1 e2 / (gamma_d1 (e1^2 + e2^2 - 1))
    assert sp.simplify(diff[0][1] + 4 * e1 * e2 / (g1 * (e1**2 + e2**2 - 1))) == 0
    assert not outer_product_difference(1).data["differs"]


def test_wrong_xi_fails_lyapunov() -> None:
    half = lambda e, gd: sp.diag(*[2 / (gd[i] * (1 - e[i] ** 2)) for i in range(len(e))])  # noqa: E731
    c = check_lyapunov_derivative(1, half)
    assert not c.passed and "eps1" in c.detail
    assert not check_epsilon_jacobian(1, half).passed


@settings(max_examples=40, deadline=None)
@given(
    x=st.lists(st.floats(-0.95, 0.95), min_size=3, max_size=3),
    gd=st.lists(st.floats(0.1, 5.0), min_size=3, max_size=3),
    gs=st.lists(st.floats(-5.0, 5.0), min_size=3, max_size=3),
)
def test_jacobian_numeric(x: list[float], gd: list[float], gs: list[float]) -> None:
    # x given through e in (-0.95, 0.95); central differences vs diagonal xi
    gd_a, gs_a = np.array(gd), np.array(gs)
    xs = (gd_a * np.array(x) + gs_a) / 2

    def eps(v: np.ndarray) -> np.ndarray:
        e = (2 * v - gs_a) / gd_a
        return np.log((1 + e) / (1 - e))

    h = 1e-7 * gd_a.min()
    jac = np.column_stack([(eps(xs + h * u) - eps(xs - h * u)) / (2 * h) for u in np.eye(3)])
    e = np.array(x)
    assert jac == pytest.approx(np.diag(4 / (gd_a * (1 - e**2))), rel=1e-5, abs=1e-5)
