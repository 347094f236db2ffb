"""The tube as data in the generated Python module (``generate --tube-data``, Python).

The module takes its tube as a ``TubeData``, checks it, switches and runs as the C's
``P_tube_check``, ``P_switch`` and ``P_run`` do: bit for bit the CasADi model of each tube,
the same check codes, the same switch results and ``|e|`` (docs/sensing.md, "The tube as
data"). Runs without a C compiler; the comparisons with the C need one.
"""

from __future__ import annotations

import ast
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.codegen.tube_data import TubeCapacity
from stt_codegen.errors import SpecError
from stt_codegen.runtime.backends import STATUS_INPUT_CLAMPED, make_controller
from stt_codegen.runtime.compiled import DesignSpec, compiler
from stt_codegen.runtime.data_module import TubeDataModule
from stt_codegen.system import MissingTool
from conftest import design_of
from test_tube_data import base_state, bits
from test_tube_segments import piecewise_design

SPECS = Path(__file__).parent / "specs"


@pytest.fixture(scope="module")
def several():
    """The 2-D tube of 3 reach segments and 3 circumvents (two on one bound) of the C's
    tests, and its Python module with the tube as data."""
    design = piecewise_design()
    return design, TubeDataModule(design)


def test_the_module_is_standalone_and_deterministic():
    """It imports ``math`` only, says it is generated and from what, and two generations
    give the same bytes."""
    design = piecewise_design()
    options = Options(("python",), "double", TubeCapacity(4, 8))
    files = generate_files(DesignSpec(design), design, options)
    assert files == generate_files(DesignSpec(design), design, options)
    source = files["piecewise.py"].decode("ascii")
    imports = [node for node in ast.walk(ast.parse(source))
               if isinstance(node, (ast.Import, ast.ImportFrom))]
    assert {alias.name for node in imports for alias in node.names} == {"math"}
    assert source.startswith("# piecewise.py: GENERATED FILE, DO NOT EDIT")
    assert "MAX_SEGMENTS = 4" in source and "def switch(active, tube, start, x, t):" in source


def test_a_tube_as_data_computes_the_casadi_model_bit_for_bit(several):
    """The spec's tube and four others (another profile, fewer circumvents, none, blended
    corners) on one module: on random (x, t, alpha) across every segment and window, the
    step equals the CasADi model of that tube, bits and status. ``DESIGN_TUBE`` is the tube
    packed on the host."""
    from test_blended_corners import blended
    design, library = several
    packed, shipped = library.pack(design), library.module.DESIGN_TUBE
    for name in ("bound", "members", "multi", "segments", "windows"):
        assert getattr(packed, name) == getattr(shipped, name), name
    rng = np.random.default_rng(7)
    for other in (design, piecewise_design("cruise"),
                  dataclasses.replace(design, circumvents=design.circumvents[2:]),
                  dataclasses.replace(design, circumvents=()), blended()):
        ref, data = make_controller("casadi", other), library.load(other)
        for k in range(150):
            x = rng.uniform(-0.5, 5.5, 2)
            # a third of them inside the blended tube's overlaps (both segments move it)
            t = rng.uniform(*((1.2, 2.0), (4.0, 5.0))[k % 2]) if k % 3 == 1 else rng.uniform(0, 10)
            alpha = np.abs(rng.normal(0.0, 0.2, 4)) * (k % 3 != 0)
            expected, got = ref.step(x, t, 1e-3, alpha), data.step(x, t, 1e-3, alpha)
            assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t)


def _changed(module, tube, **fields):
    """``tube`` made again with some fields replaced (a TubeData cannot be changed)."""
    q = tube.parameters
    values = {f: getattr(q, f) for f in type(q).__slots__}
    values.update(fields.pop("parameters", {}))
    rows = {name: getattr(tube, name) for name in type(tube).__slots__ if name != "parameters"}
    rows.update(fields)
    return module.TubeData(module.Parameters(**values), **rows)


def _row(rows, k, position, value):
    out = [list(r) for r in rows]
    out[k][position] = value
    return out


