"""Lemma 3.3 pieces (stt_codegen.proofs.lemma)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

from stt_codegen.proofs import (
    Check,
    bump_rate_bound,
    check_bump_flatness,
    check_reach_continuity,
    check_smooth_max,
    lemma_checks,
    reach_rate_bound,
    reach_rate_constant,
)
from stt_codegen.proofs.lemma import K, M, R, T, T_C, TARGET, X0


@pytest.fixture(scope="module")
def bundle() -> list[Check]:
    return lemma_checks(orders=3, reach=[(0.0, 4.75, 9.0)], bumps=[(0.01, 1.0, 1.0)])


@pytest.mark.slow
def test_bundle_all_pass(bundle: list[Check]) -> None:
    names = [c.name for c in bundle]
    assert "lemma3.3.reach.continuity" in names and "lemma3.3.bump.flatness" in names
    assert all(c.passed for c in bundle), [str(c) for c in bundle if not c.passed]
    assert all(isinstance(c.detail, str) and c.detail for c in bundle)


def test_check_is_frozen() -> None:
    c = Check("x", True, "d", {})
    with pytest.raises(AttributeError):
        c.passed = False  # type: ignore[misc]


def test_reach_continuity_order4() -> None:
    c = check_reach_continuity(orders=4)
    assert c.passed
    assert c.data["limits"] == ["T", "0", "0", "0", "0"]


def test_reach_wrong_constant_in_branch_fails() -> None:
    wrong = (TARGET - X0) * sp.tanh(T / (T_C - T)) + TARGET
    c = check_reach_continuity(wrong, orders=2)
    assert not c.passed
    assert c.data["failed_order"] == 0
    assert sp.sympify(c.data["limit"]) == 2 * sp.Symbol("T") - sp.Symbol("X")


def test_reach_wrong_constant_branch_fails() -> None:
    c = check_reach_continuity(constant=X0, orders=1)
    assert not c.passed and c.data["failed_order"] == 0


def test_reach_linear_branch_not_c1() -> None:
    lin = (TARGET - X0) * T / T_C + X0
    c = check_reach_continuity(lin, orders=2)
    assert not c.passed
    assert c.data["failed_order"] == 1
    assert "not C^1" in c.detail


def test_bump_wrong_shapes_fail() -> None:
    parabola = 1 - (T - M) ** 2 / R**2  # 0 at the edges, but a kink
    c = check_bump_flatness(parabola, orders=2)
    assert not c.passed and c.data["failed_order"] == 1
    blowup = sp.exp(K * (T - M) ** 2 / (R**2 - (T - M) ** 2))  # wrong sign of k
    c = check_bump_flatness(blowup, orders=1)
    assert not c.passed and c.data["failed_order"] == 0


def test_reach_rate_constant_bracket() -> None:
    w, lo, hi = reach_rate_constant()
    assert (1 + w) * math.tanh(w) == pytest.approx(1.0, abs=1e-15)
    assert lo <= w * (2 + w) <= hi and hi - lo < 1e-14
    ws = np.linspace(0, 20, 2_000_001)
    assert np.max((1 + ws) ** 2 / np.cosh(ws) ** 2) <= hi


@pytest.mark.slow
def test_reach_rate_bound_case_study(bundle: list[Check]) -> None:
    c = next(c for c in bundle if c.name == "lemma3.3.reach.rate_bound")
    assert c.data["sampled_max"] <= c.data["bound"]
    assert c.data["bound"] - c.data["sampled_max"] < 1e-9 * c.data["bound"]
    assert c.data["t_star"] == pytest.approx(9 * 0.6837105 / 1.6837105, rel=1e-6)
    # an independent finite difference at t*
    t, h = c.data["t_star"], 1e-6
    rho = lambda s: 4.75 * np.tanh(s / (9 - s))  # noqa: E731
    assert abs(rho(t + h) - rho(t - h)) / (2 * h) == pytest.approx(c.data["bound"], rel=1e-8)


def test_reach_rate_bound_rejects_bad_tc() -> None:
    assert not reach_rate_bound(0.0, 1.0, 0.0).passed


@pytest.mark.slow
def test_bump_rate_bound_case_study(bundle: list[Check]) -> None:
    c = next(c for c in bundle if c.name == "lemma3.3.bump.rate_bound")
    assert c.data["bound"] == pytest.approx(109.0827787, rel=1e-8)
    assert c.data["sampled_max"] <= c.data["bound"]


@settings(max_examples=8, deadline=None)
@given(k=st.floats(1e-3, 20.0), r=st.floats(0.05, 10.0), height=st.floats(0.1, 5.0))
def test_bump_rate_bound_is_sup(k: float, r: float, height: float) -> None:
    c = bump_rate_bound(k, r, height)
    assert c.passed
    assert c.data["sampled_max"] <= c.data["bound"]
    assert c.data["sampled_max"] >= c.data["bound"] * (1 - 1e-6)
    assert 0 < c.data["q_star"] < 1


def test_bump_rate_bound_rejects_bad_k() -> None:
    assert not bump_rate_bound(0.0, 1.0).passed


def test_smooth_max_wrong_forms_fail() -> None:
    a, b = sp.symbols("a_1:3", real=True)
    nu = sp.Symbol("nu", positive=True)
    no_scale = sp.log(sp.exp(nu * a) + sp.exp(nu * b))
    c = check_smooth_max(no_scale)
    assert not c.passed and "sum to nu" in c.detail
    shifted = sp.log(sp.exp(nu * a) + sp.exp(nu * b)) / nu + 1
    c = check_smooth_max(shifted)
    assert not c.passed and "ln(2)/nu" in c.detail


@settings(max_examples=50, deadline=None)
@given(a=st.floats(-50, 50), b=st.floats(-50, 50), nu=st.floats(0.5, 200))
def test_smooth_max_bias_numeric(a: float, b: float, nu: float) -> None:
    s = max(a, b) + math.log1p(math.exp(-nu * abs(a - b))) / nu
    tol = 4 * np.finfo(float).eps * (abs(a) + abs(b) + 1)
    assert -tol <= s - max(a, b) <= math.log(2) / nu + tol
