"""The tube as data (``generate --tube-data``, docs/sensing.md "The tube as data"): the
generated C runs any tube of the spec's dimension passed as a ``P_tube_data``, bit for bit
as the CasADi model of that tube; ``P_tube_check`` refuses a malformed tube naming the
test it failed; ``P_switch`` changes the active tube only where the state lies in the new
one; ``simulate_sensed`` on backend ``c`` switches its tubes through one compiled
controller."""

from __future__ import annotations

import ctypes
import re
import shutil
import dataclasses
import subprocess

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.codegen.api import design_files
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options, parse_options
from stt_codegen.codegen.tube_data import TubeCapacity, parse_capacity
from stt_codegen.errors import SpecError
from stt_codegen.system import MissingTool
from stt_codegen.runtime.backends import make_controller
from stt_codegen.runtime.compiled import DesignSpec, compiler
from stt_codegen.runtime.sensed import bundled_people
from conftest import design_of
from test_tube_segments import piecewise_design

SPECS = __import__("pathlib").Path(__file__).parent / "specs"


@pytest.fixture(scope="module")
def cc():
    try:
        return compiler()
    except MissingTool as exc:
        pytest.skip(f"no C compiler ({exc}): install gcc")


@pytest.fixture(scope="module")
def several(cc):
    """A 2-D tube with 3 reach segments and 3 circumvents, two on one bound: every code
    path of the data form's composition (F_nu over several windows and one alone)."""
    from stt_codegen.runtime.data_controller import TubeDataController
    design = piecewise_design()
    return design, TubeDataController(design)


def run_as_casadi(design, backend: str) -> None:
    """The hall's people (8 s) with ``design`` on ``backend`` (the generated code with the
    tube as data): at least three switches, and the CasADi model's run, bit for bit."""
    people = bundled_people("hall-crossing")
    runs = [stt.simulate_sensed(design, people, backend=b, horizon=8.0)
            for b in ("casadi", backend)]
    assert runs[1].sensing.switches >= 3 and runs[1].backend == backend
    for name in ("x", "u", "alpha", "status", "tube"):
        assert np.array_equal(getattr(runs[0].trajectory, name),
                              getattr(runs[1].trajectory, name)), name


def selftest_passes(files: dict, folder, cc: str) -> None:
    """The generated files written to ``folder``: ``make selftest`` (the shipped Makefile's
    warnings as errors) passes over 100 vectors, none failed."""
    for name, data in files.items():
        (folder / name).write_bytes(data)
    proc = subprocess.run(["make", "-s", "selftest", f"CC={cc}"], cwd=folder,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    last = proc.stdout.strip().splitlines()[-1]
    assert last.endswith(" passed, 0 failed") and int(last.split()[0]) > 100


def bits(values) -> list:
    return [np.asarray(v, float).tobytes() for v in values]


def base_state(tube, axle_offset: float, t: float, fraction, theta: float) -> np.ndarray:
    """The base state ``(x, y, theta)`` whose look-ahead point, ``axle_offset`` ahead of
    the axle, lies at ``fraction`` (per axis; 0 the lower side, 1 the upper) of the
    adaptive tube's box at ``t``."""
    g_l, g_u = (np.ravel(v) for v in stt.tube.reference.adaptive_tube(
        tube, np.array([t]), np.zeros((1, 4)))[:2])
    p = g_l + (g_u - g_l) * fraction
    return np.array([p[0] - axle_offset * np.cos(theta), p[1] - axle_offset * np.sin(theta),
                     theta])


def test_a_tube_as_data_computes_the_casadi_model_bit_for_bit(several):
    """On random (x, t, alpha) across every segment and window, the step of the tube passed
    as data equals the CasADi model's, bits and status; so does the tube packed in Python
    and the generated ``P_design_tube`` (the same bytes)."""
    design, library = several
    assert bytes(library.pack(design)) == bytes(library.design_tube)
    ref, data = make_controller("casadi", design), library.load(design)
    rng = np.random.default_rng(7)
    for k in range(400):
        x = rng.uniform(-0.5, 5.5, 2)
        t = rng.uniform(0.0, 10.0)
        alpha = np.abs(rng.normal(0.0, 0.2, 4)) * (k % 3 != 0)
        expected, got = ref.step(x, t, 1e-3, alpha), data.step(x, t, 1e-3, alpha)
        assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t, alpha)


