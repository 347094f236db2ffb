"""Hostile spec files: every input loads or raises SpecError naming a field.

Hypothesis, derandomized (the same examples on every run). Inputs: random mutations of
the bundled specs and of variants with a ball and polytopes (a value replaced by a hostile
one, a key deleted or added; slow tier), byte-level mutations of the TOML text, random
documents, deep nesting and huge numbers. No other exception may
escape (RecursionError, OverflowError, MemoryError, numpy/scipy/qhull errors...), and
loading writes nothing. A few fuzzed files are refused by name (the command line turns any
``SpecError`` into exit 2 and one ``error:`` line, tested elsewhere).
"""

from __future__ import annotations

import copy
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stt_codegen.errors import SpecError
from stt_codegen.spec.covering import MAX_BOXES
from stt_codegen.spec.shapes import MAX_POLYTOPE_DIMENSION, Ball, Polytope
from stt_codegen.spec.loader import Spec, parse_spec
from hard_helpers import dumps, shape_docs

DOCS = shape_docs()
TEXTS = [dumps(d).encode() for d in DOCS]


#: ``STT_FUZZ_SCALE=20`` multiplies the examples and draws fresh random ones (a long run);
#: unset, the run is derandomized: the same examples every time (CI).
SCALE = int(os.environ.get("STT_FUZZ_SCALE", "0"))


def fuzz(examples: int):
    return settings(derandomize=not SCALE, deadline=None, database=None,
                    max_examples=examples * max(SCALE, 1),
                    suppress_health_check=list(HealthCheck))

HUGE = [1e308, -1e308, 1.7976931348623157e308, 5e-324, -5e-324, 1e-300, 0.0, -0.0,
        1e12, 1.0000001e12, 2**63 - 1, -(2**63), float("nan"), float("inf"),
        float("-inf")]
scalars = st.one_of(
    st.sampled_from(HUGE),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.integers(),
    st.sampled_from([10**400, -(10**400), 10**12 + 1]),
    st.booleans(),
    st.text(max_size=20),
)
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6),
    st.dictionaries(st.sampled_from(["lower", "upper", "center", "radius", "vertices",
                                     "dims", "tolerance", "state", "half_width", "x"]),
                    inner, max_size=4)), max_leaves=20)


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for k, v in enumerate(node):
            yield from _paths(v, prefix + (k,))


def _mutate(doc, path, action, value):
    doc = copy.deepcopy(doc)
    if not path:
        return doc
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    if action == "replace":
        parent[key] = value
    elif action == "delete":
        del parent[key]
    elif action == "scale" and isinstance(parent[key], (int, float)) \
            and not isinstance(parent[key], bool):
        parent[key] = parent[key] * value if isinstance(value, float) else parent[key]
    elif action == "grow" and isinstance(parent[key], list):
        parent[key] = parent[key] * 300
    elif action == "add" and isinstance(parent[key], dict):
        parent[key]["unknown_" + str(len(parent[key]))] = value
    return doc


def assert_loads_or_spec_error(data) -> None:
    """The contract: a Spec, or a SpecError whose message names a field (or the file)."""
    try:
        spec = parse_spec(data)
    except SpecError as exc:
        text = str(exc)
        assert text and exc.reason and "\n" not in text and len(exc.field) < 200, text
        if not exc.field:
            assert text.startswith(("malformed TOML", "not UTF-8")), text
    else:
        assert isinstance(spec, Spec)


@pytest.fixture(autouse=True)
def _in_empty_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    yield
    assert os.listdir(tmp_path) == [], "loading a spec wrote a file"


@pytest.mark.slow
@fuzz(250)
@given(doc=st.sampled_from(range(len(DOCS))), pick=st.integers(0, 10**6),
       action=st.sampled_from(["replace", "replace", "delete", "scale", "grow", "add"]),
       value=values, scale=st.sampled_from([1e-300, 1e-9, -1.0, 1e9, 1e300, 0.0]))
def test_mutated_bundled_specs(doc, pick, action, value, scale):
    paths = list(_paths(DOCS[doc]))
    path = paths[pick % len(paths)]
    mutated = _mutate(DOCS[doc], path, action, scale if action == "scale" else value)
    assert_loads_or_spec_error(dumps(mutated))


@fuzz(150)
@given(doc=st.sampled_from(range(len(TEXTS))),
       edits=st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 8), st.binary(max_size=8)),
                      min_size=1, max_size=4))
def test_byte_mutations(doc, edits):
    data = bytearray(TEXTS[doc])
    for where, cut, insert in edits:
        k = where % (len(data) + 1)
        data[k:k + cut] = insert
    assert_loads_or_spec_error(bytes(data))


