"""SymPy proofs of the cascade's second stage on the deployed expressions
(stt_codegen/verify/cascade.py, docs/second-order.md)."""

from __future__ import annotations

import numpy as np
import pytest

from stt_codegen.verify import cascade as V


def test_deployed_second_stage_equals_its_formulas_and_pushes_back() -> None:
    assert V.check_transform(1).passed
    assert V.check_jacobian(1).passed
    check = V.check_pushes_back()
    assert check.passed, check.detail
    assert "w" in check.data["xi2"]


def test_velocity_tube_bounds_are_proved() -> None:
    check = V.check_velocity_tube()
    assert check.passed, check.detail


@pytest.mark.slow
def test_lyapunov_identity_holds_and_a_wrong_one_is_refused() -> None:
    assert V.check_lyapunov_derivative(1).passed
    wrong = V.check_lyapunov_derivative(1, tube_rate=False)
    assert not wrong.passed and "Derivative" in wrong.detail


@pytest.mark.slow
def test_every_cascade_check_passes_in_two_dimensions() -> None:
    checks = V.cascade_checks(2)
    assert [c.name for c in checks if not c.passed] == []
    assert len(checks) == 8


def test_what_is_not_proved_is_said() -> None:
    assert "sampled cascade" in V.NOT_PROVED and "not certified" in V.NOT_PROVED


@pytest.mark.slow
def test_verify_of_a_second_order_spec_proves_the_lemmas_and_fails_on_the_sampled_cascade():
    import stt_codegen as stt
    report = stt.verify(stt.design_tube(stt.load_spec("second-order-s1")))
    names = [c.name for c in report.checks]
    assert [c.name for c in report.failed] == ["cascade.sampled"]
    assert "cascade.lyapunov_derivative.n2" in names and "cascade.velocity_tube" in names
    # law (13)'s sampled check is about a first-order plant: not run for the cascade (the
    # stand-in [plant]'s bounds check remains)
    assert {n for n in names if n.startswith("sampled.")} == {"sampled.plant_within_assumptions"}
    rate = next(c for c in report.checks if c.name == "cascade.rate")
    assert rate.passed and "not a certificate" in rate.detail


def test_slopes_of_the_transform_and_the_law_follow_their_formulas() -> None:
    from stt_codegen.design.cascade_gain import law_slope_growth, transform_slope_growth
    assert transform_slope_growth(0.0) == 1.0 and law_slope_growth(0.0) == 1.0
    e, h = 0.7, 1e-6
    eps = lambda v: np.log((1 + v) / (1 - v))          # noqa: E731
    u = lambda v: eps(v) / (1 - v * v)                  # xi2 eps2 up to 2 k2 / rho2^2
    assert transform_slope_growth(e) == pytest.approx((eps(e + h) - eps(e - h)) / (4 * h),
                                                      rel=1e-6)
    assert law_slope_growth(e) == pytest.approx((u(e + h) - u(e - h)) / (4 * h), rel=1e-6)


@pytest.mark.parametrize("name", ["second-order-s1", "second-order-quadrotor"])
def test_cascade_rate_passes_at_the_bundled_rate_and_fails_below_the_lowest(name) -> None:
    import stt_codegen as stt
    design = stt.design_tube(stt.load_spec(name))
    spec, tube, width = design.spec, design.tube, design.check.min_width
    check = V.cascade_rate_check(spec, tube, width)
    assert check.passed, check.detail
    data = check.data
    assert data["rate_hz"] == tube.rate_hz and data["rate_ratio"] > 1
    assert -1 < min(data["inner_factors_grown"]) and max(data["inner_factors"]) < 1
    assert -1 < data["outer_factor"] < 1
    assert "linearized estimate, not a certificate" in check.detail
    # the same gains at a rate below the lowest: a factor leaves (-1, 1), the check fails
    slow = V.cascade_rate_check(spec, tube, width, rate_hz=0.9 * data["lowest_rate_hz"])
    assert not slow.passed and "is below it" in slow.detail
    assert min(slow.data["inner_factors_grown"]) < -1
    assert slow.data["lowest_rate_hz"] == pytest.approx(data["lowest_rate_hz"])
    just = V.cascade_rate_check(spec, tube, width, rate_hz=data["lowest_rate_hz"] * (1 + 1e-9))
    assert just.passed and min(just.data["inner_factors_grown"]) > -1


def test_design_document_carries_the_cascade_figures_for_second_order_specs_only() -> None:
    import json

    import stt_codegen as stt
    document = stt.design_tube(stt.load_spec("second-order-quadrotor")).to_json()
    cascade = json.loads(json.dumps(document))["cascade"]     # JSON-ready
    assert cascade["rate"]["passed"] and cascade["rate"]["rate_ratio"] > 1
    assert cascade["gains"]["velocity_gain"] > 0
    assert "cascade" not in stt.design_tube(stt.load_spec("omnirobot-s1")).to_json()
