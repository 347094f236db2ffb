"""SymPy proofs of the cascade's second stage on the deployed expressions
(stt_codegen/proofs/cascade.py, docs/second-order.md)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import design_of

from stt_codegen.proofs import cascade as V


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
    # what is left is the term dropped from the claim: it has rho2's rate dP1 and neither
    # x2's nor r's (those terms cancel)
    assert not wrong.passed and wrong.detail.startswith("difference ")
    assert "dP1" in wrong.detail and "dX1" not in wrong.detail and "dR1" not in wrong.detail


@pytest.mark.slow
def test_every_cascade_check_passes_in_two_dimensions() -> None:
    checks = V.cascade_checks(2)
    assert [c.name for c in checks if not c.passed] == []
    assert len(checks) == 8


@pytest.mark.slow
def test_verify_of_a_second_order_spec_proves_the_lemmas_and_the_sampled_cascade():
    import stt_codegen as stt
    report = stt.verify(design_of("second-order-s1"))
    names = [c.name for c in report.checks]
    assert list(report.failed) == []
    assert "cascade.lyapunov_derivative.n2" in names and "cascade.velocity_tube" in names
    # law (13)'s sampled check is about a first-order plant: not run for the cascade, whose
    # plant is judged once against the class its certificate covers
    assert {n for n in names if n.startswith("sampled.")} == set()
    assert names.count("cascade.plant_within_assumptions") == 1
    assert "cascade.rate" not in names
    sampled = next(c for c in report.checks if c.name == "cascade.sampled")
    assert sampled.passed and "proved" in sampled.detail
    assert 0 < sampled.data["velocity_margin"] < 1 and 0 < sampled.data["position_margin"] < 1
    assert sampled.data["lowest_rate_hz"] <= 1000.0


def test_design_document_carries_the_cascade_figures_for_second_order_specs_only() -> None:
    import json

    import stt_codegen as stt
    document = design_of("second-order-quadrotor").to_json()
    cascade = json.loads(json.dumps(document))["cascade"]     # JSON-ready
    assert cascade["gains"]["certificate"]["passed"]
    assert cascade["gains"]["velocity_gain"] > 0
    assert "cascade" not in stt.design_tube(stt.load_spec("omnirobot-s1")).to_json()
