"""Blended corners: a reach segment that starts before the previous one ends.

The tube passes a via box without stopping (docs/design.md, "Blended corners"): the CasADi
model, the numpy reference, the enclosures of the certificate, the via plan's timing and
the generated C and Python all add the next segment's move where it has started.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from codegen_helpers import COMPILERS, CLib, compile_shared, misra_findings, self_test, write
from sampling import random_points
from test_model_equivalence import casadi_outputs
from test_tube_segments import piecewise_design

import stt_codegen as stt
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.codegen.tube_data import DEFAULT_CAPACITY, require_capacity
from stt_codegen.design.certificate.enclosures import reach_range
from stt_codegen.design.via import BLEND_CORNERS, BLEND_SHARES, VIA_MARGIN
from stt_codegen.runtime.compiled import load_python_module
from stt_codegen.tube import reference as R
from stt_codegen.tube.model import build_model
from stt_codegen.tube.parameters import CRUISE, GLIDE, SCURVE, SMOOTHSTEP, TANH, TubeDesign

TOLERANCE = 1e-12


def blended(profile: str = SMOOTHSTEP) -> TubeDesign:
    """The three segments of ``piecewise_design`` (ends 2, 5, 8 s), the second starting at
    1.2 s and the third at 4.0 s: two blended corners."""
    design = piecewise_design(profile)
    first, second, third = design.segments
    return replace(design, segments=(first, replace(second, start=1.2),
                                     replace(third, start=4.0)))


def split_in_two(tube: TubeDesign, lead: float) -> TubeDesign:
    """A one-segment tube's move split in two at its middle box, the second half starting
    ``lead`` s before the first ends: one blended corner on the same way."""
    (whole,) = tube.segments
    middle = (tuple((a + b) / 2 for a, b in zip(whole.lower_from, whole.lower_to)),
              tuple((a + b) / 2 for a, b in zip(whole.upper_from, whole.upper_to)))
    half = (whole.start + whole.end) / 2
    return replace(tube, segments=(
        replace(whole, end=half, lower_to=middle[0], upper_to=middle[1]),
        replace(whole, start=half - lead, lower_from=middle[0], upper_from=middle[1])))


def blended_spec():
    """omnirobot-s2 through via points with blended corners (one of its three corners is
    blended; the other two would sweep the obstacles)."""
    spec = stt.load_spec("omnirobot-s2")
    return replace(spec, tube=replace(spec.tube, method="via", via_corners=BLEND_CORNERS))


def test_segments_may_overlap_two_at_a_time_only():
    design = blended()
    assert design.blends_corners and not piecewise_design().blends_corners
    first, second, third = design.segments
    with pytest.raises(ValueError, match="at most two"):
        replace(design, segments=(first, second, replace(third, start=1.9)))
    with pytest.raises(ValueError, match="start after the previous one starts"):
        replace(design, segments=(first, replace(second, start=0.0), third))
    with pytest.raises(ValueError, match="contiguous in box"):
        replace(design, segments=(first, replace(second, lower_from=(0.0, 0.0)), third))


@pytest.mark.parametrize("profile", [SMOOTHSTEP, TANH, CRUISE, SCURVE, GLIDE])
def test_model_and_reference_add_the_started_segment(profile):
    design = blended(profile)
    edges = np.array([0.0, 1.2, 2.0, 4.0, 5.0, 8.0])
    t = np.sort(np.concatenate([np.random.default_rng(2).uniform(-1.0, 10.0, 3000)]
                               + [edges + d for d in (-1e-9, 0.0, 1e-9)]))
    expected = R.reach_tube(design, t)
    got = build_model(design)["reach_tube"].map(t.size)(t[None, :])
    for a, b in zip(got, expected):
        a = np.array(a).T
        assert np.all(np.abs(a - b) <= TOLERANCE * np.maximum(1.0, np.abs(b)))
    # inside an overlap both moves count: the box is off both via boxes' lines
    first, second, _ = design.segments
    rho_l = R.reach_tube(design, [1.6])[0][0]
    p1 = R.segment_progress(first, [1.6])[0][0]
    p2 = R.segment_progress(second, [1.6])[0][0]
    assert 0.0 < p1 < 1.0 and 0.0 < p2 < 1.0
    move_1 = np.subtract(first.lower_to, first.lower_from)
    move_2 = np.subtract(second.lower_to, second.lower_from)
    assert np.allclose(rho_l, np.array(first.lower_from) + move_1 * p1 + move_2 * p2)


@pytest.mark.parametrize("profile", [SMOOTHSTEP, CRUISE, SCURVE, GLIDE])
def test_reach_tube_and_rate_stay_continuous_at_blended_corners(profile):
    design = blended(profile)
    for when in (1.2, 2.0, 4.0, 5.0):
        before, after = R.reach_tube(design, [when - 1e-9]), R.reach_tube(design, [when + 1e-9])
        for a, b in zip(before, after):
            assert np.max(np.abs(a - b)) < 1e-6, when
    # the tube does not stop at the corner (a stopped one has rho_dot = 0 at 2 s)
    assert np.max(np.abs(R.reach_tube(design, [2.0])[2])) > 0.1
    assert np.max(np.abs(R.reach_tube(piecewise_design(profile), [2.0])[2])) == 0.0


@pytest.mark.parametrize("profile", [SMOOTHSTEP, TANH, SCURVE, GLIDE])
def test_enclosures_hold_the_blended_tube_and_its_rate(profile):
    """Dense samples of every interval lie in reach_range's bounds (to rounding); an
    enclosure that ignored the started segment (the box at the interval's ends only)
    would not hold them, so the check can fail."""
    design = blended(profile)
    rng = np.random.default_rng(7)
    t0 = np.sort(rng.uniform(0.0, 9.0, 300))
    t1 = t0 + rng.uniform(0.0, 1.5, 300)
    (ll, lh), (ul, uh), ((rll, rlh), (rul, ruh)), width = reach_range(design, t0, t1)
    worst = 0.0
    for q in range(t0.size):
        t = np.linspace(t0[q], t1[q], 801)
        a, b, c, d = R.reach_tube(design, t)
        worst = max(worst, (ll[q] - a).max(), (a - lh[q]).max(), (ul[q] - b).max(),
                    (b - uh[q]).max(), (rll[q] - c).max(), (c - rlh[q]).max(),
                    (rul[q] - d).max(), (d - ruh[q]).max(), (width[q] - (b - a)).max())
    assert worst <= 1e-12
    # the check can fail: the stopped tube's enclosures do not hold the blended tube
    (ll, lh), _, ((rll, rlh), _), _ = reach_range(piecewise_design(profile), t0, t1)
    missed = 0
    for q in range(t0.size):
        t = np.linspace(t0[q], t1[q], 201)
        a, _, c, _ = R.reach_tube(design, t)
        missed += bool((ll[q] - a).max() > 1e-3 or (a - lh[q]).max() > 1e-3
                       or (c - rlh[q]).max() > 1e-3 or (rll[q] - c).max() > 1e-3)
    assert missed > 10


def test_via_plan_blends_only_the_corners_whose_sweep_is_free():
    spec = blended_spec()
    design = stt.design_tube(spec)
    assert design.certificate.passed and design.tube.blends_corners
    segs = design.tube.segments
    assert segs[-1].end == design.tube.prescribed_time
    overlaps = [a.end - b.start for a, b in zip(segs, segs[1:])]
    blended_at = [k for k, o in enumerate(overlaps) if o > 0]
    assert blended_at, overlaps
    for k in blended_at:   # a share of the shorter move
        share = overlaps[k] / min(segs[k].duration, segs[k + 1].duration)
        assert any(share == pytest.approx(f, rel=1e-9) for f in BLEND_SHARES), share
    # each blended overlap's sweep keeps VIA_MARGIN from every obstacle (dense samples)
    boxes = spec.obstacle_boxes()
    for k in blended_at:
        t = np.linspace(segs[k + 1].start, segs[k].end, 401)
        lo, hi, _, _ = R.reach_tube(design.tube, t, rates=False)
        for box in boxes:
            apart = np.any((hi + VIA_MARGIN <= np.array(box.lower))
                           | (lo - VIA_MARGIN >= np.array(box.upper)), axis=1)
            assert apart.all()
    # the same spec with its corners stopped: as many moves, none overlapping
    stopped = stt.design_tube(replace(spec, tube=replace(spec.tube, via_corners="stop")))
    assert len(stopped.tube.segments) == len(segs)
    assert not stopped.tube.blends_corners


def test_the_tube_as_data_takes_blended_corners():
    """The data form adds the next segment's move as the model does (its bits:
    ``test_tube_data.py``, ``test_tube_data_python.py``), so the capacity check takes it."""
    require_capacity(blended(), DEFAULT_CAPACITY)


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    spec = blended_spec()
    design = stt.design_tube(spec)
    files = generate_files(spec, design.tube, Options(("c", "python"), "double"))
    return spec, design.tube, files, tmp_path_factory.mktemp("blended")


def _points(design):
    p = random_points(design, 2000, seed=13)
    segs = design.segments
    # half of them inside the blended overlaps
    spans = [(b.start, a.end) for a, b in zip(segs, segs[1:]) if b.start < a.end]
    rng = np.random.default_rng(3)
    which = rng.integers(0, len(spans), 1000)
    p["t"][:1000] = [rng.uniform(*spans[k]) for k in which]
    return p


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (gcc or clang) on PATH")
def test_generated_c_is_bit_identical_to_the_model(generated):
    spec, design, files, root = generated
    source = files[f"{spec.c_name}.c"].decode()
    assert "body_blend(" in source and "body_blend_value(" in source
    folder = write(Path(root) / "c", files)
    lib = CLib(compile_shared(folder, spec.c_name, COMPILERS[0], "double"), spec.c_name,
               design.dimension, "double")
    p = _points(design)
    got = lib.evaluate(p)
    model = build_model(design)
    tube = casadi_outputs(model["tube"], p)
    step = casadi_outputs(model["controller_step"], p)
    for k, name in enumerate(("gamma_L", "gamma_U", "gamma_L_dot", "gamma_U_dot")):
        assert np.array_equal(got[name], tube[k]), name
    assert np.array_equal(got["u"], step[0]) and np.array_equal(got["alpha_next"], step[1])
    u_ref, _, _ = R.controller_step(design, p["x"], p["t"], p["dt"], p["alpha"])
    assert np.all(np.abs(got["u"] - u_ref) <= 1e-12 * np.maximum(1.0, np.abs(u_ref)))


def test_generated_python_is_bit_identical_to_the_model(generated):
    spec, design, files, _ = generated
    mod = load_python_module(files[f"{spec.c_name}.py"], spec.c_name)
    p = _points(design)
    count = 600
    tubes = [mod.tube(p["t"][i], p["alpha"][i]) for i in range(count)]
    rows = [mod.step(p["x"][i], p["t"][i], p["dt"][i], p["alpha"][i]) for i in range(count)]
    head = {k: v[:count] for k, v in p.items()}
    model = build_model(design)
    tube = casadi_outputs(model["tube"], head)
    step = casadi_outputs(model["controller_step"], head)
    for k in range(4):
        assert np.array_equal(np.array([tb[k] for tb in tubes]), tube[k])
    assert np.array_equal(np.array([r[0] for r in rows]), step[0])


def test_stopped_corners_generate_no_blend():
    spec = stt.load_spec("omnirobot-s2")
    spec = replace(spec, tube=replace(spec.tube, method="via"))
    design = stt.design_tube(spec)
    files = generate_files(spec, design.tube, Options(("c", "python"), "double"))
    assert b"blend" not in files[f"{spec.c_name}.c"]
    assert b"blend" not in files[f"{spec.c_name}.py"]


@pytest.mark.slow
def test_door_puzzle_within_its_force_only_with_blended_corners(monkeypatch, tmp_path):
    """stlpy's DoorPuzzle as a double integrator (|u| <= 0.5 N, |v| <= 2 m/s) at 46 s: the
    design within [actuator] is a via tube with blended corners, its force proved within
    the bound; the same via tube with its corners stopped is proved to ask more than the
    bound (so blending is what certifies it)."""
    pytest.importorskip("stlpy", reason='stlpy is not installed: pip install ".[stl]"')
    from stt_codegen_bench.stl_scenarios import scenario_spec

    from stt_codegen.design.cascade_gain import cascade_design_proof
    from stt_codegen.spec.loader import Spec
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    spec = Spec.from_dict(scenario_spec("DoorPuzzle", 46, order="second"))
    design = stt.design_tube(spec)
    assert design.tube.blends_corners
    assert all(p <= b for p, b in zip(design.input_proof.peak, spec.input_bound))
    for profile in (SMOOTHSTEP, SCURVE):
        stopped = replace(spec, input_bound=None, tube=replace(
            spec.tube, method="via", via_timing="acceleration", via_profile=profile,
            via_corners="stop"))
        trial = stt.design_tube(stopped)
        assert trial.method == "via" and not trial.tube.blends_corners
        proof = cascade_design_proof(trial, spec)
        assert max(p / b for p, b in zip(proof.peak, spec.input_bound)) > 1.0


def _leg_peaks(spec) -> list[float]:
    """The peak acceleration of the centre of each moving leg of the spec's task plan (the
    first plan), each leg between two holds."""
    from stt_codegen.design import tasks
    from stt_codegen.design.search import base_design
    base = base_design(spec)
    order, choice = tasks.task_plans(spec, base)[0]
    tube, _ = tasks.plan_tasks(spec, base, choice, order)
    legs, leg = [], []
    for seg in tube.segments + (None,):
        if seg is None or (seg.profile == CRUISE and seg.lower_from == seg.lower_to):
            if leg:
                t0, t1 = leg[0].start, max(s.end for s in leg)
                shifted = [replace(s, start=s.start - t0, end=s.end - t0) for s in leg]
                legs.append(tasks._peak_acceleration(base, shifted, t1 - t0))
            leg = []
        else:
            leg.append(seg)
    return legs


def test_blended_legs_are_timed_to_one_peak_acceleration(monkeypatch):
    """DoorPuzzle's three legs (two keys, then the target) with blended corners, timed for
    the force: each leg's time follows the square root of its blended peak acceleration, so
    the legs' peaks agree within 2 %; timed as with stopped corners (the rebalancing taken
    away) they differ by more than 8 % (its last leg, a long move after two short ones,
    blends least)."""
    pytest.importorskip("stlpy", reason='stlpy is not installed: pip install ".[stl]"')
    from stt_codegen_bench.stl_scenarios import scenario_spec

    from stt_codegen.design import tasks
    from stt_codegen.spec.loader import Spec
    spec = Spec.from_dict(scenario_spec("DoorPuzzle", 38, order="second"))
    spec = replace(spec, input_bound=None, tube=replace(
        spec.tube, method="via", via_timing="acceleration", via_profile=SCURVE,
        via_corners=BLEND_CORNERS))
    peaks = _leg_peaks(spec)
    assert len(peaks) == 3 and max(peaks) / min(peaks) < 1.02
    monkeypatch.setattr(tasks, "_blended_weights", lambda spec, plans, base, seconds: seconds)
    before = _leg_peaks(spec)
    assert max(before) / min(before) > 1.08 and max(before) > max(peaks)


def _blended_files(precision: str) -> tuple:
    spec = blended_spec()
    design = stt.design_tube(spec)
    return spec, generate_files(spec, design.tube, Options(("c",), precision))


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (gcc or clang) on PATH")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_blended_c_builds_strictly_and_passes_its_self_test(precision, tmp_path):
    """Every warning an error, gcc or clang; the self-test compares the C with the numpy
    oracle's vectors (the single-precision bound for float)."""
    spec, files = _blended_files(precision)
    self_test(write(tmp_path, files), spec.c_name, COMPILERS[-1], precision)


