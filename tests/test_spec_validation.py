"""Every validation rule of the spec schema, fed bad input, names the field and the reason."""

from __future__ import annotations

import pytest
from conftest import arena_toml

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import load_spec, parse_spec

VALID = arena_toml("case-1", extra="[[obstacles]]\nlower = [2.0, 2.0]\nupper = [3.0, 3.0]\n")


def replace(old: str, new: str) -> str:
    assert old in VALID
    return VALID.replace(old, new)


def test_valid_spec_loads_with_defaults():
    spec = parse_spec(VALID)
    assert spec.dimension == 2
    assert spec.initial_state == (0.25, 0.25)
    assert spec.initial_half_width == pytest.approx((0.2, 0.2))
    assert spec.target_center == (4.75, 4.75)
    assert spec.tube.delta_b == 0.2 and spec.gain is None and spec.rate_hz == 1000.0
    assert spec.plant_model == "single-integrator"
    assert len(spec.source_hash) == 64


BAD = [
    # (spec text, field, fragment of the reason)
    ("name = 'x'\nprescribed_time = [", "", "malformed TOML"),
    ("extra = 1\n" + VALID, "extra", "unknown key"),
    (VALID + "\n[tube]\nwobble = 1.0\n", "tube.wobble", "unknown key"),
    (replace('name = "case-1"\n', ""), "name", "missing"),
    (replace("[target]\nlower = [4.5, 4.5]\nupper = [5.0, 5.0]\n", ""), "target", "missing"),
    (replace('name = "case-1"', 'name = 3'), "name", "must be a string"),
    (replace('name = "case-1"', 'name = "x\\"; system(\\"rm -rf /\\"); //"'), "name",
     "not an identifier"),
    (replace('name = "case-1"', 'name = "1abc"'), "name", "not an identifier"),
    (replace('name = "case-1"', 'name = "' + "a" * 65 + '"'), "name", "at most 64"),
    (replace("prescribed_time = 9.0", "prescribed_time = 0.0"), "prescribed_time",
     "must be positive"),
    (replace("prescribed_time = 9.0", "prescribed_time = -1"), "prescribed_time",
     "must be positive"),
    (replace("prescribed_time = 9.0", "prescribed_time = nan"), "prescribed_time",
     "must be finite"),
    (replace("prescribed_time = 9.0", "prescribed_time = inf"), "prescribed_time",
     "must be finite"),
    (replace("prescribed_time = 9.0", 'prescribed_time = "9"'), "prescribed_time",
     "must be a number"),
    (replace("prescribed_time = 9.0", "prescribed_time = true"), "prescribed_time",
     "must be a number"),
    (replace("prescribed_time = 9.0", "prescribed_time = 1e300"), "prescribed_time",
     "beyond 1e12"),
    (replace("lower = [0.0, 0.0]\nupper = [0.5, 0.5]", "lower = [0.0, 0.0, 0.0]\nupper = [0.5, 0.5]"),
     "initial.lower", "must have 2 entries"),
    (replace("upper = [5.0, 5.0]\n[initial]", "upper = [5.0]\n[initial]"),
     "state_space.upper", "must have 2 entries"),
    (replace("lower = [0.0, 0.0]\nupper = [5.0, 5.0]", "lower = [6.0, 0.0]\nupper = [5.0, 5.0]"),
     "state_space.lower", "exceeds upper"),
    (replace("lower = [0.0, 0.0]\nupper = [5.0, 5.0]", "lower = [5.0, 0.0]\nupper = [5.0, 5.0]"),
     "state_space.lower", "empty box"),
    (replace("lower = [0.0, 0.0]\nupper = [5.0, 5.0]", "lower = []\nupper = []"),
     "state_space.lower", "must not be empty"),
    (replace("[initial]\nlower = [0.0, 0.0]", "[initial]\nlower = [-1.0, 0.0]"), "initial",
     "not inside the state space"),
    (replace("[target]\nlower = [4.5, 4.5]\nupper = [5.0, 5.0]",
             "[target]\nlower = [4.5, 4.5]\nupper = [5.5, 5.0]"), "target",
     "not inside the state space"),
    (replace("upper = [0.5, 0.5]\n", "upper = [0.5, 0.5]\nstate = [0.6, 0.25]\n"),
     "initial.state", "not in the interior"),
    (replace("upper = [0.5, 0.5]\n", "upper = [0.5, 0.5]\nstate = [0.0, 0.25]\n"),
     "initial.state", "not in the interior"),
    (replace("upper = [0.5, 0.5]\n", "upper = [0.5, 0.5]\nhalf_width = [0.3, 0.1]\n"),
     "initial.half_width", "outside the initial set"),
    (replace("upper = [0.5, 0.5]\n", "upper = [0.5, 0.5]\nhalf_width = [0.0, 0.1]\n"),
     "initial.half_width", "must be positive"),
    (replace("upper = [5.0, 5.0]\n[[obstacles]]",
             "upper = [5.0, 5.0]\ncenter = [4.5, 4.75]\n[[obstacles]]"),
     "target.center", "not in the interior"),
    (replace("upper = [5.0, 5.0]\n[[obstacles]]",
             "upper = [5.0, 5.0]\nhalf_width = [0.2, 0.3]\n[[obstacles]]"),
     "target.half_width", "outside the target set"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [0.4, 0.4]\nupper = [3.0, 3.0]"),
     "obstacles[0]", "meets the initial set"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [2.0, 2.0]\nupper = [4.5, 4.5]"),
     "obstacles[0]", "meets the target set"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [2.0, 2.0]\nupper = [3.0, 6.0]"),
     "obstacles[0]", "not inside the state space"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [2.0, 2.0]\nupper = [3.0, 3.0]\ndims = [0, 0]"),
     "obstacles[0].dims", "repeats"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [2.0, 2.0]\nupper = [3.0, 3.0]\ndims = [0, 5]"),
     "obstacles[0].dims", "not a dimension index"),
    (replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]", "lower = [2.0, 2.0, 1.0]\nupper = [3.0, 3.0, 2.0]"),
     "obstacles[0].lower", "3 entries for a 2-dimensional"),
    (VALID + "\n[tube]\nkappa = 0.0\n", "tube.kappa", "must be positive"),
    (VALID + "\n[tube]\nsmoothness = -5\n", "tube.smoothness", "must be positive"),
    (VALID + "\n[tube]\ndelta_b = nan\n", "tube.delta_b", "must be finite"),
    (VALID + "\n[controller]\ngain = 0\n", "controller.gain", "must be positive"),
    (VALID + "\n[controller]\nrate_hz = -1\n", "controller.rate_hz", "must be positive"),
    (VALID + '\n[plant]\nmodel = "bicycle"\n', "plant.model", "must be one of"),
    (VALID + '\n[plant]\nmodel = "omnidirectional"\n', "plant.model", "has 3 states"),
    (VALID + "\n[plant]\ndisturbance_amplitude = -0.1\n", "plant.disturbance_amplitude",
     "non-negative"),
    (replace("[initial]", "initial = 3\n[initial_x]"), "initial_x", "unknown key"),
    (VALID + "\n[actuator]\ninput_bound = [2.0]\n", "actuator.input_bound",
     "must have 2 entries (one per input of the single-integrator plant: u1, u2), got 1"),
    (VALID + "\n[actuator]\ninput_bound = [2.0, 0.0]\n", "actuator.input_bound[1]",
     "must be positive"),
    (VALID + "\n[actuator]\ninput_bound = [2.0, -1]\n", "actuator.input_bound[1]",
     "must be positive"),
    (VALID + "\n[actuator]\ninput_bound = [2.0, inf]\n", "actuator.input_bound[1]",
     "must be finite"),
    (VALID + "\n[actuator]\ninput_bound = []\n", "actuator.input_bound", "must not be empty"),
    (VALID + "\n[actuator]\ninput_bound = 2.0\n", "actuator.input_bound",
     "must be an array of numbers"),
    (VALID + "\n[actuator]\n", "actuator.input_bound", "missing"),
    (VALID + "\n[actuator]\ninput_bound = [1.0, 1.0]\nmax_rate = 3\n", "actuator.max_rate",
     "unknown key (allowed: input_bound, reverse_speed)"),
    ("obstacles = 5\n" + VALID.replace("[[obstacles]]\nlower = [2.0, 2.0]\nupper = [3.0, 3.0]\n", ""),
     "obstacles", "must be an array"),
]


