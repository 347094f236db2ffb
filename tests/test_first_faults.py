"""The faults a new user meets first: each reproduced as it was met, then fixed."""

from __future__ import annotations

import json
import math
import subprocess
import time
import sys
import tomllib
from pathlib import Path

import pytest

import stt_codegen as stt
from stt_codegen.design.certificate.actuator import prove_input_bound

SPECS = Path(__file__).parent / "specs"
DRIVE = SPECS / "office-drive.toml"


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], capture_output=True,
                          text=True, timeout=600)


def drive_doc(**tables) -> dict:
    """The office spec (a differential drive) as a dict, with tables replaced."""
    return {**tomllib.loads(DRIVE.read_text()), **tables}


def toml_text(doc: dict) -> str:
    """``doc`` as TOML (tables of scalars and lists, arrays of such tables)."""
    def value(v):
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)
    head = [f"{k} = {value(v)}" for k, v in doc.items() if not isinstance(v, (dict, list))]
    body = []
    for k, v in doc.items():
        rows = [v] if isinstance(v, dict) else v if isinstance(v, list) and v and \
            isinstance(v[0], dict) else []
        for row in rows:
            body.append(f"[{k}]" if isinstance(v, dict) else f"[[{k}]]")
            body += [f"{a} = {value(b)}" for a, b in row.items()]
    return "\n".join(head + body) + "\n"


# 1. A differential drive with [actuator]: the proved peaks of (v, omega) against its bound


