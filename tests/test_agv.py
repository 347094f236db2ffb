"""A warehouse AGV at the base's speed, and waiting for a forklift (docs/differential-drive.md,
docs/moving-obstacles.md): the base's ``|u|`` bounded sample by sample, the refusal that
names ``plant.axle_offset``, and the re-timed via plan kept within ``[actuator]``."""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.input_bound import InputProof, input_peak
from stt_codegen.design.look_ahead import look_ahead_input_proof
from stt_codegen.design.moving import DURATION_FACTORS, MOTION_TIMED_VIA, speed_limits
from stt_codegen.design.route import route_length
from stt_codegen.design.search import check_tube
from stt_codegen.errors import SpecError

SPECS = Path(__file__).parent / "specs"
AGV = SPECS / "agv-warehouse.toml"
FORKLIFT = SPECS / "agv-forklift.toml"


def _agv_doc(**plant) -> dict:
    doc = tomllib.loads(AGV.read_text())
    doc["plant"].update(plant)
    return doc


def test_the_norm_bound_lies_between_the_largest_peak_and_their_hypot():
    """``speed`` is the norm of the per-input bounds at one sample: at most
    ``hypot(*peak)`` (equal only where the inputs peak at the same sample) and at least
    every single peak, on random bounds."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        abs_e = rng.uniform(0.0, 0.9, size=(40, 2))
        width = rng.uniform(0.05, 2.0, size=(40, 2))
        t = np.arange(40) * 0.02
        proof = input_peak(0.3, abs_e, width, t, 1.0)
        assert max(proof.peak) <= proof.speed <= math.hypot(*proof.peak) * (1 + 1e-12)
        k = int(round(proof.speed_time / 0.02))
        u = 4 * 0.3 * 2 * np.arctanh(abs_e[k]) / (1 - abs_e[k] ** 2) / width[k]
        assert proof.speed == pytest.approx(float(np.hypot(*u)), rel=1e-12)


def test_the_base_takes_the_norm_bound_and_falls_back_to_the_peaks():
    with_norm = InputProof(True, (0.6, 0.8), (1.0, 2.0), 11.0, speed=0.9, speed_time=1.5)
    assert look_ahead_input_proof(with_norm, 0.5).peak == (0.9, 1.8)
    assert look_ahead_input_proof(with_norm, 0.5).time == (1.5, 1.5)
    peaks_only = InputProof(True, (0.6, 0.8), (1.0, 2.0), 11.0)
    assert look_ahead_input_proof(peaks_only, 0.5).peak == pytest.approx((1.0, 2.0))
    assert look_ahead_input_proof(peaks_only, 0.5).time == (2.0, 2.0)


def test_another_axle_offset_is_the_spec_loaded_with_it():
    at_06 = stt.Spec.from_dict(_agv_doc(axle_offset=0.6))
    at_08 = stt.Spec.from_dict(_agv_doc())
    assert at_06.with_axle_offset(0.8) == at_08        # sets, obstacles, assumptions, base
    assert at_08.with_axle_offset(0.6) == at_06
    assert at_06.with_axle_offset(0.8).robot.radius == pytest.approx(1.2)


def test_another_axle_offset_applies_to_every_target_box():
    boxes = {"any_of": [{"lower": [17.5, 1.5], "upper": [18.5, 2.5]},
                        {"lower": [17.5, 9.5], "upper": [18.5, 10.5]}]}
    at_06 = stt.Spec.from_dict({**_agv_doc(axle_offset=0.6), "target": boxes})
    at_08 = stt.Spec.from_dict({**_agv_doc(), "target": boxes})
    longer = at_06.with_axle_offset(0.8)
    assert [k for k, _ in longer.target_any_of] == [k for k, _ in at_08.target_any_of] == [0, 1]
    assert all(a == b for (_, a), (_, b) in zip(longer.target_any_of, at_08.target_any_of))


def test_another_axle_offset_is_refused_by_field():
    spec = stt.load_spec(str(AGV))
    with pytest.raises(SpecError) as raised:
        spec.with_axle_offset(1.6)          # the start set no longer fits beside the wall
    assert raised.value.field == "initial"
    with pytest.raises(SpecError) as raised:
        spec.with_axle_offset(6.0)          # the robot no longer fits in the floor's 12 m
    assert raised.value.field == "plant.axle_offset"
    with pytest.raises(SpecError) as raised:
        spec.with_axle_offset(0.0)
    assert raised.value.field == "plant.axle_offset"
    with pytest.raises(SpecError) as raised:
        stt.load_spec("crossing-moving").with_axle_offset(0.5)
    assert raised.value.field == "plant.model"


def test_the_retiming_leaves_out_fast_segments_only_with_an_actuator():
    assert speed_limits(stt.load_spec("crossing-moving")) == [DURATION_FACTORS]
    sets = speed_limits(stt.load_spec(str(FORKLIFT)))
    # no leg faster than planned first (then slower), then faster and faster
    assert [min(s) for s in sets] == [1.0, 1.5, 2.0, 0.75, 0.5]
    assert sets[-1] == DURATION_FACTORS
    assert all(set(s) == {f for f in DURATION_FACTORS if f >= min(s)} for s in sets)


def test_the_agv_is_certified_within_twice_the_straight_line_time():
    """The AGV (v_max 1.2 m/s, omega_max 1.5 rad/s) in 40 s along a 29 m route: 1.65 times
    the straight-line time at v_max, its (v, omega) proved within the bound."""
    spec = stt.load_spec(str(AGV))
    design = stt.design_tube(spec)
    assert design.certificate.passed
    assert design.input_proof.meets(spec.input_bound)
    straight = route_length(design.tube, spec.initial_state) / spec.input_bound[0]
    assert 20.0 < straight < spec.prescribed_time <= 2.0 * straight


@pytest.mark.slow
def test_the_agv_closed_loop_reaches_the_target_within_the_limits():
    spec = stt.load_spec(str(AGV))
    result = stt.simulate(stt.design_tube(spec), backend="python")
    assert result.satisfied and not result.collision and result.stayed_in_tube
    assert result.reach_time <= spec.prescribed_time
    assert all(p <= b for p, b in zip(result.max_abs_u, spec.input_bound))


@pytest.mark.slow
def test_a_turn_rate_refusal_names_the_axle_offset_that_is_certified():
    """At a 0.4 m look-ahead with v_max 1.5 m/s, the AGV's best tube in 40 s keeps |v| but
    asks more than 1.5 rad/s even from the heading it can have: the refusal names
    plant.axle_offset (and prescribed_time), and each, followed alone, is certified."""
    doc = _agv_doc(axle_offset=0.4)
    doc["actuator"]["input_bound"] = [1.5, 1.5]
    short = stt.Spec.from_dict(doc)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(short)
    words = str(raised.value)
    offset = raised.value.advice["plant.axle_offset"]
    assert f"plant.axle_offset = {offset:g} m is certified" in words
    assert 0.4 < offset <= 0.8
    assert stt.design_tube(short.with_axle_offset(offset)).input_proof.meets(
        short.input_bound)
    later = raised.value.advice["prescribed_time"]
    assert stt.design_tube(replace(short, prescribed_time=later)).certificate.passed


@pytest.mark.slow
def test_the_agv_waits_for_the_forklift_then_crosses():
    """The forklift crosses the AGV's cross aisle as it arrives: the static tube meets it;
    with [actuator] the re-timed via plan (a slower first leg) lets it pass, its (v, omega)
    proved within the bound, and the closed loop is satisfied without contact."""
    spec = stt.load_spec(str(FORKLIFT))
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    assert design.input_proof.meets(spec.input_bound)
    without = stt.design_tube(replace(spec, moving_obstacles=()))
    crossing = [m for m in check_tube(without.tube, spec).certificate.margins
                if m.name == "avoids moving obstacle 3"]
    assert crossing and not crossing[0].passed            # it would have met the forklift
    mine = [m for m in design.certificate.margins if m.name == "avoids moving obstacle 3"]
    assert mine[0].passed and mine[0].margin > 0.0
    # the tube reaches the cross aisle's far corner later than the static one: it let the
    # forklift pass (the first segment that ends in that via box; a wait adds holds)
    corner = without.tube.segments[1]
    arrives = next(seg.end for seg in design.tube.segments
                   if (seg.lower_to, seg.upper_to) == (corner.lower_to, corner.upper_to))
    assert arrives > corner.end
    result = stt.simulate(design, backend="python")
    assert result.satisfied and not result.collision and result.stayed_in_tube


def test_velocity_inputs_try_blended_corners_last_and_not_where_an_obstacle_moves():
    """Law (13) and a base (a velocity input) try via points with cruise segments and
    blended corners last; not with an obstacle that moves (the forklift); with
    ``[sensing]`` too (the tube as data runs blended corners)."""
    from types import SimpleNamespace

    from stt_codegen.design.actuator import slower_variants
    default = SimpleNamespace(method="paper", tube=SimpleNamespace(circumvents=()))
    label = "via points, cruise segments, blended corners"
    omni = stt.load_spec("omnirobot-s1")
    for spec in (stt.load_spec(str(AGV)), replace(omni, tube=replace(omni.tube, method="auto"))):
        tried = slower_variants(spec, default)
        assert tried[-1][0] == label and tried[-1][1].tube.via_corners == "blend"
        assert tried[-1][1].tube.via_profile == "cruise"
    assert label not in dict(slower_variants(stt.load_spec(str(FORKLIFT)), default))
    assert label in dict(slower_variants(stt.load_spec("hall-crossing"), default))


@pytest.mark.slow
def test_blended_corners_shorten_a_sensed_mazes_named_time():
    """The U-maze with a sensing envelope (a single integrator) within 0.6 m/s: asked for
    12 s, it is named 23 s, where its stopped via tubes alone need 25 s."""
    doc = tomllib.loads((Path(__file__).parent / "specs" / "pointmaze-sensed.toml").read_text())
    del doc["plant"]
    spec = stt.Spec.from_dict({**doc, "actuator": {"input_bound": [0.6, 0.6]}})
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    named = raised.value.advice["prescribed_time"]
    assert named <= 23.0
    design = stt.design_tube(replace(spec, prescribed_time=named))
    assert design.tube.blends_corners and design.input_proof.meets(spec.input_bound)


@pytest.mark.slow
def test_blended_corners_shorten_the_agvs_named_time():
    """Asked for 30 s (refused), the AGV is named 36.5 s, where its stopped via tubes need
    39 s: the tube with blended corners asks less speed of the same time. Followed, it is
    certified with blended corners within [1.2 m/s, 1.5 rad/s]."""
    short = stt.Spec.from_dict({**tomllib.loads(AGV.read_text()), "prescribed_time": 30.0})
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(short)
    named = raised.value.advice["prescribed_time"]
    assert named <= 37.0
    design = stt.design_tube(replace(short, prescribed_time=named))
    assert design.tube.blends_corners
    assert design.input_proof.meets(short.input_bound)


def test_a_base_times_its_moves_for_the_turn_into_each():
    """With ``via_timing = "turn"`` a move after a right-angle corner gains ``via_turn pi /
    2`` of weight over the length timing, a straight run none, and a diagonal move weighs
    its Euclidean length (the length timing's max norm is a per-axis bound's). A base given its
    bound tries it after the length-timed tubes; law (13) does not."""
    from types import SimpleNamespace

    from stt_codegen.design.actuator import slower_variants
    from stt_codegen.design.via import timed_moves
    spec = stt.load_spec(str(AGV))
    moves = [np.array([4.0, 0.0]), np.array([0.0, 2.0]), np.array([0.0, 2.0])]
    turned = replace(spec, tube=replace(spec.tube, via_timing="turn", via_turn=0.8))
    length, _ = timed_moves(spec, moves, 8.0, "cruise")
    turn, _ = timed_moves(turned, moves, 8.0, "cruise")
    assert length == pytest.approx([4.0, 2.0, 2.0])
    weights = [4.0, 2.0 + 0.8 * math.pi / 2, 2.0]
    assert turn == pytest.approx([8.0 * w / sum(weights) for w in weights])
    # a diagonal move: its Euclidean length (the base's speed), not its max norm
    slanted = [np.array([4.0, 0.0]), np.array([3.0, 3.0])]
    turn, _ = timed_moves(turned, slanted, 8.0, "cruise")
    weights = [4.0, math.hypot(3.0, 3.0) + 0.8 * math.pi / 4]
    assert turn == pytest.approx([8.0 * w / sum(weights) for w in weights])
    assert timed_moves(spec, slanted, 7.0, "cruise")[0] == pytest.approx([4.0, 3.0])
    default = SimpleNamespace(method="paper", tube=SimpleNamespace(circumvents=()))
    labels = [label for label, _ in slower_variants(spec, default, (1.2, 1.5))]
    assert labels[-2:] == ["via points timed for the turn, cruise segments",
                           "via points timed for the turn, cruise segments, blended corners"]
    last = slower_variants(spec, default, (1.2, 1.5))[-2][1].tube
    assert last.via_timing == "turn" and last.via_turn == pytest.approx(1.2 / 1.5)
    omni = stt.load_spec("omnirobot-s1")
    omni = replace(omni, tube=replace(omni.tube, method="auto"))
    assert not any("turn" in label for label, _ in slower_variants(omni, default, (1.0, 1.0)))


@pytest.mark.slow
def test_legs_timed_for_the_turn_shorten_the_named_time_of_a_short_look_ahead():
    """At a 0.5 m look-ahead the AGV in 40 s is refused naming 41 s (44.5 s with its legs
    timed by length alone): its best tube gives the moves after the racks' corners the time
    to turn. Followed, it is certified within [1.2 m/s, 1.5 rad/s]."""
    short = stt.Spec.from_dict(_agv_doc(axle_offset=0.5))
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(short)
    named = raised.value.advice["prescribed_time"]
    assert named <= 42.0 and "timed for the turn" in str(raised.value)
    design = stt.design_tube(replace(short, prescribed_time=named))
    assert design.input_proof.meets(short.input_bound)