def test_one_library_runs_other_tubes_of_the_same_dimension(several):
    """Tubes that are not the spec's (another profile, fewer circumvents, shifted times)
    run on the same compiled library, bit for bit as their own CasADi model."""
    design, library = several
    others = [piecewise_design("cruise"),
              dataclasses.replace(design, circumvents=design.circumvents[2:]),
              dataclasses.replace(design, circumvents=())]
    rng = np.random.default_rng(8)
    for other in others:
        ref, data = make_controller("casadi", other), library.load(other)
        for _ in range(100):
            x, t = rng.uniform(0.0, 5.0, 2), rng.uniform(0.0, 10.0)
            alpha = np.abs(rng.normal(0.0, 0.2, 4))
            expected, got = ref.step(x, t, 1e-3, alpha), data.step(x, t, 1e-3, alpha)
            assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2]


def test_a_tube_that_blends_corners_runs_as_data_bit_for_bit(several):
    """A tube whose segments overlap two at a time (blended corners: the second starts at
    1.2 s, before the first ends at 2 s; the third at 4 s, before the second ends at 5 s)
    runs on the same library, bit for bit as its CasADi model, half the times inside the
    overlaps, where both segments move the box."""
    from test_blended_corners import blended
    _, library = several
    design = blended()
    assert design.blends_corners and library.check(library.pack(design)) == 0
    ref, data = make_controller("casadi", design), library.load(design)
    rng = np.random.default_rng(9)
    for k in range(300):
        x = rng.uniform(-0.5, 5.5, 2)
        t = rng.uniform(*((1.2, 2.0), (4.0, 5.0))[k % 2]) if k % 4 < 2 else rng.uniform(0, 10)
        alpha = np.abs(rng.normal(0.0, 0.2, 4)) * (k % 3 != 0)
        expected, got = ref.step(x, t, 1e-3, alpha), data.step(x, t, 1e-3, alpha)
        assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t, alpha)


def _three_at_once(tube):
    """The second segment starting at 1 s and the third at 1.5 s, before the first ends."""
    tube.segments[1].start = 1.0
    tube.segments[2].start = 1.5


def test_an_s_curve_tube_is_refused_by_the_data_form(several):
    """The data form runs the profiles law (13)'s designs produce (``DATA_PROFILES``): a tube
    of S-curve or glide segments (the cascade's) is refused when packed on the host, naming
    the field; in the C, their codes (3, 4) fail the check on its segments (code 5); the
    same tube with cruise segments passes it."""
    from stt_codegen.codegen.tube_data import DATA_PROFILES
    from stt_codegen.tube.pieces import PROFILE_NAMES
    _, library = several
    assert "scurve" not in DATA_PROFILES and "glide" not in DATA_PROFILES
    assert "cruise" in DATA_PROFILES
    assert PROFILE_NAMES[:len(DATA_PROFILES)] == DATA_PROFILES      # the same codes
    with pytest.raises(stt.SpecError, match="tube_data: the tube has scurve segments"):
        library.pack(piecewise_design("scurve"))
    with pytest.raises(stt.SpecError, match="tube_data: the tube has glide segments"):
        library.pack(piecewise_design("glide"))
    tube = library.pack(piecewise_design("cruise"))
    assert library.check(tube) == 0
    tube.segments[1].profile = 3                           # PROFILE_NAMES.index("scurve")
    assert library.check(tube) == 5
    tube.segments[1].profile = 4                           # PROFILE_NAMES.index("glide")
    assert library.check(tube) == 5


def _broken(library, design, change):
    tube = library.pack(design)
    change(tube)
    return library.check(tube)


