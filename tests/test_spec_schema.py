"""The spec schema (pydantic v2): ``stt-codegen schema`` is a JSON Schema that tools can use,
it accepts the bundled specs and rejects what the loader rejects structurally."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from pathlib import Path

import pytest
from conftest import arena_toml

from stt_codegen.cases import bundled_cases, bundled_spec_bytes
from stt_codegen.cli import main
from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import parse_spec
from stt_codegen.spec.schema import check_document

jsonschema = pytest.importorskip("jsonschema", reason="install the Python package jsonschema "
                                                      "(in the test extra)")
SPECS = Path(__file__).parent / "specs"


@pytest.fixture(scope="module")
def validator():
    import contextlib
    import io
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["schema"]) == 0
    schema = json.loads(out.getvalue())
    cls = jsonschema.validators.validator_for(schema)
    assert cls is jsonschema.Draft7Validator          # the dialect it declares
    cls.check_schema(schema)
    return cls(schema)


def _documents():
    docs = {name: tomllib.loads(bundled_spec_bytes(name).decode()) for name in bundled_cases()}
    docs.update({p.stem: tomllib.loads(p.read_text()) for p in sorted(SPECS.glob("*.toml"))})
    return docs


def test_the_bundled_specs_validate(validator):
    docs = _documents()
    assert set(bundled_cases()) <= set(docs) and len(docs) >= 4
    for name, doc in docs.items():
        errors = [e.message for e in validator.iter_errors(doc)]
        assert errors == [], name
    for name in bundled_cases():
        assert parse_spec(bundled_spec_bytes(name)).name == name


def _valid_doc() -> dict:
    return tomllib.loads(bundled_spec_bytes("omnirobot-s1").decode())


@pytest.mark.parametrize("where", [(), ("tube",), ("initial",), ("obstacles", 0)])
def test_an_unknown_key_is_rejected_by_both(validator, where):
    doc = _valid_doc()
    table = doc
    for key in where:
        table = table[key]
    table["wobble"] = 1.0
    assert not validator.is_valid(doc)
    with pytest.raises(SpecError) as info:
        check_document(doc)
    assert info.value.field.endswith("wobble") and "unknown key" in info.value.reason


@pytest.mark.parametrize("path, value, field, reason", [
    (("prescribed_time",), "9", "prescribed_time", "must be a number"),
    (("prescribed_time",), True, "prescribed_time", "must be a number"),
    (("prescribed_time",), -9.0, "prescribed_time", "must be positive"),
    (("prescribed_time",), 1e13, "prescribed_time", "beyond 1e12"),
    (("tube", "kappa"), 0, "tube.kappa", "must be positive"),
    (("name",), "1abc", "name", "not an identifier"),
    (("plant", "model"), "bicycle", "plant.model", "must be one of"),
    (("obstacles", 0, "lower"), [], "obstacles[0].lower", "must not be empty"),
    (("obstacles", 0, "lower"), "x", "obstacles[0].lower", "must be an array of numbers"),
    (("state_space",), 3, "state_space", "must be a table"),
    (("actuator",), {"input_bound": [1.0, 0.0, 1.0]}, "actuator.input_bound[1]",
     "must be positive"),
    (("actuator",), {"input_bound": "x"}, "actuator.input_bound", "must be an array"),
    (("actuator",), {}, "actuator.input_bound", "missing"),
    (("obstacles", 0, "active"), [1.0, 2.0, 3.0], "obstacles[0].active", "[t_on, t_off]"),
    (("obstacles", 0, "active"), [-1.0, 2.0], "obstacles[0].active[0]", "non-negative"),
    (("obstacles", 0, "velocity"), "x", "obstacles[0].velocity", "must be an array"),
    (("obstacles", 0, "path"), [1.0], "obstacles[0].path", "must be an array of rows"),
])
def test_schema_and_validator_agree_on_bad_values(validator, path, value, field, reason):
    doc = _valid_doc()
    table = doc
    for key in path[:-1]:
        table = table[key]
    table[path[-1]] = value
    assert not validator.is_valid(doc)
    with pytest.raises(SpecError) as info:
        check_document(doc)
    assert info.value.field == field and reason in info.value.reason, str(info.value)


def test_no_nan_or_infinity():
    """JSON has neither; the validator refuses both (strict, finite numbers)."""
    for bad in (math.nan, math.inf, -math.inf):
        doc = _valid_doc()
        doc["target"]["lower"][0] = bad
        with pytest.raises(SpecError) as info:
            check_document(doc)
        assert info.value.field == "target.lower[0]" and "finite" in info.value.reason


def test_defaults_are_the_loaders():
    """The schema's defaults are the values a spec without those keys gets."""
    spec = parse_spec(arena_toml("defaults"))
    document = check_document(tomllib.loads(arena_toml("defaults")))
    for key in ("delta_b", "theta0", "kappa", "mu", "smoothness"):
        assert getattr(spec.tube, key) == getattr(document.tube, key), key
    assert spec.rate_hz == document.controller.rate_hz and spec.gain is None
    assert spec.plant_model == document.plant.model
    assert spec.disturbance_amplitude == document.plant.disturbance_amplitude