@pytest.mark.parametrize("change, code", [
    (lambda t: {"segments": ()}, 2),
    (lambda t: {"windows": t.windows * 11}, 2),                            # 33 > 32
    (lambda t: {"bound": t.bound[:3]}, 2),
    (lambda t: {"parameters": {"kappa": 0.0}}, 3),
    (lambda t: {"parameters": {"mu": math.nan}}, 3),
    (lambda t: {"bound": (-1.0,) + t.bound[1:]}, 4),    # below the spec's state space
    (lambda t: {"bound": (6.0,) + t.bound[1:]}, 4),     # lower above upper
    (lambda t: {"segments": _row(t.segments, 1, 1, 1.0)}, 5),   # ends not increasing
    (lambda t: {"segments": _row(t.segments, 1, 0, 0.0)}, 5),   # starts not increasing
    (lambda t: {"segments": _row(_row(t.segments, 1, 0, 1.0), 2, 0, 1.5)}, 5),  # 3 at once
    (lambda t: {"segments": _row(t.segments, 0, 2, 3)}, 5),     # no such profile
    (lambda t: {"windows": _row(t.windows, 1, 0, 0.5)}, 6),     # starts not sorted
    (lambda t: {"windows": _row(t.windows, 0, 6, 9.0)}, 6),     # not the running maximum
    (lambda t: {"windows": _row(t.windows, 2, 7, 4)}, 6),       # no such bound
    (lambda t: {"windows": _row(t.windows, 2, 3, 0.0)}, 6),
    (lambda t: {"members": (1,) + t.members[1:]}, 7),
    (lambda t: {"multi": ()}, 7),
])
def test_a_malformed_tube_is_refused_naming_the_test(several, change, code):
    """The codes of the C's ``P_tube_check`` for the same faults."""
    design, library = several
    m = library.module
    tube = library.pack(design)
    assert m.tube_check(tube) == m.TUBE_OK
    assert m.tube_check(_changed(m, tube, **change(tube))) == code
    assert m.tube_check(None) == m.TUBE_NULL == m.tube_check("a tube")


def test_a_tube_is_fixed_once_made_and_its_entries_are_numbers(several):
    design, library = several
    m = library.module
    tube = library.pack(design)
    with pytest.raises(AttributeError):
        tube.segments = ()
    with pytest.raises(AttributeError):
        tube.parameters.gain = 1.0
    with pytest.raises((TypeError, ValueError)):
        _changed(m, tube, parameters={"gain": "1.0"})
    with pytest.raises(ValueError):
        _changed(m, tube, windows=_row(tube.windows, 0, 7, 0.5))     # a bound index of 0.5
    with pytest.raises((TypeError, ValueError)):
        _changed(m, tube, segments=[row[:4] for row in tube.segments])  # rows of 4
    # the counts are checked by every function that runs a tube: INVALID_INPUT, u = 0
    crowded = _changed(m, tube, windows=tube.windows * 11)
    u, _, status = m.step(crowded, [0.3, 0.3], 0.0, 1e-3, [0.0] * 4)
    assert status == m.STATUS_INVALID_INPUT and u == [0.0, 0.0]


def test_the_switch_takes_a_tube_only_where_the_state_lies_in_it(several):
    """As the C's test: refused (the active tube and alpha kept, the result and |e|
    recorded) for a tube that fails the check, a start in the future, a state at
    |e| > 1/2; switched (alpha reset, its own time from its start) at a state at its
    centre; ``run`` without a tube is INVALID_INPUT."""
    design, library = several
    m = library.module
    active = m.Active()
    u, status = m.run(active, [0.3, 0.3], 0.0, 1e-3)
    assert status == m.STATUS_INVALID_INPUT and u == [0.0, 0.0]
    assert m.switch(active, library.pack(design), 0.0, [0.3, 0.3], 0.0) == m.SWITCH_DONE
    for _ in range(50):
        m.run(active, [0.3, 0.3], 0.0, 1e-3)
    alpha_before = list(active.alpha)
    assert any(alpha_before)
    moved = dataclasses.replace(design, segments=tuple(
        dataclasses.replace(seg, lower_from=(2.0, 2.0), upper_from=(2.4, 2.4)) if k == 0
        else seg for k, seg in enumerate(design.segments)))
    later = library.pack(moved)
    broken = _changed(m, later, multi=())
    assert m.switch(active, broken, 1.0, [0.3, 0.3], 1.0) == m.SWITCH_INVALID_TUBE
    assert active.tube_check == m.TUBE_MEMBERS
    assert m.switch(active, later, 2.0, [2.2, 2.2], 1.0) == m.SWITCH_NOT_DUE
    assert m.switch(active, later, 1.0, [0.3, 0.3], 1.0) == m.SWITCH_OUTSIDE
    assert active.error > 0.5
    assert m.switch(active, later, 1.0, [math.nan, 0.3], 1.0) == m.SWITCH_INVALID_INPUT
    assert m.switch("active", later, 1.0, [2.2, 2.2], 1.0) == m.SWITCH_INVALID_INPUT
    assert active.switches == 1 and active.alpha == alpha_before
    assert m.switch(active, later, 1.0, [2.2, 2.2], 1.0) == m.SWITCH_DONE
    assert active.error <= 1e-12 and active.switches == 2 and not any(active.alpha)
    expected = make_controller("casadi", moved).step(np.array([2.2, 2.2]), 0.25, 1e-3,
                                                     np.zeros(4))
    u, status = m.run(active, [2.2, 2.2], 1.25, 1e-3)
    assert bits([u]) == bits([expected[0]]) and status == expected[2]