@pytest.mark.parametrize("change, code", [
    (lambda t: setattr(t, "n_segments", 0), 2),
    (lambda t: setattr(t, "n_windows", 33), 2),
    (lambda t: setattr(t.parameters, "kappa", 0.0), 3),
    (lambda t: setattr(t.parameters, "mu", float("nan")), 3),
    (lambda t: t.bound.__setitem__(0, -1.0), 4),          # below the spec's state space
    (lambda t: t.bound.__setitem__(0, 6.0), 4),           # lower above upper
    (lambda t: setattr(t.segments[1], "end", 1.0), 5),    # ends not increasing
    (lambda t: setattr(t.segments[1], "start", 0.0), 5),  # starts not increasing
    (_three_at_once, 5),                                  # three segments move at once
    (lambda t: setattr(t.segments[0], "profile", 3), 5),  # no such profile
    (lambda t: setattr(t.windows[1], "start", 0.5), 6),   # starts not sorted
    (lambda t: setattr(t.windows[0], "max_end", 9.0), 6),  # not the running maximum
    (lambda t: setattr(t.windows[2], "bound", 4), 6),     # no such bound
    (lambda t: setattr(t.windows[2], "radius", 0.0), 6),
    (lambda t: t.members.__setitem__(0, 1), 7),
    (lambda t: setattr(t, "n_multi", 0), 7),
])
def test_a_malformed_tube_is_refused_naming_the_test(several, change, code):
    design, library = several
    assert library.check(library.pack(design)) == 0
    assert _broken(library, design, change) == code


def test_counts_out_of_range_make_every_function_refuse(several):
    """The functions that run a tube check its counts (no read past the arrays):
    INVALID_INPUT with u = 0."""
    design, library = several
    tube = library.pack(design)
    tube.n_windows = 1000
    from stt_codegen.runtime.data_controller import _Loaded
    u, _, status = _Loaded(library, tube).step(np.array([0.3, 0.3]), 0.0, 1e-3, np.zeros(4))
    assert status == 2 and not u.any()


class Switcher:
    """``P_active``, ``P_switch`` and ``P_run`` of a compiled data-form library."""

    def __init__(self, library) -> None:
        self.library = library
        self.active = library.active()
        library.functions["active_init"](ctypes.byref(self.active))

    def to(self, tube, start, x, t) -> int:
        x = np.ascontiguousarray(x, float)
        return self.library.functions["switch"](
            ctypes.byref(self.active), ctypes.byref(tube), start,
            x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), t)

    def step(self, x, t, dt):
        x = np.ascontiguousarray(x, float)
        u = np.zeros(x.size)
        p = ctypes.POINTER(ctypes.c_double)
        status = self.library.functions["run"](ctypes.byref(self.active), x.ctypes.data_as(p),
                                               t, dt, u.ctypes.data_as(p))
        return u, status


