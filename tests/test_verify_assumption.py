"""Assumption 2 (stt_codegen.proofs.assumption)."""

from __future__ import annotations

import math

import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

from stt_codegen.proofs import (
    assumption2_omnidirectional,
    assumption2_single_integrator,
    check_assumption2,
    symmetric_part,
)


def test_omnidirectional_symmetric_part() -> None:
    x3 = sp.Symbol("x3", real=True)
    c, s = sp.cos(x3), sp.sin(x3)
    gs = symmetric_part(sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]]))
    assert gs == sp.diag(c, c, 1)
    assert gs.eigenvals() == {c: 2, sp.Integer(1): 1}


def test_heading_range_inside_passes() -> None:
    c = assumption2_omnidirectional((-1.0, 1.0))
    assert c.passed
    assert c.data["g_lower"] == pytest.approx(math.cos(1.0), rel=1e-12)


def test_heading_range_reaching_half_pi_fails_with_point() -> None:
    c = assumption2_omnidirectional((0.0, 2.0))
    assert not c.passed
    assert c.data["lost_at"] == pytest.approx([math.pi / 2])
    assert "pi/2" in c.detail


def test_heading_range_touching_half_pi_in_floats_fails() -> None:
    c = assumption2_omnidirectional((-math.pi / 2, 0.3))  # cos = 6e-17 > 0 in doubles
    assert not c.passed
    assert c.data["lost_at"] == pytest.approx([-math.pi / 2])


def test_wide_range_reports_both_points() -> None:
    c = assumption2_omnidirectional((-4.0, 4.0))
    assert not c.passed
    assert c.data["lost_at"] == pytest.approx([-math.pi / 2, math.pi / 2])
    assert c.data["min_value"] == pytest.approx(-1.0)


def test_range_with_negative_cos_only() -> None:
    c = assumption2_omnidirectional((2.0, 3.0))
    assert not c.passed and c.data["lost_at"] == pytest.approx([3.0])


def test_single_integrator() -> None:
    c = assumption2_single_integrator(3)
    assert c.passed and c.data["g_lower"] == 1.0


def test_generic_nonsymmetric_plant() -> None:
    x1 = sp.Symbol("x1", real=True)
    g = sp.Matrix([[1, x1], [0, 1]])  # g_s eigenvalues 1 -+ x1/2
    ok = check_assumption2(g, {x1: (-1.0, 1.0)})
    assert ok.passed and ok.data["g_lower"] == pytest.approx(0.5)
    bad = check_assumption2(g, {x1: (0.0, 3.0)})
    assert not bad.passed and bad.data["lost_at"] == pytest.approx([2.0])
    missing = check_assumption2(g, {})
    assert not missing.passed and "no range" in missing.detail


@settings(max_examples=10, deadline=None)
@given(lo=st.floats(-1.5, 1.5), width=st.floats(0.0, 3.0))
def test_bound_is_min_cos(lo: float, width: float) -> None:
    hi = min(lo + width, 1.5)
    c = assumption2_omnidirectional((lo, hi))
    assert c.passed
    expected = min(math.cos(lo), math.cos(hi))
    assert c.data["g_lower"] == pytest.approx(expected, rel=1e-12)


def test_subnormal_width_range_is_decided() -> None:
    """Regression (found by hypothesis): [0, 2.2e-309] made SymPy raise TypeError when
    comparing the range's end with pi; the range is now snapped outward exactly."""
    c = assumption2_omnidirectional((0.0, 2.225073858507203e-309))
    assert c.passed and c.data["g_lower"] == pytest.approx(1.0, rel=1e-12)
