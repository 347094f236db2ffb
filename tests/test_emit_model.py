"""The emitter on the project's real model: generated Python is bit-identical to CasADi."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stt_codegen.design.search import design_tube
from stt_codegen.codegen.emit import count_operations, python_function, python_source
from stt_codegen.tube.model import build_model
from stt_codegen.spec.loader import bundled_cases, load_spec

from test_emit_python import assert_bit_identical


@pytest.fixture(scope="module")
def model():
    design = design_tube(load_spec(bundled_cases()[0])).tube
    return build_model(design)


def _value(name: str):
    special = st.sampled_from([math.inf, -math.inf, math.nan, 0.0, -0.0])
    if name == "t":
        base = st.one_of(st.floats(-1.0, 12.0), st.sampled_from([9.0, math.nextafter(9.0, 0.0)]))
    elif name == "dt":
        base = st.sampled_from([0.01, 1e-3, 1e-6, 0.0, -0.01])
    elif name == "alpha":
        base = st.floats(-0.2, 1.0)
    else:
        base = st.floats(-1.0, 6.0)
    return st.one_of(base, base, base, special)


def test_model_source_generates_and_counts(model) -> None:
    src = python_source(list(model.functions.values()))
    for name, fn in model.functions.items():
        assert f"def {name}(" in src
        counts = count_operations(fn)
        assert counts.total == fn.n_instructions()


@pytest.mark.parametrize(
    "name", ["reach_tube", "circumvent", "tube", "adaptive_law", "error_transform",
             "control", "alpha_step", "controller_step"],
)
def test_model_function_bit_identical(model, name: str) -> None:
    fn = model.functions[name]
    gen = python_function(fn)
    inputs = st.tuples(*[
        st.lists(_value(fn.name_in(i)), min_size=fn.numel_in(i), max_size=fn.numel_in(i))
        for i in range(fn.n_in())
    ])

    @settings(max_examples=150, deadline=None)
    @given(inputs)
    def check(values):
        assert_bit_identical(fn, gen, values)

    check()