def test_the_switch_takes_a_tube_only_where_the_state_lies_in_it(several):
    """Refused (the active tube and alpha kept, the result and |e| recorded): a tube that
    fails the check, a start in the future, a state at |e| > 1/2; switched (alpha reset,
    its own time from its start): a state at its centre. ``P_run`` without a tube is
    INVALID_INPUT."""
    design, library = several
    s = Switcher(library)
    tube = library.pack(design)
    u, status = s.step([0.3, 0.3], 0.0, 1e-3)
    assert status == 2 and not u.any()
    assert s.to(tube, 0.0, [0.3, 0.3], 0.0) == 0 and s.active.switches == 1
    for _ in range(50):                                   # the first tube runs: alpha moves
        u, status = s.step([0.3, 0.3], 0.0, 1e-3)
    alpha_before = list(s.active.alpha)
    later = library.pack(dataclasses.replace(
        design, segments=tuple(dataclasses.replace(seg, lower_from=(2.0, 2.0),
                                                   upper_from=(2.4, 2.4))
                               if k == 0 else seg for k, seg in enumerate(design.segments))))
    broken = library.pack(design)
    broken.n_multi = 0
    assert s.to(broken, 1.0, [0.3, 0.3], 1.0) == 2 and s.active.tube_check == 7
    assert s.to(later, 2.0, [2.2, 2.2], 1.0) == 3                       # not due
    assert s.to(later, 1.0, [0.3, 0.3], 1.0) == 4 and s.active.error > 0.5
    assert s.active.switches == 1 and list(s.active.alpha) == alpha_before
    assert s.to(later, 1.0, [2.2, 2.2], 1.0) == 0 and s.active.error <= 1e-12
    assert s.active.switches == 2 and not any(s.active.alpha) and s.active.start == 1.0
    # the run is the step of the new tube at its own time t - start
    expected = make_controller("casadi", dataclasses.replace(
        design, segments=tuple(dataclasses.replace(seg, lower_from=(2.0, 2.0),
                                                   upper_from=(2.4, 2.4))
                               if k == 0 else seg for k, seg in enumerate(design.segments))
    )).step(np.array([2.2, 2.2]), 0.25, 1e-3, np.zeros(4))
    u, status = s.step([2.2, 2.2], 1.25, 1e-3)
    assert bits([u]) == bits([expected[0]]) and status == expected[2]


def test_people_crossing_the_hall_run_through_one_compiled_controller(cc):
    """``simulate_sensed`` on backend ``c`` loads each switched tube into the spec's C with
    the tube as data: the same trajectory, bit for bit, as the CasADi model's run."""
    run_as_casadi(design_of("hall-crossing"), "c")


def blended_maze():
    """The U-maze with a sensing envelope (``specs/pointmaze-sensed.toml``, a single
    integrator in place of MuJoCo) through via points with cruise segments and blended
    corners: its tube turns twice without stopping."""
    import tomllib
    doc = tomllib.loads((SPECS / "pointmaze-sensed.toml").read_text())
    del doc["plant"]
    spec = stt.Spec.from_dict(doc)
    return stt.design_tube(dataclasses.replace(spec, tube=dataclasses.replace(
        spec.tube, method="via", via_profile="cruise", via_corners="blend")))


def test_a_sensed_tube_that_blends_corners_runs_as_data_through_its_overlaps(cc):
    """``simulate_sensed`` with nobody in the maze keeps the spec's blended tube (index 0)
    all the way, through both overlaps: the generated C and Python with the tube as data
    run the same trajectory as the CasADi model, bit for bit, and reach the target."""
    design = blended_maze()
    overlaps = [(b.start, a.end) for a, b in zip(design.tube.segments,
                                                 design.tube.segments[1:]) if b.start < a.end]
    assert len(overlaps) == 2
    runs = [stt.simulate_sensed(design, [], backend=b, horizon=12.0)
            for b in ("casadi", "c", "python")]
    t = runs[0].trajectory.t
    assert all(np.any((a < t) & (t < b)) for a, b in overlaps)
    assert not np.any(runs[0].trajectory.tube) and runs[0].satisfied
    for run in runs[1:]:
        for name in ("x", "u", "alpha", "status", "tube"):
            assert np.array_equal(getattr(runs[0].trajectory, name),
                                  getattr(run.trajectory, name)), (run.backend, name)


@pytest.fixture(scope="module")
def base(cc):
    """The hall's differential-drive base (tests/specs/hall-crossing-drive.toml) and its
    C with the tube as data."""
    from stt_codegen.runtime.data_controller import look_ahead_data_controller
    design = stt.design_tube(stt.load_spec(str(SPECS / "hall-crossing-drive.toml")))
    return design, look_ahead_data_controller(design)