def test_a_spec_from_a_dict_is_the_spec_from_its_file():
    from stt_codegen import Spec, load_spec
    for name in bundled_cases():
        doc = tomllib.loads(bundled_spec_bytes(name).decode())
        assert Spec.from_dict(doc) == load_spec(name)
    doc = tomllib.loads(bundled_spec_bytes("omnirobot-s2").decode())
    doc["state_space"] = {k: tuple(v) for k, v in doc["state_space"].items()}  # tuples work
    spec = Spec.from_dict(doc)
    assert spec == load_spec("omnirobot-s2") and len(spec.source_hash) == 64
    with pytest.raises(SpecError) as info:
        Spec.from_dict([("name", "x")])
    assert info.value.field == "" and "table" in info.value.reason


def test_numpy_arrays_and_scalars_are_accepted_where_lists_and_numbers_are():
    """``Spec.from_dict`` takes numpy arrays for lists (also nested: vertices, matrices)
    and numpy scalars for numbers: the same Spec, and hash, as the plain document."""
    import numpy as np

    from stt_codegen import Spec
    plain = tomllib.loads(arena_toml("numpy", extra=(
        "[[obstacles]]\nvertices = [[2.0, 2.0], [3.0, 2.0], [2.5, 3.0]]\n"
        "[[obstacles]]\ncenter = [1.0, 3.5]\nradius = 0.3\ndims = [0, 1]\n"
        "[plant]\nmodel = \"linear\"\na = [[0.0, 1.0], [0.0, 0.0]]\nc = [0.1, 0.0]\n"
        "[assumptions]\ninput_gain = [0.5, 2.0]\n")))
    arrays = copy.deepcopy(plain)
    arrays["prescribed_time"] = np.float64(9.0)
    arrays["state_space"] = {k: np.array(v) for k, v in plain["state_space"].items()}
    arrays["initial"]["upper"] = np.array([0.5, 0.5], dtype=np.float32)
    arrays["target"] = {k: np.array(v) for k, v in plain["target"].items()}
    arrays["obstacles"][0]["vertices"] = np.array(plain["obstacles"][0]["vertices"])
    arrays["obstacles"][1]["radius"] = np.float64(0.3)
    arrays["obstacles"][1]["dims"] = np.arange(2)                     # int64 indices
    arrays["plant"]["a"] = np.array(plain["plant"]["a"])
    arrays["plant"]["c"] = np.array(plain["plant"]["c"])
    arrays["assumptions"]["input_gain"] = np.array([0.5, 2.0])
    expected = Spec.from_dict(plain)
    spec = Spec.from_dict(arrays)
    assert spec == expected and spec.source_hash == expected.source_hash
    assert spec.linear_plant.a == ((0.0, 1.0), (0.0, 0.0))
    assert all(type(v) is float for v in spec.state_space.lower + spec.initial_set.upper)
    # an integer scalar is a number too; a numpy boolean is not, as a Python one is not
    assert Spec.from_dict({**plain, "prescribed_time": np.int64(9)}) == expected
    with pytest.raises(SpecError) as info:
        Spec.from_dict({**plain, "prescribed_time": np.bool_(True)})
    assert info.value.field == "prescribed_time" and "must be a number" in info.value.reason
    with pytest.raises(SpecError) as info:      # the array's shape is still checked
        Spec.from_dict({**plain, "state_space": {"lower": np.zeros(3), "upper": np.ones(3)}})
    assert info.value.field == "initial.lower" and "must have 3 entries" in info.value.reason
