"""Named plants declare their own bounds: what a model implies over a box, and
how ``[assumptions]`` combines with it (contradictions are a ``SpecError`` naming the key)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import LinearPlant, load_spec, parse_spec
from stt_codegen.spec.model_bounds import (abs_sin_max, cos_range, linear_drift_bound,
                                           model_bounds, symmetric_eigen_range)

ROBOT = """
name = "robot"
prescribed_time = 9.0
[state_space]
lower = [0.0, 0.0, -1.2]
upper = [5.0, 5.0, 1.2]
[initial]
lower = [0.0, 4.5, -0.1]
upper = [0.5, 5.0, 0.1]
[target]
lower = [4.5, 4.5, -1.2]
upper = [5.0, 5.0, 1.2]
[plant]
model = "omnidirectional"
"""


def robot(extra: str = ""):
    return parse_spec(ROBOT + extra)


def test_the_robot_declares_its_bounds_from_the_heading_range():
    a = load_spec("omnirobot-s1").assumptions
    assert a.model == "omnidirectional" and a.declared == ()
    assert a.input_gain[0] == pytest.approx(math.cos(1.2), abs=1e-11)
    assert a.input_gain[0] <= math.cos(1.2) and a.input_gain[1] == 1.0   # outward
    assert a.input_gain_skew == pytest.approx(math.sin(1.2)) and a.input_gain_skew >= math.sin(1.2)
    assert a.input_gain_coupling == a.input_gain_skew and a.drift_bound == 0.0
    assert a.blocks == ((0, 1), (2,))
    assert a.disturbance_bound == pytest.approx(math.sqrt(3) * 0.1)


@pytest.mark.parametrize("lo, hi", [(-1.2, 1.2), (0.3, 1.1), (-1.5, -0.2), (2.0, 4.0),
                                    (-7.0, -6.0), (0.0, 0.0), (-3.2, 3.2)])
def test_cos_and_sin_ranges_match_dense_sampling(lo, hi):
    theta = np.linspace(lo, hi, 200001)
    c_min, c_max = cos_range(lo, hi)
    assert c_min <= np.cos(theta).min() + 1e-15 and c_max >= np.cos(theta).max() - 1e-15
    assert c_min == pytest.approx(np.cos(theta).min(), abs=1e-9)
    assert c_max == pytest.approx(np.cos(theta).max(), abs=1e-9)
    assert abs_sin_max(lo, hi) == pytest.approx(np.abs(np.sin(theta)).max(), abs=1e-9)


def test_a_heading_range_reaching_half_pi_gives_a_nonpositive_g_min_not_an_error():
    b = model_bounds("omnidirectional", (0, 0, -math.pi), (1, 1, 0.5))
    assert b.input_gain[0] <= -1.0 + 1e-9 and b.input_gain_skew == pytest.approx(1.0)


def test_linear_bounds_match_numpy():
    rng = np.random.default_rng(5)
    for n in (1, 2, 3, 5):
        g = rng.normal(size=(n, n))
        a = rng.normal(size=(n, n))
        c = rng.normal(size=n)
        lower, upper = -rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n)
        b = model_bounds("linear", lower, upper, LinearPlant(a.tolist(), g.tolist(), c.tolist()))
        eig = np.linalg.eigvalsh((g + g.T) / 2)
        assert b.input_gain[0] <= eig[0] and b.input_gain[1] >= eig[-1]
        assert b.input_gain == pytest.approx((eig[0], eig[-1]), abs=1e-9)
        skew = np.linalg.norm((g - g.T) / 2, 2)
        assert skew <= b.input_gain_skew == pytest.approx(skew, abs=1e-9)
        off = g - np.diag(np.diag(g))
        assert b.input_gain_coupling == pytest.approx(np.linalg.norm(off, axis=1).max())
        x = rng.uniform(lower, upper, size=(20000, n))
        assert np.linalg.norm(x @ a.T + c, axis=1).max() <= b.drift_bound


def test_jacobi_eigenvalues_of_ill_conditioned_matrices():
    g = np.diag([1e-6, 1.0, 1e6]) + 1e-3 * np.ones((3, 3))
    lo, hi, skew = symmetric_eigen_range(g.tolist())
    eig = np.linalg.eigvalsh(g)
    assert lo <= eig[0] and hi >= eig[-1] and skew < 1e-5
    assert hi == pytest.approx(eig[-1], rel=1e-11)


def test_drift_bound_beyond_the_exact_dimensions_is_an_upper_bound():
    rng = np.random.default_rng(2)
    n = 12
    a, c = rng.normal(size=(n, n)), rng.normal(size=n)
    bound = linear_drift_bound(a.tolist(), c.tolist(), [-1.0] * n, [1.0] * n)
    corners = rng.choice([-1.0, 1.0], size=(4000, n))
    assert np.linalg.norm(corners @ a.T + c, axis=1).max() <= bound


def test_linear_blocks_follow_the_zero_pattern():
    g = [[1, 0, 0.2, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0.1, 0, 1]]
    b = model_bounds("linear", [0] * 4, [1] * 4, LinearPlant([[0] * 4] * 4, g, [0] * 4))
    assert b.blocks == ((0, 2), (1, 3))
    assert model_bounds("single-integrator", [0] * 3, [1] * 3).blocks == ((0,), (1,), (2,))


@pytest.mark.parametrize("text, field, model_value", [
    ("input_gain = [0.5, 1.0]", "assumptions.input_gain", "0.362357754"),
    ("input_gain = [0.3, 0.9]", "assumptions.input_gain", "1"),
    ("input_gain_skew = 0.5", "assumptions.input_gain_skew", "0.932039086"),
    ("input_gain_coupling = 0.0", "assumptions.input_gain_coupling", "0.932039086"),
])
def test_a_declared_bound_the_model_violates_is_a_spec_error(text, field, model_value):
    with pytest.raises(SpecError) as info:
        robot("[assumptions]\n" + text + "\n")
    assert info.value.field == field
    assert model_value in info.value.reason and "omnidirectional" in info.value.reason
    assert "heading range" in info.value.reason


def test_a_declared_bound_wider_than_the_model_is_used_and_noted():
    a = robot("[assumptions]\ninput_gain = [0.3, 1.2]\ndrift_bound = 0.5\n").assumptions
    assert a.input_gain == (0.3, 1.2) and a.drift_bound == 0.5
    assert a.input_gain_skew == pytest.approx(math.sin(1.2))          # the model's
    assert a.input_gain_coupling == pytest.approx(0.45 + a.input_gain_skew)  # implied
    assert a.blocks == ((0, 1, 2),)          # a declared g drops the model's structure
    assert len(a.notes) == 2 and "wider than the omnidirectional model" in a.notes[0]


def test_the_model_value_typed_back_is_not_a_contradiction():
    a = robot(f"[assumptions]\ninput_gain = [{math.cos(1.2)!r}, 1.0]\n").assumptions
    assert a.input_gain[0] <= math.cos(1.2)


def test_an_unknown_plant_declared_on_the_default_model_works_as_before():
    text = ROBOT.replace('model = "omnidirectional"', 'model = "single-integrator"')
    a = parse_spec(text + "[assumptions]\ninput_gain = [0.5, 3]\ninput_gain_coupling = 0\n"
                   "drift_bound = 1\n").assumptions
    assert (a.input_gain, a.input_gain_coupling, a.drift_bound) == ((0.5, 3.0), 0.0, 1.0)
    assert a.coupled_blocks(3) == ((0,), (1,), (2,))
    with pytest.raises(SpecError) as info:
        parse_spec(text + "[assumptions]\ninput_gain = [1.5, 2]\n")
    assert info.value.field == "assumptions.input_gain" and "linear" in info.value.reason


def test_with_plant_model_derives_the_bounds_again():
    spec = load_spec("omnirobot-s1").with_plant_model("single-integrator")
    assert spec.plant_model == "single-integrator"
    assert spec.assumptions.input_gain == (1.0, 1.0) and spec.assumptions.blocks[2] == (2,)
    wider = robot("[assumptions]\ninput_gain = [0.3, 1]\n").with_plant_model("linear")
    assert wider.assumptions.input_gain == (0.3, 1.0)        # g = I lies within it
    text = ROBOT.replace('model = "omnidirectional"', 'model = "single-integrator"')
    exact = parse_spec(text + "[assumptions]\ninput_gain = [1, 1]\n")
    with pytest.raises(SpecError) as info:
        exact.with_plant_model("omnidirectional")   # cos(1.2) < 1: the robot violates it
    assert info.value.field == "assumptions.input_gain"
