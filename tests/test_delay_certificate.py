"""A computation delay and sampling jitter in the sampled-data certificate:
``[controller] delay`` and ``jitter`` are validated, the check proves the tube kept with them
(docs/sampled-data.md, "Computation delay and jitter"), ``verify`` reports the largest delay
the design tolerates, and the check fails beyond it."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import arena_toml, designed
from hypothesis import HealthCheck, event, given, note, settings
from hypothesis import strategies as st

import stt_codegen as stt
from stt_codegen.design.certificate.plant_class import plant_class
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.certificate.sampled import (check_sampled,
                                                    check_sampled_first_per_axis,
                                                    largest_delay, lowest_rate)
from stt_codegen.design.samples import sample_tube
from stt_codegen.tube import reference
from stt_codegen.verification.sampled import delay_check

SPECS = Path(__file__).parent / "specs"


def _timed(spec, delay=0.0, jitter=0.0):
    return dataclasses.replace(spec, delay=delay, jitter=jitter)


def _check(spec, design, **timing):
    with reference.numpy_math():
        return check_sampled_first_per_axis(design, sample_tube(design), plant_class(spec),
                                            **timing)


@pytest.fixture(scope="module")
def s1():
    spec, design, _ = designed("omnirobot-s1")
    with reference.numpy_math():
        largest = largest_delay(design, spec)
    return spec, design, largest


def test_without_delay_the_check_is_the_one_it_was(s1):
    spec, design, _ = s1
    with reference.numpy_math():
        samples, plants = sample_tube(design), plant_class(spec)
        plain = check_sampled(design, samples, plants, lyapunov=False)
        zero = check_sampled(design, samples, plants, lyapunov=False, delay=0.0, jitter=0.0)
    assert (plain.passed, plain.level, plain.margin) == (zero.passed, zero.level, zero.margin)
    assert zero.data["delay"] == 0.0 and zero.data["jitter"] == 0.0


def test_omnirobot_s1_tolerates_a_fraction_of_its_period(s1):
    spec, design, largest = s1
    dt = 1.0 / design.rate_hz
    assert largest is not None and 0.0 < largest < dt
    assert _check(spec, design, delay=largest).passed


def test_the_check_fails_when_the_delay_is_doubled_past_the_largest(s1):
    """A design certified with a delay fails its sampled check beyond twice that delay:
    the check can fail, and the largest delay is not a vacuous figure."""
    spec, design, largest = s1
    certified = _check(spec, design, delay=largest)
    doubled = _check(spec, design, delay=min(2.0 * largest, 1.0 / design.rate_hz))
    assert certified.passed
    assert not doubled.passed and "may leave the tube" in doubled.reason
    assert doubled.margin < 0.0 < certified.margin


@pytest.mark.slow
def test_a_delay_costs_margin_and_raises_the_bound_of_e(s1):
    spec, design, largest = s1
    plain, late = _check(spec, design), _check(spec, design, delay=0.5 * largest)
    assert plain.passed and late.passed
    assert late.margin < plain.margin and late.level > plain.level


@pytest.mark.slow
def test_jitter_is_proved_too_and_costs_delay(s1):
    spec, design, largest = s1
    dt = 1.0 / design.rate_hz
    jitter = 0.02 * dt
    assert _check(spec, design, jitter=jitter).passed
    with reference.numpy_math():
        with_jitter = largest_delay(design, _timed(spec, jitter=jitter))
    assert with_jitter is not None and with_jitter <= largest
    assert not _check(spec, design, delay=largest, jitter=0.25 * dt).passed


def test_the_check_refuses_a_delay_beyond_the_period(s1):
    spec, design, _ = s1
    dt = 1.0 / design.rate_hz
    with pytest.raises(ValueError, match="delay \\+ 2 jitter <= dt"):
        _check(spec, design, delay=0.8 * dt, jitter=0.2 * dt)


@pytest.mark.slow
def test_verify_reports_the_largest_delay(s1):
    spec, design, largest = s1
    with reference.numpy_math():
        check = delay_check(spec, design)
    assert check.passed and check.name == "sampled.delay"
    assert check.data["largest_delay_s"] == largest
    assert f"{largest * 1000:.4g} ms" in check.detail and "tolerated" in check.detail
    # a spec asking for more than the design tolerates fails the same check
    with reference.numpy_math():
        beyond = delay_check(_timed(spec, delay=min(2.0 * largest, 1.0 / design.rate_hz)),
                             design)
    assert not beyond.passed and "beyond it" in beyond.detail


def test_no_delay_check_where_the_sampled_check_fails_without_one():
    """gain-range-s2-fixed-gain fails sampled.tube_kept; sampled.delay adds no second
    failure for it (None), where a passing design gets its figure."""
    from pathlib import Path
    spec = stt.load_spec(Path(__file__).parent / "specs" / "gain-range-s2-fixed-gain.toml")
    design = stt.design_tube(spec)
    with reference.numpy_math():
        assert not _check(spec, design.tube).passed
        assert delay_check(spec, design.tube) is None


@pytest.mark.slow
def test_the_lowest_rate_counts_the_delay_in_seconds(s1):
    """A delay of 0.9 ms fits a 1 kHz period but not a shorter one: no rate above the
    design's is named for it, and the rate named is one that passes with it."""
    spec, design, largest = s1
    timed = _timed(spec, delay=largest)
    with reference.numpy_math():
        rate, gain = lowest_rate(design, timed, plant_class(timed), None)
    assert rate is not None and rate <= design.rate_hz
    assert largest + 0.0 <= 1.0 / rate


