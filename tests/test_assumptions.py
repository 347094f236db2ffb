"""``[assumptions]`` and the ``linear`` plant in the spec loader: defaults,
values, and one ``SpecError`` naming the field for every rule."""

from __future__ import annotations

import math

import pytest

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import Assumptions, load_spec, parse_spec

BASE = """
name = "plant-test"
prescribed_time = 5.0
[state_space]
lower = [0.0, 0.0]
upper = [4.0, 4.0]
[initial]
lower = [0.0, 0.0]
upper = [1.0, 1.0]
[target]
lower = [3.0, 3.0]
upper = [4.0, 4.0]
"""


def spec_with(text: str):
    return parse_spec(BASE + text)


def rejected(text: str) -> SpecError:
    with pytest.raises(SpecError) as info:
        spec_with(text)
    return info.value


def test_defaults_reproduce_the_former_behaviour():
    spec = spec_with("[plant]\ndisturbance_amplitude = 0.2\n")
    a = spec.assumptions
    assert a.input_gain == (1.0, 1.0) and a.input_gain_skew == 0.0
    assert a.input_gain_coupling == 0.0 and a.drift_bound == 0.0
    assert a.disturbance_bound == pytest.approx(math.sqrt(2) * 0.2)
    assert a.declared == ()
    robot = load_spec("omnirobot-s2").assumptions          # the model's own bounds
    assert robot.input_gain[0] == pytest.approx(math.cos(1.2)) and robot.input_gain[1] == 1.0


def test_declared_values_and_the_implied_coupling():
    spec = spec_with("[assumptions]\ninput_gain = [0.5, 3]\ninput_gain_skew = 0.25\n"
                     "drift_bound = 2\ndisturbance_bound = 0.4\n")
    a = spec.assumptions
    assert a.input_gain == (0.5, 3.0) and a.input_gain_skew == 0.25
    assert a.input_gain_coupling == pytest.approx(1.25 + 0.25)   # (g_max - g_min)/2 + skew
    assert (a.drift_bound, a.disturbance_bound) == (2.0, 0.4)
    assert set(a.declared) == {"input_gain", "input_gain_skew", "drift_bound",
                               "disturbance_bound"}
    tight = spec_with("[assumptions]\ninput_gain = [0.5, 3]\ninput_gain_coupling = 0.1\n")
    assert tight.assumptions.input_gain_coupling == 0.1
    loose = spec_with("[assumptions]\ninput_gain = [0.5, 1]\ninput_gain_coupling = 9\n")
    assert loose.assumptions.input_gain_coupling == 0.25          # implied bound is smaller


@pytest.mark.parametrize("text, field, words", [
    ("input_gain = [0.0, 1.0]", "assumptions.input_gain", "positive (Assumption 2)"),
    ("input_gain = [-1, 1.0]", "assumptions.input_gain", "positive"),
    ("input_gain = [2.0, 1.0]", "assumptions.input_gain", "exceeds"),
    ("input_gain = [1.0]", "assumptions.input_gain", "two numbers"),
    ("input_gain = 1.0", "assumptions.input_gain", "two numbers"),
    ('input_gain = [1.0, "2"]', "assumptions.input_gain[1]", "number"),
    ("input_gain = [1.0, inf]", "assumptions.input_gain[1]", "finite"),
    ("input_gain_skew = -0.1", "assumptions.input_gain_skew", "non-negative"),
    ("input_gain_coupling = -1", "assumptions.input_gain_coupling", "non-negative"),
    ("drift_bound = -2", "assumptions.drift_bound", "non-negative"),
    ("disturbance_bound = true", "assumptions.disturbance_bound", "number"),
    ("gain_bounds = [1, 2]", "assumptions.gain_bounds", "unknown key"),
])
def test_assumption_rules(text, field, words):
    error = rejected("[assumptions]\n" + text + "\n")
    assert error.field == field and words in error.reason


def test_linear_plant_defaults_and_values():
    spec = spec_with('[plant]\nmodel = "linear"\n')
    assert spec.linear_plant.a == ((0.0, 0.0), (0.0, 0.0))
    assert spec.linear_plant.g == ((1.0, 0.0), (0.0, 1.0))
    assert spec.linear_plant.c == (0.0, 0.0)
    spec = spec_with('[plant]\nmodel = "linear"\na = [[0, 1], [-1, 0]]\n'
                     'g = [[2, 0.5], [0, 1]]\nc = [0.1, -0.2]\n')
    assert spec.linear_plant.a == ((0.0, 1.0), (-1.0, 0.0))
    assert spec.linear_plant.g == ((2.0, 0.5), (0.0, 1.0)) and spec.linear_plant.c == (0.1, -0.2)
    assert spec_with("").linear_plant is None


@pytest.mark.parametrize("text, field, words", [
    ("g = [[1, 0], [0, 1], [0, 0]]", "plant.g", "must have 2 rows"),
    ("g = [[1, 0, 0], [0, 1, 0]]", "plant.g[0]", "must have 2 entries"),
    ("a = [[1, 0], [0]]", "plant.a[1]", "must have 2 entries"),
    ("a = [1, 0]", "plant.a", "rows"),
    ("a = 3", "plant.a", "rows"),
    ("c = [1, 2, 3]", "plant.c", "must have 2 entries"),
    ('g = [[1, 0], [0, "x"]]', "plant.g[1][1]", "number"),
    ("g = [[1, 0], [0, nan]]", "plant.g[1][1]", "finite"),
    ("d = [[1, 0], [0, 1]]", "plant.d", "unknown key"),
])
def test_linear_plant_shapes(text, field, words):
    error = rejected('[plant]\nmodel = "linear"\n' + text + "\n")
    assert error.field == field and words in error.reason


def test_matrices_need_the_linear_model():
    error = rejected("[plant]\ng = [[1, 0], [0, 1]]\n")
    assert error.field == "plant.g" and "only the linear model" in error.reason


def test_wrong_shape_on_the_command_line_is_exit_2(tmp_path):
    import subprocess
    import sys
    path = tmp_path / "bad.toml"
    path.write_text(BASE + '[plant]\nmodel = "linear"\ng = [[1, 0, 0], [0, 1, 0]]\n')
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "verify", str(path)],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 2 and "plant.g[0]" in out.stderr and "Traceback" not in out.stderr


def test_assumptions_dataclass_is_frozen():
    with pytest.raises(AttributeError):
        Assumptions().drift_bound = 1.0  # type: ignore[misc]