def test_the_switch_and_the_check_are_the_c_ones(several):
    """On random states and on malformed tubes, the Python ``switch``'s result and ``|e|``
    and ``tube_check``'s code equal the generated C's (``P_switch``, ``P_tube_check``)."""
    try:
        compiler()
    except MissingTool as exc:
        pytest.skip(f"no C compiler ({exc}): install gcc")
    from stt_codegen.runtime.data_controller import TubeDataController
    design, library = several
    c_library = TubeDataController(design)
    rng = np.random.default_rng(9)
    for other in (design, piecewise_design("tanh"),
                  dataclasses.replace(design, circumvents=design.circumvents[:1])):
        py, c = library.load(other), c_library.load(other)
        for _ in range(100):
            x = rng.uniform(-0.5, 5.5, 2)
            assert bits([py.switch_error(x)]) == bits([c.switch_error(x)]), x
    c_tube = c_library.pack(design)
    c_tube.parameters.kappa = 0.0
    py_tube = _changed(library.module, library.pack(design), parameters={"kappa": 0.0})
    assert library.check(py_tube) == c_library.check(c_tube) == 3


def test_people_crossing_the_hall_run_through_one_generated_module():
    """``simulate_sensed`` on backend ``python`` loads each switched tube into the spec's
    Python module with the tube as data: the CasADi model's run, bit for bit."""
    from test_tube_data import run_as_casadi
    run_as_casadi(design_of("hall-crossing"), "python")


def test_a_tube_larger_than_the_capacity_is_refused_by_field(several):
    design, _ = several
    small = TubeDataModule(design, TubeCapacity(3, 3))
    with pytest.raises(SpecError, match="capacity") as info:
        small.pack(dataclasses.replace(design, circumvents=design.circumvents * 2))
    assert info.value.field == "tube_data"


@pytest.mark.slow
def test_with_an_actuator_bound_the_clamp_is_the_casadi_models():
    """A spec with ``[actuator]``: the data form's law with its clamp (status
    INPUT_CLAMPED) is the CasADi model's, bit for bit."""
    design = stt.design_tube(stt.load_spec(SPECS / "actuator-s1.toml")).tube
    ref, data = make_controller("casadi", design), TubeDataModule(design).load(design)
    rng = np.random.default_rng(1)
    n, dt, statuses = design.dimension, 1.0 / design.rate_hz, set()
    for _ in range(200):
        x = np.array(design.initial_state) + rng.normal(0.0, 0.3, n)
        t = rng.uniform(0.0, 1.1 * design.prescribed_time)
        alpha = np.abs(rng.normal(0.0, 0.1, 2 * n))
        expected, got = ref.step(x, t, dt, alpha), data.step(x, t, dt, alpha)
        assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t)
        statuses.add(got[2])
    assert STATUS_INPUT_CLAMPED in statuses                # the clamp acted