@pytest.mark.slow
def test_design_reports_the_bases_proved_limits_in_text_and_json(tmp_path):
    spec_file = tmp_path / "drive.toml"
    spec_file.write_text(toml_text(drive_doc(actuator={"input_bound": [1.6, 16.0]})))
    out = run("design", str(spec_file), "--plot", str(tmp_path / "drive.png"))
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    line = next(s for s in out.stdout.splitlines() if "input bound" in s)
    assert "(v, omega)" in line and "|v|" in line and "<= 1.6" in line and "<= 16" in line
    assert (tmp_path / "drive.png").stat().st_size > 0
    out = run("design", str(spec_file), "--json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["input_bound"] == [1.6, 16.0]
    peak = doc["input_peak"]["peak"]
    assert len(peak) == 2 and all(0 < p <= b for p, b in zip(peak, doc["input_bound"]))
    # |omega| from the heading the base can have: below the worst heading's |u| / l
    assert peak[1] < peak[0] / 0.1
    assert doc["input_peak"]["margin"] >= 0


# 2. stlpy's NonlinearReachAvoid as a differential drive: the sampled check's enclosure of e
#    could turn empty by rounding (a ball's edge a few ulps below the box near e = 0), and
#    phi' was then asked at |e| = -inf: math.atanh's domain error.

NONLINEAR_REACH_AVOID = {
    "name": "stlpy-nonlinear-reach-avoid-drive", "prescribed_time": 1.5,
    "state_space": {"lower": [0.0, 0.0], "upper": [10.0, 10.0]},
    "initial": {"lower": [0.9, 1.9], "upper": [1.1, 2.1], "state": [1.0, 2.0],
                "heading": 0.0},
    "target": {"lower": [6.97, 7.97], "upper": [8.03, 9.03]},
    "obstacles": [{"center": [3.5, 5.0], "radius": 1.5}],
    "controller": {"rate_hz": 400.0},
    "plant": {"model": "differential-drive", "axle_offset": 0.1, "track_width": 0.16},
}


def test_the_input_proof_of_a_tube_whose_enclosure_touches_the_ball_by_rounding():
    """The tube ``design_tube`` tried for the spec at ``t_c = 24 s`` (the search for the
    ``prescribed_time`` that works) is proved, not a domain error."""
    doc = {**NONLINEAR_REACH_AVOID, "prescribed_time": 24.0}
    design = stt.design_tube(stt.Spec.from_dict(doc))
    judged = stt.Spec.from_dict({**doc, "actuator": {"input_bound": [10.0, 5.0]}})
    proof = prove_input_bound(design.tube, judged)
    assert proof.proved, proof.reason
    assert all(0 < p < math.inf for p in proof.peak)


def test_phi_slope_is_infinite_at_and_beyond_the_tubes_edge():
    from stt_codegen.design.certificate.sampled_axis import phi_slope, phi_slope_scalar

    assert phi_slope_scalar(0.0) == 2.0
    assert phi_slope_scalar(0.5) == pytest.approx(float(phi_slope(0.5)), rel=1e-15)
    for s in (1.0, -1.0, 1.5, -math.inf):
        assert phi_slope_scalar(s) == math.inf


@pytest.mark.slow
def test_the_nonlinear_reach_avoid_drive_is_refused_by_a_design_error(tmp_path):
    """``(v, omega)`` within ``[10, 5]`` in 1.5 s: no design (exit 1), named, no traceback."""
    spec_file = tmp_path / "nra.toml"
    spec_file.write_text(toml_text({**NONLINEAR_REACH_AVOID,
                                    "actuator": {"input_bound": [10.0, 5.0]}}))
    out = run("design", str(spec_file))
    assert out.returncode == 1 and "Traceback" not in out.stderr, out.stderr
    assert "actuator.input_bound" in out.stderr and "omega" in out.stderr


# 3. The field named is the one to change


def _refusal(doc: dict) -> stt.SpecError:
    with pytest.raises(stt.SpecError) as info:
        stt.Spec.from_dict(doc)
    return info.value


def test_an_axle_offset_in_millimetres_names_plant_axle_offset():
    doc = drive_doc()
    error = _refusal({**doc, "plant": {**doc["plant"], "axle_offset": 600}})
    assert error.field == "plant.axle_offset"
    assert "600.12" in error.reason and "0.12" in error.reason


def test_a_body_too_large_for_the_room_names_robot_radius():
    error = _refusal(drive_doc(robot={"radius": 5.0}))
    assert error.field == "robot.radius" and "state space" in error.reason


def test_a_start_set_at_the_wall_names_initial():
    doc = drive_doc()
    error = _refusal({**doc, "initial": {**doc["initial"], "lower": [0.1, 0.5],
                                         "state": [0.5, 1.0]}})
    assert error.field == "initial" and "boundary" in error.reason
    assert "[0.22, 9.78] x [0.22, 7.78]" in error.reason         # where it may lie


def test_a_start_set_reaching_an_obstacle_names_initial():
    """The obstacle [2.5, 3.5] x [0, 2.5] inflated by 0.22 reaches x = 2.28; the set ends
    at 2.45, its point 2.1 is clear."""
    error = _refusal(drive_doc(initial={"lower": [2.0, 0.5], "upper": [2.45, 1.5],
                                        "state": [2.1, 1.0], "heading": 0.0}))
    assert error.field == "initial" and "obstacles[0]" in error.reason


# 5. An unknown key gets a "did you mean" when a key is close to it


@pytest.mark.parametrize("table, key, meant", [
    ("plant", "axel_offset", "axle_offset"),
    ("controller", "rate", "rate_hz"),
    (None, "actuators", "actuator"),
])
def test_an_unknown_key_suggests_the_closest(table, key, meant):
    doc = drive_doc()
    if table is None:
        doc[key] = {"input_bound": [1.6, 16.0]}
    else:
        doc[table] = {**doc[table], key: 1.0}
    error = _refusal(doc)
    assert error.field == (key if table is None else f"{table}.{key}")
    assert f"did you mean {meant!r}?" in error.reason and "allowed:" in error.reason


def test_an_unknown_key_far_from_every_key_gets_no_suggestion():
    error = _refusal(drive_doc(controller={"rate_hz": 200.0, "zzz": 1.0}))
    assert "did you mean" not in error.reason
    assert "allowed: compensate_delay, delay, gain, jitter, rate_hz" in error.reason


# 6. A differential drive's heading is in radians, within [-pi, pi]


@pytest.mark.parametrize("heading, hint", [
    (90.0, "if 90 is in degrees, it is 1.5708 rad"),
    (-45.0, "if -45 is in degrees, it is -0.785398 rad"),
    (3.5, "the same heading is -2.78319"),
    (1000.0, "within [-pi, pi]"),
])
def test_a_heading_beyond_pi_is_refused_with_the_hint(heading, hint):
    doc = drive_doc()
    error = _refusal({**doc, "initial": {**doc["initial"], "heading": heading}})
    assert error.field == "initial.heading" and "radians" in error.reason
    assert hint in error.reason


@pytest.mark.parametrize("heading", [math.pi, -math.pi, 1.5708, -3.0])
def test_a_heading_within_pi_is_taken(heading):
    doc = drive_doc()
    spec = stt.Spec.from_dict({**doc, "initial": {**doc["initial"], "heading": heading}})
    assert spec.drive.heading == heading


# 7. A second-order spec refused for its cascade: the position tube designed is drawn


@pytest.mark.slow
def test_a_refused_cascade_carries_the_position_tube_it_designed():
    """umaze-cascade at 100 Hz: the position tube is certified, no second stage is; the
    refusal carries that tube (``design --plot`` draws it, titled as designed)."""
    from dataclasses import replace

    from stt_codegen.design.failures import FailureKind
    from stt_codegen.design.search import check_tube
    from stt_codegen.runtime.plots import rejected_figure

    spec = replace(stt.load_spec(str(SPECS / "umaze-cascade.toml")), rate_hz=100.0)
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(spec)
    error = info.value
    assert error.kind is FailureKind.SAMPLING_RATE and error.tried is not None
    assert check_tube(error.tried, spec).passed          # the position tube designed
    title = rejected_figure(spec, error).axes[0].get_title()
    assert "the tube designed" in title and "NO DESIGN (sampling rate)" in title


# 8. design_time_s is the whole design_tube call


def _timed_design(spec):
    started = time.perf_counter()
    design = stt.design_tube(spec)
    return design, time.perf_counter() - started


def test_design_time_includes_the_rejected_target_alternatives():
    """The first two target boxes are walled in: their searches fail before the third
    designs (without them, the time is about 40 % of the call's)."""
    from test_tasks import arena, spec_of

    walls = [([3.6, 3.6], [5.0, 3.9]), ([3.6, 3.9], [3.9, 5.0]), ([3.6, 1.1], [5.0, 1.4]),
             ([3.6, 1.4], [3.9, 2.4]), ([3.6, 2.4], [5.0, 2.7])]
    doc = arena(2, [], obstacles=[{"lower": lo, "upper": hi} for lo, hi in walls], t_c=10.0)
    doc.pop("tasks")
    doc["target"] = {"any_of": [{"lower": [4.4, 4.4], "upper": [5.0, 5.0]},
                                {"lower": [4.4, 1.6], "upper": [5.0, 2.2]},
                                {"lower": [4.4, 0.0], "upper": [5.0, 0.6]}]}
    design, measured = _timed_design(spec_of(doc))
    assert design.target_choice == 2
    assert 0.9 * measured <= design.design_time_s <= measured


@pytest.mark.slow
def test_design_time_includes_the_cascades_certification():
    design, measured = _timed_design(stt.load_spec("second-order-s1"))
    assert "second_stage" in design.__dict__          # certified once, kept
    assert 0.9 * measured <= design.design_time_s <= measured


# 4. Numbers in messages without float noise


def test_a_computed_bound_in_a_message_has_no_float_noise():
    """The room around initial.state 0.5 in [0.3, 0.7] is 0.7 - 0.5 = 0.19999999999999996."""
    error = _refusal(drive_doc(initial={"lower": [0.3, 0.5], "upper": [0.7, 1.5],
                                        "state": [0.5, 1.0], "half_width": [0.3, 0.3]}))
    assert error.field == "initial.half_width"
    assert "(at most 0.2 around the point)" in error.reason


def test_number_text_drops_the_noise_and_keeps_typed_values():
    from stt_codegen.errors import number_text

    assert number_text(0.45 - 0.1) == "0.35" and number_text(87.35000000000001) == "87.35"
    assert number_text(1234567.5) == "1234567.5" and number_text(0.1) == "0.1"
    assert number_text(3) == "3" and number_text(math.inf) == "inf"