def test_a_base_switches_at_its_look_ahead_point(base):
    """The base's ``P_switch`` tests the look-ahead point of ``(x, y, theta)``: the axle
    at the tube's centre facing along x puts the point ``l`` ahead, past the switch's
    limit; the axle ``l`` behind the centre puts it at the centre (``|e|`` about 0: the
    tube at ``t = 0`` is the initial box to rounding)."""
    design, library = base
    loaded = library.load(design.tube)
    lo, hi = np.array(design.tube.initial_lower), np.array(design.tube.initial_upper)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    l = design.look_ahead.axle_offset
    assert loaded.switch_error([centre[0] - l, centre[1], 0.0]) <= 1e-6
    ahead = loaded.switch_error([centre[0], centre[1], 0.0])
    assert ahead == pytest.approx(l / half[0], rel=1e-6) and ahead > 0.5
    assert loaded.switch_error([centre[0], centre[1] - l, np.pi / 2]) <= 1e-6
    assert loaded.switch_error([np.nan, 0.0, 0.0]) == np.inf


def test_a_base_runs_its_replanned_tubes_through_one_compiled_controller(base):
    """``simulate_sensed`` of the base on backend ``c`` loads each switched tube into the
    look-ahead variant's C with the tube as data: the same trajectory, bit for bit, as the
    CasADi model's run (its Python module's: tests/test_tube_data_python.py)."""
    design, _ = base
    run_as_casadi(design, "c")


def test_a_base_runs_a_tube_that_blends_a_corner_bit_for_bit(base):
    """The base's C with the tube as data runs a tube that blends a corner (the spec's move
    split in two at its middle box, the second half starting 4 s before the first ends) as
    the CasADi model of the look-ahead step, bits and status, half the times inside the
    overlap (its Python module's twin: tests/test_tube_data_python.py)."""
    from test_blended_corners import split_in_two
    design, library = base
    tube = split_in_two(design.tube, 4.0)
    first, second = tube.segments
    assert tube.blends_corners and library.check(library.pack(tube)) == 0
    ref, data = make_controller("casadi", tube, design.look_ahead), library.load(tube)
    rng = np.random.default_rng(12)
    l = design.look_ahead.axle_offset
    for k in range(200):
        t = (rng.uniform(second.start, first.end) if k % 2
             else rng.uniform(0.0, 1.1 * tube.prescribed_time))
        x = base_state(tube, l, t, rng.uniform(-0.1, 1.1, 2), rng.uniform(-np.pi, np.pi))
        alpha = np.abs(rng.normal(0.0, 0.05, 4)) * (k % 3 != 0)
        expected, got = ref.step(x, t, 1.0 / tube.rate_hz, alpha), data.step(
            x, t, 1.0 / tube.rate_hz, alpha)
        assert bits(got[:2]) == bits(expected[:2]) and got[2] == expected[2], (x, t)


@pytest.mark.parametrize("precision", ["double", "single"])
def test_the_base_data_form_selftest_passes(base, cc, tmp_path, precision):
    """The base's C with the tube as data: its self-test runs the spec's vectors on
    ``P_design_tube`` (the shipped Makefile's warnings as errors) and passes."""
    design, _ = base
    files = design_files(design, Options(("c",), precision, TubeCapacity(8, 32)))
    prefix = design.spec.c_name
    selftest_passes(files, tmp_path, cc)
    header = files[f"{prefix}.h"].decode()
    assert f"{prefix}_tube_data" in header and "x[HALL_CROSSING_DRIVE_N_STATE]" in header


@pytest.mark.parametrize("precision", ["double", "single"])
def test_the_generated_selftest_passes_on_the_design_tube(cc, tmp_path, precision):
    """The data form's self-test runs the spec's vectors on ``P_design_tube`` (the shipped
    Makefile's warnings as errors) and passes; generation is deterministic."""
    design = piecewise_design()
    spec = DesignSpec(design)
    options = Options(("c",), precision, TubeCapacity(4, 8))
    files = generate_files(spec, design, options)
    assert files == generate_files(spec, design, options)
    selftest_passes(files, tmp_path, cc)
    header = files[f"{spec.c_name}.h"].decode()
    assert "#define PIECEWISE_MAX_SEGMENTS 4" in header and "the tube as data" in header
    assert '"tube_data": {' in files["manifest.json"].decode()


