"""A second-order plant's drift bound per axis (``[assumptions] drift_bound = [F_1, ..,
F_n]``, docs/second-order.md, "The class"): the spec's field, a quadrotor's own bound
(gravity on its vertical axis only), the certificate that reads it, and the small drone
that only it makes certifiable within its thrust."""

from __future__ import annotations

import dataclasses
import pathlib
import re
import tomllib

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.design.certificate.cascade_sampled import (CascadeClass, cascade_class,
                                                            check_cascade_sampled,
                                                            model_within_class)
from stt_codegen.design.samples import sample_tube
from stt_codegen.spec.second_order import model_bounds
from stt_codegen.tube import reference

DRONE = pathlib.Path(__file__).parent / "specs" / "drone-room.toml"


def _drone(**assumptions) -> dict:
    data = tomllib.loads(DRONE.read_text())
    data["assumptions"].update(assumptions)
    return data


def test_a_list_is_one_bound_per_axis_and_its_largest_is_the_drift_bound() -> None:
    order = stt.Spec.from_dict(_drone(drift_bound=[0.0, 0.5, 9.81])).second_order
    assert order.drift_bounds == (0.0, 0.5, 9.81) and order.drift_bound == 9.81
    same = stt.Spec.from_dict(_drone(drift_bound=2.0)).second_order
    assert same.drift_bounds == (2.0, 2.0, 2.0) and same.drift_bound == 2.0
    assert cascade_class(stt.Spec.from_dict(_drone(drift_bound=[0.0, 0.5, 9.81]))
                         ).drift_bounds(3).tolist() == [0.0, 0.5, 9.81]


@pytest.mark.parametrize("value,field,words", [
    ([1.0, 2.0], "assumptions.drift_bound", "needs 3 entries"),
    ([1.0, -2.0, 1.0], "assumptions.drift_bound[1]", "non-negative"),
    (-1.0, "assumptions.drift_bound", "non-negative"),
    ("9.81", "assumptions.drift_bound", "must be a number"),
])
def test_a_bad_drift_bound_names_the_field(value, field, words) -> None:
    with pytest.raises(stt.SpecError) as info:
        stt.Spec.from_dict(_drone(drift_bound=value))
    assert info.value.field == field and words in info.value.reason


def test_a_first_order_plant_takes_one_drift_bound() -> None:
    data = {"name": "flat", "prescribed_time": 5.0,
            "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 4.0]},
            "initial": {"lower": [0.2, 0.2], "upper": [0.8, 0.8]},
            "target": {"lower": [3.0, 3.0], "upper": [3.8, 3.8]},
            "assumptions": {"drift_bound": [0.1, 0.1]}}
    with pytest.raises(stt.SpecError) as info:
        stt.Spec.from_dict(data)
    assert info.value.field == "assumptions.drift_bound"
    assert "only for a second-order plant.model" in info.value.reason


def test_a_quadrotors_own_drift_has_gravity_on_its_vertical_axis_only() -> None:
    own = model_bounds("quadrotor", (1.2, 0.3, 9.81), 3, (3.0, 3.0, 2.0), (0,) * 3, (6,) * 3)
    assert own.drift_bounds == pytest.approx((0.75, 0.75, 9.81 + 0.5), rel=1e-15)
    assert own.drift_bound == pytest.approx(9.81 + 0.5, rel=1e-15)
    flat = model_bounds("double-integrator", (2.0,), 2, None, (0,) * 2, (6,) * 2)
    assert flat.drift_bounds == (0.0, 0.0) and flat.drift_bound == 0.0
    dragged = model_bounds("quadrotor", (1.2, 0.3, 9.81), 3, None, (0,) * 3, (6,) * 3)
    assert dragged.drift_bounds is None and dragged.drift_bound is None


def test_the_model_is_checked_against_each_axis_of_the_class() -> None:
    spec = stt.Spec.from_dict(_drone(drift_bound=[0.0, 0.0, 9.81]))
    ok, words, data = model_within_class(spec)
    assert ok and data["drift"] == [0.0, 0.0, 9.81]
    short = stt.Spec.from_dict(_drone(drift_bound=[0.0, 0.0, 9.0]))
    ok, words, _ = model_within_class(short)
    assert not ok and "max |f_2| = 9.81" in words and "f_0" not in words