# ---------------------------------------------------------------------------------------
# the spec's keys


def _spec_text(controller: str, plant: str = "") -> str:
    return arena_toml("timed", extra="[controller]\n" + controller + plant)


@pytest.mark.parametrize("controller, field, words", [
    ("rate_hz = 100.0\ndelay = 0.011\n", "controller.delay", "exceeds the period"),
    ("rate_hz = 100.0\ndelay = 0.006\njitter = 0.003\n", "controller.delay",
     "delay + 2 jitter = 0.012 s"),
    ("rate_hz = 100.0\njitter = 0.006\n", "controller.jitter", "exceeds the period"),
    ("rate_hz = 100.0\ndelay = -0.001\n", "controller.delay", ""),
])
def test_a_delay_that_does_not_fit_the_period_names_its_field(tmp_path, controller, field,
                                                              words):
    path = tmp_path / "timed.toml"
    path.write_text(_spec_text(controller))
    with pytest.raises(stt.SpecError) as raised:
        stt.load_spec(path)
    assert raised.value.field == field and words in str(raised.value)


def test_the_command_line_refuses_it_with_exit_2_and_one_line(tmp_path):
    path = tmp_path / "timed.toml"
    path.write_text(_spec_text("rate_hz = 100.0\ndelay = 0.02\n"))
    run = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", str(path)],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert "controller.delay" in run.stderr


def test_specs_without_delay_keep_zero():
    spec = stt.load_spec("omnirobot-s1")
    assert (spec.delay, spec.jitter) == (0.0, 0.0)
    assert math.isclose(1.0 / spec.rate_hz, 1e-3)


# ---------------------------------------------------------------------------------------
# the look-ahead law: the held (v, omega) turns the point's g with the heading


def _office(rate_hz: float):
    import tomllib
    from stt_codegen.cases import bundled_spec_bytes
    doc = tomllib.loads(bundled_spec_bytes("office-base").decode())
    doc["controller"] = {"rate_hz": rate_hz}
    doc.pop("actuator")               # the tube alone: no input bound to design within
    spec = stt.Spec.from_dict(doc)
    return spec, stt.design_tube(spec).tube


def test_the_heading_turn_of_the_held_command_is_counted():
    """At 50 Hz the check without the turn passes and with it fails, naming the turn; at
    200 Hz it passes with the turn. The turn is the base's own (input_gain_turn)."""
    spec, design = _office(50.0)
    turn = spec.assumptions.input_gain_turn
    drive = spec.drive
    m, d = drive.mean_error, abs(drive.differential_error)
    assert turn[0] >= (1 + m) / drive.axle_offset + 2 * d / drive.track_width
    assert turn[1] >= drive.slip[2]
    without = dataclasses.replace(spec, assumptions=dataclasses.replace(
        spec.assumptions, input_gain_turn=None))
    assert _check(without, design).passed
    turned = _check(spec, design)
    assert not turned.passed and "the heading may turn by" in turned.reason
    spec, design = _office(200.0)
    assert _check(spec, design).passed


@pytest.mark.slow
def test_the_look_ahead_takes_a_delay():
    spec, design = _office(200.0)
    with reference.numpy_math():
        largest = largest_delay(design, spec)
    assert largest is not None and 0.0 < largest < 1.0 / design.rate_hz
    assert _check(spec, design, delay=largest).passed
    assert not _check(spec, design, delay=min(2.0 * largest, 1.0 / design.rate_hz)).passed


# ---------------------------------------------------------------------------------------
# the design: its sampled proof must hold with the timing, else it names what works


def _line(rate_hz: float = 100.0, delay: float = 0.0):
    from pathlib import Path
    spec = stt.load_spec(Path(__file__).parent / "specs" / "line-s1.toml")
    return dataclasses.replace(spec, rate_hz=rate_hz, delay=delay)


def test_a_design_with_a_delay_is_proved_with_it():
    design = stt.design_tube(_line(delay=0.002))
    assert design.spec.delay == 0.002
    assert _check(design.spec, design.tube, delay=0.002).passed


def test_a_delay_the_design_cannot_take_is_refused_naming_one_that_is_then_certified():
    """A full period of delay at 100 Hz leaves line-s1's tube in simulation
    (tests/test_delay_closed_loop.py); the design refuses it and names a delay that it
    then certifies."""
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(_line(delay=0.01))
    error = raised.value
    assert error.kind.value == "timing"
    assert "controller.delay = 0.01 s at 100 Hz" in str(error)
    named = re.search(r"controller\.delay = ([0-9.e-]+) s is certified", str(error))
    assert named is not None
    delay = float(named.group(1))
    assert 0.0 < delay < 0.01
    design = stt.design_tube(_line(delay=delay))
    assert _check(design.spec, design.tube, delay=delay).passed