def test_the_generated_selftest_passes_on_a_blended_design_tube(cc, tmp_path):
    """The self-test of the data form of a tube that blends corners (the piecewise tube's
    second segment starting 0.8 s and its third 1 s before the previous one ends) passes:
    its vectors (4 of whose 56 times fall in the overlaps) are the reference's."""
    from test_blended_corners import blended

    from stt_codegen.codegen.vectors import test_vectors
    design = blended()
    t = np.asarray(test_vectors(design, "double")["t"], float)
    assert np.count_nonzero(((1.2 < t) & (t < 2.0)) | ((4.0 < t) & (t < 5.0))) >= 4
    spec = DesignSpec(design)
    files = generate_files(spec, design, Options(("c",), "double", TubeCapacity(4, 8)))
    selftest_passes(files, tmp_path, cc)


def test_bad_requests_name_the_field():
    assert parse_options("c,python", "double", True).tube_data == TubeCapacity(8, 32)
    with pytest.raises(SpecError, match="expected True or a TubeCapacity"):
        parse_options("c", "double", "8,32")
    with pytest.raises(SpecError, match="SEGMENTS,WINDOWS"):
        parse_capacity("8")
    with pytest.raises(SpecError, match="from 1 to 4096"):
        parse_capacity("0,3")
    with pytest.raises(SpecError, match="more than the capacity"):
        generate_files(DesignSpec(piecewise_design()), piecewise_design(),
                       Options(("c",), "double", TubeCapacity(2, 8)))
    with pytest.raises(SpecError, match="not generated in c for a second-order plant"):
        design_files(design_of("second-order-s1"), parse_options("c", "double", True))
    with pytest.raises(SpecError, match="not generated in python for a second-order plant"):
        design_files(design_of("second-order-s1"), parse_options("python", "double", True))
    base = stt.design_tube(stt.load_spec(str(SPECS / "hall-crossing-drive.toml")))
    files = design_files(base, parse_options("c,python", "double", True))
    source = files[f"{base.spec.c_name}.py"].decode()
    assert "class TubeData:" in source and "def switch(active, tube, start, x, t):" in source
    assert "def step(tube, x, t, dt, alpha):" in source and "N_STATE = 3" in source


def test_the_command_line_writes_the_data_form_or_exits_2(tmp_path):
    from stt_codegen.cli import main
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "a"), "--tube-data"]) == 0
    assert "omnirobot_s1_tube_data" in (tmp_path / "a" / "omnirobot_s1.h").read_text()
    assert "class TubeData:" in (tmp_path / "a" / "omnirobot_s1.py").read_text()
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "b"), "--tube-data",
                 "--lang", "python"]) == 0
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        "manifest.json", "omnirobot_s1.py", "omnirobot_s1_vectors.json"]
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "c"),
                 "--tube-data", "x"]) == 2
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "d"),
                 "--tube-data", "0,3"]) == 2
    assert not (tmp_path / "c").exists() and not (tmp_path / "d").exists()


@pytest.mark.embedded
def test_on_the_cortex_m4f_the_switch_and_the_step_are_counted(tmp_path, capsys):
    """The data form in single precision on the emulated Cortex-M4F: the self-test on the
    spec's tube passes, every switch is taken, every step is OK, and a tube with 8
    segments and 16 open windows costs more per step and per switch than the spec's
    (1 segment, no window); the bytes the host packs for it are a valid tube there; the
    command prints the same report and exits 0."""
    from stt_codegen.cli import main
    from stt_codegen.embedded.tube_data_loop import run_tube_data
    r = run_tube_data(design_of("hall-crossing"), TubeCapacity(8, 32), tmp_path)
    assert r["ok"] and r["vectors_failed"] == 0 and r["vectors_passed"] > 100
    assert r["switch_design"]["result"] == 0 and r["switch_cost"]["result"] == 0
    assert set(r["steps_design"]["statuses"] + r["steps_cost"]["statuses"]) == {0}
    assert min(r["steps_cost"]["instructions"]) > max(r["steps_design"]["instructions"])
    assert r["switch_cost"]["instructions"] > r["switch_design"]["instructions"]
    assert r["ram_bytes"] == 0
    # the cost tube packed on the host and copied in on the target: well formed there,
    # and its steps are the compiled tube's, bit for bit
    assert r["wire"]["check"] == 0 and r["wire"]["same_steps"] and r["wire"]["bytes"] > 0
    assert main(["embedded", "hall-crossing", "--tube-data", "--json"]) == 0
    assert '"open_windows": 16' in capsys.readouterr().out
    assert main(["embedded", "hall-crossing", "--tube-data", "8,8"]) == 2


