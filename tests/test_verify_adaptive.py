"""Adaptive law (11) (stt_codegen.proofs.adaptive)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from stt_codegen.proofs import (
    adaptive_law_checks,
    adversarial_psi_signals,
    alpha_rate_bound,
    alpha_upper_bound,
    check_adaptive_law_numeric,
    simulate_alpha,
)
from stt_codegen.proofs.adaptive import theta, theta_zero_threshold

CASE = dict(theta0=0.01, kappa=5.0, mu=1.0)  # section V


def test_symbolic_checks_pass() -> None:
    checks = adaptive_law_checks(-0.5, psi0=1.0, psi_dot_max=110.0, **CASE)
    assert [c.name for c in checks] == ["adaptive.parameters", "adaptive.nonnegative",
                                        "adaptive.upper_bound", "adaptive.singularity"]
    assert all(c.passed for c in checks), [str(c) for c in checks]
    sing = checks[-1]
    assert 0 < sing.data["y_min"] <= 1.0 and sing.data["alpha_dot_max"] > 0


def test_kappa_zero_rejected_as_unbounded() -> None:
    (c,) = adaptive_law_checks(-0.5, theta0=0.01, kappa=0.0, mu=1.0)
    assert not c.passed and "unbounded" in c.detail


@pytest.mark.parametrize("psi0", [-0.1, 0.0])
def test_nonpositive_psi0_fails(psi0: float) -> None:
    c = adaptive_law_checks(-0.5, psi0=psi0, **CASE)[-1]
    assert c.name == "adaptive.singularity" and not c.passed
    assert "Lemma 3.3 fails" in c.detail


def test_theta_zero_threshold() -> None:
    y = theta_zero_threshold()
    assert 18 < y < 20
    assert theta(CASE["mu"] + y, 1.0, CASE["mu"]) == 0.0
    assert theta(CASE["mu"] + np.nextafter(y, 0), 1.0, CASE["mu"]) > 0.0


@settings(max_examples=200, deadline=None)
@given(psi_min=st.floats(-3.0, 3.0), theta0=st.floats(1e-3, 1.0), kappa=st.floats(0.1, 20.0),
       mu=st.floats(0.05, 3.0))
def test_bound_is_certified_and_tight(psi_min: float, theta0: float, kappa: float,
                                      mu: float) -> None:
    a = alpha_upper_bound(psi_min, theta0, kappa, mu)
    assert a > max(0.0, -psi_min)
    ts = theta0 * (1 - np.tanh(psi_min - mu))
    f = lambda x: Fraction(kappa) * Fraction(x) * (Fraction(psi_min) + Fraction(x)) ** 2  # noqa: E731
    assert f(a) >= Fraction(float(ts)) * (1 - Fraction(1, 10**12))
    assert f(a * (1 - 1e-9)) < Fraction(float(ts))  # tight
    # the right-hand side of (11) is <= 0 at alpha_max for every psi >= psi_min
    for psi in psi_min + np.array([0.0, 1e-6, 0.1, 1.0, 10.0, 30.0]):
        rhs = theta(psi, theta0, mu) / (psi + a) ** 2 - kappa * a
        assert rhs <= 1e-12 * kappa * a


@pytest.mark.parametrize("psi_min", [pytest.param(-0.5, marks=pytest.mark.slow),
                                     pytest.param(0.3, marks=pytest.mark.slow), -2.0])
def test_numeric_adversarial(psi_min: float) -> None:
    c = check_adaptive_law_numeric(adversarial_psi_signals(1.0, psi_min), 6.0, **CASE)
    assert c.passed, c.detail
    per = c.data["signals"]
    assert per["hold"]["ratio"] > 0.999  # the bound is attained in the limit
    assert all(d["alpha_min"] >= -1e-12 for d in per.values())


def test_numeric_check_can_fail() -> None:
    # claiming psi_min = 0.5 while the signal goes down to -0.5 must be caught
    sig = adversarial_psi_signals(1.0, -0.5)
    c = check_adaptive_law_numeric({"hold": sig["hold"]}, 4.0, psi_min=0.5, **CASE)
    assert not c.passed and "> alpha_max" in c.detail


def test_rate_bound_holds_on_step() -> None:
    sig = adversarial_psi_signals(1.0, -0.5)["step"]  # slope <= 1.5 * 50 / 2
    y_min, ad_max = alpha_rate_bound(1.0, -0.5, 37.5, **CASE)
    t, al, ps = simulate_alpha(sig, 4.0, **CASE)
    assert (ps + al).min() >= y_min
    rhs = theta(ps, CASE["theta0"], CASE["mu"]) / (ps + al) ** 2 - CASE["kappa"] * al
    assert np.abs(rhs).max() <= ad_max


def test_theta_underflow_keeps_alpha_nonnegative() -> None:
    t, al, _ = simulate_alpha(lambda t: 25.0, 2.0, **CASE)
    assert np.all(al >= 0.0) and al.max() < 1e-4