@pytest.mark.parametrize("text, field, reason", BAD, ids=[f"{b[1] or 'file'}-{i}"
                                                          for i, b in enumerate(BAD)])
def test_bad_input_names_field_and_reason(text, field, reason):
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert info.value.field == field, str(info.value)
    assert reason in info.value.reason, str(info.value)
    assert str(info.value).startswith(f"{field}: " if field else reason[:5])


def test_actuator_input_bound_one_per_input():
    """``[actuator] input_bound``: absent is ``None`` (no limit); given, one positive number
    per input of the plant model, whose input names the count's message uses."""
    assert parse_spec(VALID).input_bound is None
    assert load_spec("omnirobot-s1").input_bound is None
    assert parse_spec(VALID + "\n[actuator]\ninput_bound = [2, 0.5]\n").input_bound == (2.0, 0.5)
    from importlib import resources
    robot = resources.files("stt_codegen.cases").joinpath("omnirobot-s1.toml").read_text()
    assert parse_spec(robot + "\n[actuator]\ninput_bound = [2.0, 2.0, 1.0]\n"
                      ).input_bound == (2.0, 2.0, 1.0)
    with pytest.raises(SpecError) as info:
        parse_spec(robot + "\n[actuator]\ninput_bound = [2.0, 2.0]\n")
    assert info.value.field == "actuator.input_bound"
    assert info.value.reason == ("must have 3 entries (one per input of the omnidirectional "
                                 "plant: v1, v2, omega), got 2")