@pytest.mark.slow
def test_a_base_too_slow_for_its_turn_is_refused_naming_a_rate_then_certified():
    """office-base at 50 Hz: no design's proof holds (the heading's turn within a period);
    the refusal names a rate, at which the design and its sampled proof then hold."""
    import tomllib
    from stt_codegen.cases import bundled_spec_bytes
    doc = tomllib.loads(bundled_spec_bytes("office-base").decode())
    doc["controller"] = {"rate_hz": 50.0}
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(stt.Spec.from_dict(doc))
    assert "the heading may turn by" in str(raised.value)
    named = re.search(r"controller\.rate_hz = ([0-9.]+) is certified", str(raised.value))
    assert named is not None and float(named.group(1)) > 50.0
    doc["controller"] = {"rate_hz": float(named.group(1))}
    design = stt.design_tube(stt.Spec.from_dict(doc))
    assert _check(design.spec, design.tube).passed


# ---------------------------------------------------------------------------------------
# soundness: a run with the delay stays within what the check proves


@pytest.mark.slow
def test_the_run_with_the_largest_delay_stays_within_the_proved_bound_of_e(s1):
    """omnirobot-s1 with the largest delay the check proves: the closed loop (the robot's
    own plant, the generated C) keeps |e| at the samples below the check's bound of it."""
    spec, design, largest = s1
    late = dataclasses.replace(spec, delay=largest)
    proved = _check(late, design, delay=largest)
    result = stt.simulate(dataclasses.replace(stt.design_tube(spec), spec=late), backend="c")
    assert result.stayed_in_tube
    assert result.max_abs_e <= proved.level + 1e-9, (result.max_abs_e, proved.level)


@pytest.mark.slow
@settings(derandomize=True, deadline=None, database=None, max_examples=16,
          suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 2**32 - 1), g_min=st.floats(0.5, 1.2), spread=st.floats(0.0, 1.0),
       skew=st.floats(0.0, 0.1), coupling=st.floats(0.0, 0.1), drift=st.floats(0.0, 1.0),
       disturbance=st.floats(0.0, 0.3), share=st.floats(0.05, 1.0))
def test_no_plant_of_an_accepted_class_leaves_the_tube_with_the_delay(
        seed, g_min, spread, skew, coupling, drift, disturbance, share):
    """Random classes and delays: where the check passes with the delay, a random plant of
    the class run with that delay stays in the tube, with |e| at the samples below the
    check's bound."""
    from plants_helpers import plant_system, plant_within
    from stt_codegen.runtime.simulate import run_closed_loop
    from stt_codegen.spec.assumptions import Assumptions
    spec, design, _ = designed("omnirobot-s1")
    a = Assumptions((g_min, g_min + spread), skew, coupling, drift, disturbance)
    delay = share * largest_delay_of(design, spec, a)
    with reference.numpy_math():
        verdict = check_sampled_first_per_axis(design, sample_tube(design), a, delay=delay)
    note(f"delay {delay:.3g} s: {verdict.passed} {verdict.reason}")
    event("accepted" if verdict.passed else "refused")
    if not verdict.passed:
        return
    plant = plant_system(plant_within(np.random.default_rng(seed), a, spec.state_space))
    result = run_closed_loop(dataclasses.replace(spec, delay=delay), design, backend="c",
                             plant=plant)
    assert result.stayed_in_tube, (a, delay)
    assert result.max_abs_e <= verdict.level + 1e-9, (a, delay)


def largest_delay_of(design, spec, assumptions, halvings: int = 3) -> float:
    """A delay the check proves for a class given by hand, within ``dt / 2^halvings`` below
    the largest (0 if none): the property test draws its delay below it and checks the
    verdict at the delay drawn, so three halvings (not the design's six) will do."""
    from stt_codegen.design.certificate.sampled import largest_passing
    with reference.numpy_math():
        samples = sample_tube(design)
        found = largest_passing(
            lambda d: check_sampled_first_per_axis(design, samples, assumptions,
                                                   delay=d).passed,
            1.0 / design.rate_hz, halvings=halvings)
    return found or 0.0


@pytest.mark.slow
def test_a_base_at_50_hz_is_certified_but_not_with_a_whole_period_of_delay():
    """The Kobuki-like base is certified at 50 Hz; with a 20 ms delay (a whole period) law
    (13)'s check fails at every shorter delay tried and no faster rate can hold the delay:
    the refusal names the prediction (controller.compensate_delay), which then designs."""
    spec = stt.load_spec(str(SPECS / "kobuki-office.toml"))
    assert stt.design_tube(spec).certificate.passed
    late = dataclasses.replace(spec, delay=0.02)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(late)
    words = str(raised.value)
    assert raised.value.kind is FailureKind.TIMING
    assert raised.value.advice == {"controller.compensate_delay": True}
    assert "controller.compensate_delay = true is certified with controller.delay = 0.02 s" \
        in words
    assert stt.design_tube(dataclasses.replace(late, compensate_delay=True)).certificate.passed