@fuzz(100)
@given(doc=st.dictionaries(st.sampled_from(["name", "prescribed_time", "state_space",
                                            "initial", "target", "obstacles", "tube",
                                            "controller", "plant"]), values, max_size=9))
@pytest.mark.slow
def test_random_documents(doc):
    assert_loads_or_spec_error(dumps(doc))


@pytest.mark.parametrize("text", [
    "prescribed_time = " + "9" * 400,                  # an integer beyond float
    "prescribed_time = " + "[" * 5000 + "]" * 5000,    # nesting deeper than the parser
    "prescribed_time = " + "[" * 400 + "]" * 400,      # deep, but parses
    "prescribed_time = 1e400",
    "prescribed_time = -9223372036854775808",
    "x = " + '"' + "a" * 100000 + '"',
    '"" = 1',                                          # an empty key
    '"a\\nb" = 1',                                     # a key with a newline
    '"' + "k" * 5000 + '" = 1',                        # a long key
], ids=["bigint", "deep5000", "deep400", "1e400", "int64min", "longstring", "emptykey",
        "newlinekey", "longkey"])
def test_extreme_values(text):
    base = TEXTS[0].decode()
    lines = [ln for ln in base.splitlines() if not ln.startswith('"prescribed_time"')]
    assert_loads_or_spec_error("\n".join([text] + lines))


def _ball_or_polytope(n: int, shape: str, tolerance: float) -> str:
    doc = {"name": "hd", "prescribed_time": 9.0,
           "state_space": {"lower": [0.0] * n, "upper": [5.0] * n},
           "initial": {"lower": [0.0] * n, "upper": [0.5] * n},
           "target": {"lower": [4.5] * n, "upper": [5.0] * n}}
    if shape == "ball":
        doc["obstacles"] = [{"center": [2.5] * n, "radius": 0.5, "tolerance": tolerance}]
    else:
        verts = [[2.0 + (i == j) for j in range(n)] for i in range(n)] + [[2.0] * n]
        doc["obstacles"] = [{"vertices": verts, "tolerance": tolerance}]
    return dumps(doc)


@pytest.mark.parametrize("shape,n", [("ball", 12), ("ball", 40), ("ball", 64),
                                     pytest.param("polytope", 4, marks=pytest.mark.slow),
                                     ("polytope", 12), ("polytope", 40)])
def test_high_dimensional_shapes_are_bounded(shape, n, monkeypatch):
    """A covering must not enumerate 2^n box corners: its work is counted, not timed.

    The covering pops at most ``2 MAX_BOXES + 1`` boxes per shape (each split adds one box
    to the accepted-or-pending count, which stays within ``MAX_BOXES``) and measures the
    distance from the shape at one point per box for a ball (its farthest corner) and at
    the ``2^k`` corners for a polytope, whose dimension ``k`` is at most
    ``MAX_POLYTOPE_DIMENSION`` (larger ones are refused before any covering). A refusal
    is explained by one more covering (without the forbidden boxes): at most three
    coverings for the two loads.
    """
    evaluated: list[int] = []
    for cls in (Ball, Polytope):
        def counting(self, points, _original=cls.distance):
            evaluated.append(np.atleast_2d(points).shape[0])
            return _original(self, points)
        monkeypatch.setattr(cls, "distance", counting)
    assert_loads_or_spec_error(_ball_or_polytope(n, shape, 10.0))
    assert_loads_or_spec_error(_ball_or_polytope(n, shape, 0.01))
    if shape == "polytope" and n > MAX_POLYTOPE_DIMENSION:
        assert evaluated == []
        return
    per_box = 1 if shape == "ball" else 2 ** n
    assert 0 < sum(evaluated) <= 3 * (2 * MAX_BOXES + 1) * per_box


FUZZED_FILES = [
    TEXTS[0].replace(b"9.0", b"nan", 1),
    TEXTS[3].replace(b"0.3", b"1e400", 1),
    TEXTS[4].replace(b"[3.2, 3.8]", b"[3.2]", 1),
    b"prescribed_time = " + b"9" * 400 + b"\n" + TEXTS[0],
    b"name = [[[[[[[[[[1]]]]]]]]]]\n",
    b"\xff\xfe" + TEXTS[1],
]


@pytest.mark.parametrize("data", FUZZED_FILES, ids=range(len(FUZZED_FILES)))
def test_fuzzed_files_are_refused_naming_a_field(data):
    """Files the fuzzing found, refused with one line (``stt-codegen`` turns any
    ``SpecError`` into exit 2 and that line: tests/test_errors_and_imports.py and
    tests/test_cli.py)."""
    with pytest.raises(SpecError):
        parse_spec(data)
    assert_loads_or_spec_error(data)