@pytest.mark.embedded
def test_a_base_on_the_cortex_m4f_switches_and_steps_its_tubes_as_data(tmp_path):
    """The base's data form on the emulated Cortex-M4F (tests/specs/hall-crossing-drive.toml):
    the self-test passes, both switches are taken at the look-ahead point of the state the
    program gives (the axle behind each tube's point), every step keeps the point inside
    its tube (OK, or INPUT_CLAMPED: the program holds the state still while the tube moves
    on), the cost tube costs more, and the host-packed bytes run as the compiled tube."""
    from stt_codegen.embedded.tube_data_loop import run_tube_data
    design = stt.design_tube(stt.load_spec(str(SPECS / "hall-crossing-drive.toml")))
    r = run_tube_data(design, TubeCapacity(8, 32), tmp_path)
    assert r["ok"] and r["vectors_failed"] == 0 and r["vectors_passed"] > 100
    assert r["switch_design"]["result"] == 0 and r["switch_cost"]["result"] == 0
    statuses = set(r["steps_design"]["statuses"] + r["steps_cost"]["statuses"])
    assert 0 in statuses and statuses <= {0, 3}
    assert min(r["steps_cost"]["instructions"]) > max(r["steps_design"]["instructions"])
    assert r["wire"]["check"] == 0 and r["wire"]["same_steps"] and r["ram_bytes"] == 0


@pytest.mark.skipif(shutil.which("cppcheck") is None,
                    reason="cppcheck missing: install the Debian package cppcheck")
@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", ["law (13)", "base"])
def test_misra_findings_are_the_listed_deviations(tmp_path, precision, variant):
    """cppcheck's MISRA C:2012 addon on the data form (docs/codegen.md), law (13)'s and a
    differential-drive base's: only the first order's deviations, with the data form's API
    among the unused functions and rule 8.7 on the two public functions the file also
    calls."""
    from test_codegen_misra import DEVIATIONS
    if variant == "base":
        design = stt.design_tube(stt.load_spec(str(SPECS / "hall-crossing-drive.toml")))
        prefix = design.spec.c_name
        files = design_files(design, Options(("c",), precision, TubeCapacity(8, 32)))
    else:
        design = piecewise_design()
        spec = DesignSpec(design)
        prefix = spec.c_name
        files = generate_files(spec, design, Options(("c",), precision, TubeCapacity(4, 8)))
    for name in (f"{prefix}.c", f"{prefix}.h"):
        (tmp_path / name).write_bytes(files[name])
    proc = subprocess.run(["cppcheck", "--enable=all", "--addon=misra", "--std=c99",
                           "--suppress=missingIncludeSystem", "--quiet",
                           "--template={file}:{line}:{id}", f"{prefix}.c"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    allowed = DEVIATIONS + (
        ("unusedFunction", r"^(int|void) \w+_(active_init|switch|run)\("),
        ("misra-c2012-8.7", r"^int \w+_(step|tube_check)\("))
    seen = set()
    for name, line, check in (f.split(":") for f in proc.stderr.splitlines()
                              if f.count(":") >= 2):
        text = (tmp_path / name).read_text().splitlines()[int(line) - 1]
        assert any(d[0] == check and re.search(d[1], text) for d in allowed), \
            f"{name}:{line}: {check} not on the deviation list: {text!r}"
        seen.add(check)
    assert {"unusedFunction", "misra-c2012-8.7"} <= seen