@pytest.fixture(scope="module")
def base():
    """The hall's differential-drive base (tests/specs/hall-crossing-drive.toml, with the
    base's limits) and the look-ahead variant's Python module with the tube as data."""
    from stt_codegen.runtime.data_module import look_ahead_data_module
    design = stt.design_tube(stt.load_spec(str(SPECS / "hall-crossing-drive.toml")))
    return design, look_ahead_data_module(design)


def test_a_base_module_is_the_casadi_model_bit_for_bit(base):
    """The base's module with the tube as data (``step(tube, x, t, dt, alpha)``, ``x = (x,
    y, theta)``, ``u = (v, omega)``): on random base states around its tubes (the spec's
    and one moved), random headings, ``alpha`` and both ``dt`` kinds, the step equals the
    CasADi model of the look-ahead step, bits and status, every status met. So does a
    tube that blends a corner (the spec's move split in two at its middle box, the second
    half starting 4 s before the first ends)."""
    design, library = base
    assert design.look_ahead.input_bound is not None        # the clamp is in the step
    moved = dataclasses.replace(design.tube, circumvents=design.tube.circumvents[:1])
    from test_blended_corners import split_in_two
    blended = split_in_two(design.tube, 4.0)
    assert blended.blends_corners
    rng = np.random.default_rng(11)
    seen = set()
    for tube in (design.tube, moved, blended):
        ref = make_controller("casadi", tube, design.look_ahead)
        data = library.load(tube)
        for k in range(200):
            t = rng.uniform(0.0, 1.1 * tube.prescribed_time)
            x = base_state(tube, design.look_ahead.axle_offset, t,
                           rng.uniform(0.48, 0.52, 2) if k % 2 else rng.uniform(-0.1, 1.1, 2),
                           rng.uniform(-np.pi, np.pi))
            alpha = np.abs(rng.normal(0.0, 0.05, 4)) * (k % 3 != 0)
            dt = 1.0 / tube.rate_hz if k % 4 else 2.0 / tube.rate_hz
            expected, got = ref.step(x, t, dt, alpha), data.step(x, t, dt, alpha)
            assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t)
            seen.add(int(got[2]))
    assert seen >= {0, 1, 3, 5}, seen


def test_a_base_module_switches_as_the_c(base):
    """The base's ``switch`` tests the look-ahead point of ``(x, y, theta)``: its result and
    ``|e|`` equal the generated C's ``P_switch`` on random base states; the axle ``l``
    behind the initial box's centre puts the point at the centre."""
    design, library = base
    loaded = library.load(design.tube)
    lo, hi = np.array(design.tube.initial_lower), np.array(design.tube.initial_upper)
    centre, l = 0.5 * (lo + hi), design.look_ahead.axle_offset
    assert loaded.switch_error([centre[0] - l, centre[1], 0.0]) <= 1e-6
    assert loaded.switch_error([centre[0], centre[1], 0.0]) > 0.5
    assert loaded.switch_error([math.nan, 0.0, 0.0]) == math.inf
    try:
        compiler()
    except MissingTool as exc:
        pytest.skip(f"no C compiler ({exc}): install gcc")
    from stt_codegen.runtime.data_controller import look_ahead_data_controller
    c = look_ahead_data_controller(design).load(design.tube)
    rng = np.random.default_rng(12)
    for _ in range(100):
        x = np.array([*(centre + rng.uniform(-1.0, 1.0, 2)), rng.uniform(-np.pi, np.pi)])
        assert bits([loaded.switch_error(x)]) == bits([c.switch_error(x)]), x


def test_a_base_crosses_the_hall_through_one_generated_module(base):
    """``simulate_sensed`` of the base on backend ``python`` loads each switched tube into
    the look-ahead variant's module with the tube as data: the CasADi model's run, bit for
    bit."""
    from test_tube_data import run_as_casadi
    run_as_casadi(base[0], "python")


def test_the_cascade_has_no_module_taking_its_tube_as_data():
    from stt_codegen.spec.variants import variant_of
    design = design_of("second-order-s1")
    with pytest.raises(SpecError, match="not generated in python for a second-order") as info:
        variant_of(design.spec).entry("data_module")(design)
    assert info.value.field == "tube_data"
    # it says where the variant takes its tube as data, and where to read about it
    assert "the cascade variant takes its tube as data in no language" in str(info.value)
    assert 'docs/sensing.md, "The tube as data"' in str(info.value)
