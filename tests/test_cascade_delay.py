"""The sampled cascade's certificate with a computation delay and jitter
(stt_codegen/design/certificate/cascade_sampled.py, docs/second-order.md, "A computation
delay and jitter"): without them it is the check it was, float for float; with them it
proves a delay on second-order-s1 and fails beyond it; the closed loop with the proved
delay stays in both tubes; the loader takes a delay for a second-order spec."""

from __future__ import annotations

import dataclasses
import tomllib

import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.cases import bundled_spec_bytes
from stt_codegen.design.cascade_gain import _rate_certified, fastest_searched_rate
from stt_codegen.design.certificate import certify_tube
from stt_codegen.design.certificate.cascade_sampled import (cascade_check_of, cascade_class,
                                                            check_cascade_sampled)
from stt_codegen.design.samples import sample_tube
from stt_codegen.tube import reference
from stt_codegen.verification.cascade import cascade_delay_check

#: Halvings of the bisections here (a resolution of h / 16: the largest delay found is
#: within h / 16 of the check's limit, so twice it is beyond the limit).
HALVINGS = 4


@pytest.fixture(scope="module")
def s1():
    """``(design, samples, cascade.delay)`` of second-order-s1 at its rate."""
    design = design_of("second-order-s1")
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    min_width = certify_tube(design.tube, design.spec).min_width
    return design, samples, cascade_delay_check(design.spec, design.tube, min_width, HALVINGS)


def _largest(s1) -> float:
    return s1[2].data["largest_delay_s"]


def _check(design, samples, **timing):
    spec = design.spec
    return check_cascade_sampled(design.tube, samples, design.stage, cascade_class(spec),
                                 spec.second_order.initial_velocity, **timing)


def test_without_delay_the_check_is_the_one_it_was(s1):
    design, samples, _ = s1
    plain = _check(design, samples)
    # the cached entry passes the spec's timing, delay=0.0 and jitter=0.0 here
    zero = cascade_check_of(design.tube, design.spec, design.stage)
    assert plain.passed and zero == plain and zero.data == plain.data
    assert "delay" not in zero.data and "jitter" not in zero.data


def test_s1_tolerates_a_delay_and_fails_at_twice_it(s1):
    design, samples, _ = s1
    largest = _largest(s1)
    h = 1.0 / design.tube.rate_hz
    assert largest is not None and 0.0 < largest < h
    plain, late = _check(design, samples), _check(design, samples, delay=largest)
    assert late.passed and late.data["delay"] == largest
    # the delay costs room in the velocity tube and raises the bound of |e2|
    assert late.velocity_margin < plain.velocity_margin
    assert late.max_abs_e2 > plain.max_abs_e2
    doubled = _check(design, samples, delay=min(2.0 * largest, h))
    assert not doubled.passed and "may leave its tube" in doubled.reason
    assert not _check(design, samples, delay=h).passed


def test_jitter_is_proved_too_and_costs_room(s1):
    design, samples, _ = s1
    h = 1.0 / design.tube.rate_hz
    plain = _check(design, samples)
    jittered = _check(design, samples, jitter=0.01 * h)
    assert jittered.passed and jittered.velocity_margin < plain.velocity_margin
    assert not _check(design, samples, jitter=0.2 * h).passed
    with pytest.raises(ValueError, match="delay \\+ 2 jitter <= dt"):
        _check(design, samples, delay=0.8 * h, jitter=0.2 * h)


@pytest.mark.slow
def test_the_closed_loop_with_the_proved_delay_stays_in_both_tubes(s1):
    largest = _largest(s1)
    timed = dataclasses.replace(stt.load_spec("second-order-s1"), delay=largest)
    design = stt.design_tube(timed)
    assert design.spec.delay == largest
    assert cascade_check_of(design.tube, timed, design.stage).passed
    # the peak of |e2| is in the first second (the start's transient)
    result = stt.simulate(design, backend="reference", horizon=1.0)
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    assert not result.exceeded_velocity_bound


def test_verify_reports_the_largest_delay(s1):
    design, _, check = s1
    assert check.name == "cascade.delay" and check.passed
    h = 1.0 / design.tube.rate_hz
    # on the bisection's grid of h / 16
    assert check.data["largest_delay_s"] / h * 2 ** HALVINGS == pytest.approx(
        round(check.data["largest_delay_s"] / h * 2 ** HALVINGS))
    assert check.data["delay_s"] == 0.0 and check.data["period_s"] == h
    assert "is tolerated" in check.detail and "1/16 of the period" in check.detail


def test_the_rate_search_skips_periods_shorter_than_the_delay(s1):
    design, _, _ = s1
    timed = dataclasses.replace(design.spec, delay=0.0009)
    assert fastest_searched_rate(1000.0, timed) == pytest.approx(1.0 / 0.0009)
    assert fastest_searched_rate(1000.0, design.spec) == 16000.0
    assert not _rate_certified(design.tube, timed, 2000.0)      # refused before any check


@pytest.mark.parametrize("case", ["second-order-s1", "second-order-quadrotor"])
def test_the_loader_takes_a_delay_for_a_second_order_spec(case):
    doc = tomllib.loads(bundled_spec_bytes(case).decode())
    period = 1.0 / doc["controller"]["rate_hz"]
    doc["controller"]["delay"] = 0.1 * period
    doc["controller"]["jitter"] = 0.01 * period
    spec = stt.Spec.from_dict(doc)
    assert (spec.delay, spec.jitter) == (0.1 * period, 0.01 * period)
    doc["controller"]["delay"] = period              # delay + 2 jitter beyond the period
    with pytest.raises(stt.SpecError) as raised:
        stt.Spec.from_dict(doc)
    assert raised.value.field == "controller.delay"


@pytest.mark.slow
def test_a_delay_the_cascade_cannot_hold_names_a_shorter_one_that_is_then_certified():
    """second-order-s1 at 1 kHz with a delay and jitter filling the period (0.98 ms, 10 us):
    no shape is certified and no faster rate holds the delay; the refusal names the largest
    delay (to 1/64 of it) with which a shape is certified at 1 kHz, and that design is
    certified."""
    spec = dataclasses.replace(stt.load_spec("second-order-s1"), delay=0.98e-3, jitter=1e-5)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    shorter = raised.value.advice["controller.delay"]
    assert 0.0 < shorter < 0.98e-3
    assert f"controller.delay = {shorter:.3g} s is certified at 1000 Hz" in str(raised.value)
    design = stt.design_tube(dataclasses.replace(spec, delay=shorter))
    assert design.certificate.passed and design.stage is not None


@pytest.mark.slow
def test_a_whole_period_the_cascade_cannot_hold_names_compensate_delay_then_certified():
    """second-order-s1 at 1 kHz with a whole period of delay and no jitter: the refusal
    names controller.compensate_delay = true, and that design is certified."""
    spec = dataclasses.replace(stt.load_spec("second-order-s1"), delay=1e-3)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert raised.value.advice == {"controller.compensate_delay": True}
    assert ("controller.compensate_delay = true is certified with controller.delay = 0.001 s "
            "at 1000 Hz") in str(raised.value)
    design = stt.design_tube(dataclasses.replace(spec, compensate_delay=True))
    assert design.certificate.passed and design.stage is not None