@pytest.mark.parametrize("precision", ["double", "single"])
def test_blended_c_has_only_the_listed_misra_deviations(precision, tmp_path):
    """cppcheck's MISRA C:2012 addon on the C of a design that blends: the findings are
    the deviations of every generated C (tests/test_codegen_misra.py)."""
    import re
    import shutil
    from test_codegen_misra import DEVIATIONS
    cppcheck = shutil.which("cppcheck")
    if cppcheck is None:
        pytest.skip("cppcheck missing: install the Debian package cppcheck")
    spec, files = _blended_files(precision)
    prefix = spec.c_name
    folder = write(tmp_path, {k: v for k, v in files.items()
                              if k in (f"{prefix}.c", f"{prefix}.h")})
    for name, line, check, text in misra_findings(cppcheck, folder, prefix):
        assert any(d[0] == check and re.search(d[1], text) for d in DEVIATIONS), \
            f"{name}:{line}: {check} not on the deviation list: {text!r}"


@pytest.mark.embedded
def test_a_blended_cascade_runs_on_the_cortex_m4f_like_the_host() -> None:
    """The drone room (its design blends corners) with the single-precision C on the
    emulated Cortex-M4F: satisfied, never outside either tube, arriving and passing the
    pillars as the double C on the host does."""
    from stt_codegen.embedded.cascade_loop import run_cascade_embedded
    design = stt.design_tube(stt.load_spec(str(Path(__file__).parent / "specs"
                                               / "drone-room.toml")))
    assert design.tube.blends_corners
    report = run_cascade_embedded(design)
    assert report["satisfied"], report
    assert report["outside_position"] == report["outside_velocity"] == report["invalid"] == 0
    host = stt.simulate(design, backend="c")
    assert abs(report["reach_time"] - host.reach_time) <= 0.01
    assert abs(report["min_clearance"] - host.min_obstacle_clearance) <= 1e-3


def test_verify_passes_a_blended_design_with_the_rates_added():
    """``verify`` certifies the blended tube again and bounds ``sup |rho_dot|`` by the sum
    of the two segments' at a blended corner (the adaptive law's checks take it)."""
    design = stt.design_tube(blended_spec())
    report = stt.verify(design)
    assert report.passed, [c.name for c in report.checks if not c.passed]


@pytest.mark.slow
def test_a_blended_cascade_runs_alike_on_every_backend() -> None:
    """The cascade's own templates (C and Python) compose the blended tube too: the drone
    room's closed loop is the same, bit for bit, with its C, its Python module and the
    CasADi model, and satisfied."""
    design = stt.design_tube(stt.load_spec(str(Path(__file__).parent / "specs"
                                               / "drone-room.toml")))
    assert design.tube.blends_corners
    runs = [stt.simulate(design, backend=b) for b in ("casadi", "c", "python")]
    assert all(r.satisfied for r in runs)
    for run in runs[1:]:
        assert np.array_equal(run.trajectory.x, runs[0].trajectory.x)
        assert np.array_equal(run.trajectory.u, runs[0].trajectory.u)