def test_missing_file_and_non_utf8(tmp_path):
    with pytest.raises(SpecError, match="no bundled case and no file"):
        load_spec(tmp_path / "absent.toml")
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"name = \"\xff\"\n")
    with pytest.raises(SpecError, match="not UTF-8"):
        load_spec(bad)


def test_file_and_bundled_name_give_the_same_spec(tmp_path):
    from importlib import resources
    text = resources.files("stt_codegen.cases").joinpath("omnirobot-s1.toml").read_text()
    path = tmp_path / "copy.toml"
    path.write_text(text)
    assert load_spec(path) == load_spec("omnirobot-s1")
    assert load_spec(path).source_hash == load_spec("omnirobot-s1").source_hash


def test_infinite_number_in_array():
    with pytest.raises(SpecError) as info:
        parse_spec(replace("[initial]\nlower = [0.0, 0.0]", "[initial]\nlower = [-inf, 0.0]"))
    assert info.value.field == "initial.lower[0]" and "finite" in info.value.reason


def test_plant_state_counts_come_from_the_one_registry():
    """A model that requires a state count is refused on another one, with the registry's
    reason, by the loader, by the simulation's plant factory and by ``verify --plant``."""
    from stt_codegen.runtime.plants import make_plant
    from stt_codegen.spec.plants import PLANTS, dimension_mismatch
    from stt_codegen.verification.command import verify
    fixed = [p for p in PLANTS.values() if p.states is not None]
    assert fixed and all(dimension_mismatch(p.name, p.states) is None for p in fixed)
    two_states = parse_spec(VALID)
    for plant in fixed:
        n = 2 if plant.states != 2 else 3
        reason = dimension_mismatch(plant.name, n)
        assert f"has {plant.states} states" in reason and str(n) in reason
        if n == 2:
            with pytest.raises(SpecError) as info:
                parse_spec(VALID + f'\n[plant]\nmodel = "{plant.name}"\n')
            assert (info.value.field, info.value.reason) == ("plant.model", reason)
            with pytest.raises(SpecError) as info:
                verify(two_states, plant=plant.name)
            assert (info.value.field, info.value.reason) == ("plant", reason)
        with pytest.raises(SpecError) as info:
            make_plant(plant.name, n, 0.1)
        assert (info.value.field, info.value.reason) == ("plant.model", reason)


@pytest.mark.parametrize("text, field, reason", [
    (replace("lower = [0.0, 0.0]\nupper = [5.0, 5.0]",
             "lower = [" + ", ".join(["0.0"] * 65) + "]\nupper = [" + ", ".join(["5.0"] * 65)
             + "]"), "state_space.lower", "65 dimensions; at most 64"),
    (VALID + "[[obstacles]]\nlower = [2.0, 2.0]\nupper = [3.0, 3.0]\n" * 4096, "obstacles",
     "4097 obstacles; at most 4096"),
    (VALID + "[[obstacles]]\nvertices = [" + ", ".join(["[1.0, 2.0]"] * 1025) + "]\n",
     "obstacles[1].vertices", "1025 vertices; at most 1024"),
], ids=["dimensions", "obstacles", "vertices"])
def test_size_limits_name_what_is_counted(text, field, reason):
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert (info.value.field, info.value.reason) == (field, reason)