@pytest.fixture(scope="module")
def s1():
    design = design_of("second-order-s1")
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    return design, samples


def _check(s1, drift):
    design, samples = s1
    plants = CascadeClass(1.0, 1.0, 0.0, drift, 0.0, design.spec.disturbance_amplitude,
                          design.spec.second_order.velocity_bound)
    return check_cascade_sampled(design.tube, samples, design.second_stage[0], plants,
                                 design.spec.second_order.initial_velocity)


def test_equal_entries_are_the_one_bound_and_a_smaller_entry_only_helps(s1) -> None:
    """The certificate with ``(F, F)`` is the one with ``F``, figure for figure; with
    ``(0, F)`` it is at least as good: margins no smaller, the first axis's peaks smaller,
    the second axis's the same."""
    one, both = _check(s1, 0.5), _check(s1, (0.5, 0.5))
    assert one == dataclasses.replace(both, data=one.data) and one.passed
    calm = _check(s1, (0.0, 0.5))
    assert calm.passed
    assert calm.position_margin >= one.position_margin
    assert calm.velocity_margin >= one.velocity_margin
    assert calm.peak_input[0] < one.peak_input[0] and calm.peak_velocity[0] < one.peak_velocity[0]
    assert calm.peak_input[1] == pytest.approx(one.peak_input[1], rel=1e-9)
    assert "[0, 0.5]_i" in calm.data["class"]


def test_a_bound_with_the_wrong_number_of_axes_is_refused(s1) -> None:
    with pytest.raises(ValueError, match="1 or 2 entries"):
        _check(s1, (0.1, 0.2, 0.3))


@pytest.mark.slow
def test_the_drone_at_200_hz_is_certified_within_its_thrusts() -> None:
    """The small drone (thrusts [4, 4, 10] N, 0.4-0.6 kg, gravity on z only) at 200 Hz and
    its own 10 s: certified within the thrusts by a via tube with blended corners."""
    spec = stt.load_spec(str(DRONE))
    design = stt.design_tube(spec)
    assert design.method == "via" and design.tube.blends_corners
    assert design.certificate.passed and design.spec.prescribed_time == spec.prescribed_time
    assert design.input_proof.meets(spec.input_bound)


#: A deadline the drone at 200 Hz does not meet: its refusals name what works.
SHORTER = 8.0


@pytest.mark.slow
def test_the_drone_at_200_hz_names_a_prescribed_time_that_is_then_certified() -> None:
    """At 8 s the drone at 200 Hz is refused, naming a prescribed_time; designed with it,
    certified within the thrusts."""
    spec = dataclasses.replace(stt.load_spec(str(DRONE)), prescribed_time=SHORTER)
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(spec)
    named = info.value.advice["prescribed_time"]
    assert spec.prescribed_time < named <= 20.0
    design = stt.design_tube(dataclasses.replace(spec, prescribed_time=named))
    assert design.input_proof is not None
    assert np.all(np.asarray(design.input_proof.peak) <= np.asarray(spec.input_bound))


@pytest.mark.slow
def test_the_drone_at_200_hz_names_a_faster_rate_that_keeps_its_own_time() -> None:
    """The same refusal names a faster rate at which the spec's own prescribed_time is
    certified within the thrusts: the rate that keeps the tubes when the whole design with
    the bound is certified there, else a multiple of it (``FASTER_RATE_FACTORS``)."""
    spec = dataclasses.replace(stt.load_spec(str(DRONE)), prescribed_time=SHORTER)
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(spec)
    rate = info.value.advice["controller.rate_hz"]
    words = str(info.value)
    assert re.search(rf"controller\.rate_hz = {rate:g} is certified\b", words), words
    kept = re.search(r"controller\.rate_hz = ([0-9.]+) keeps the tubes but no design there "
                     r"keeps actuator\.input_bound", words)
    assert kept is None or float(kept.group(1)) < rate, words
    assert spec.rate_hz < rate <= 16.0 * spec.rate_hz
    design = stt.design_tube(dataclasses.replace(spec, rate_hz=rate))
    assert design.certificate.passed and design.spec.prescribed_time == spec.prescribed_time
    assert design.input_proof.meets(spec.input_bound)
