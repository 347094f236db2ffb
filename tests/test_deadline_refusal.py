"""A deadline too short for the rate is refused naming a ``prescribed_time`` that
``design_tube`` then certifies (design/deadline.py), for law (13) and for the cascade."""

from __future__ import annotations

import dataclasses
import re

import pytest

import stt_codegen as stt
from stt_codegen.design.failures import FailureKind


@pytest.mark.parametrize("case, deadline", [
    pytest.param("omnirobot-s1", 0.5, marks=pytest.mark.slow), ("second-order-s1", 1.0)])
def test_a_deadline_too_short_names_one_that_is_then_certified(case, deadline):
    spec = dataclasses.replace(stt.load_spec(case), prescribed_time=deadline)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert raised.value.kind in (FailureKind.SAMPLING_RATE, FailureKind.NON_EMPTY)
    named = re.search(r"prescribed_time = ([0-9.]+) s is certified$", str(raised.value))
    assert named is not None, str(raised.value)
    later = float(named.group(1))
    assert deadline < later <= 16 * deadline
    assert raised.value.advice["prescribed_time"] == later     # for a program to follow
    design = stt.design_tube(dataclasses.replace(spec, prescribed_time=later))
    assert design.certificate.passed and design.spec.prescribed_time == later


def test_a_refusal_a_later_deadline_cannot_cure_is_left_as_it_is():
    """An obstacle over the target: no deadline helps, and none is named."""
    spec = stt.Spec.from_dict({
        "name": "walled", "prescribed_time": 5.0,
        "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 4.0]},
        "initial": {"lower": [0.0, 0.0], "upper": [0.5, 0.5]},
        "target": {"lower": [3.0, 3.0], "upper": [4.0, 4.0]},
        "obstacles": [{"lower": [2.5, 0.0], "upper": [2.8, 4.0]}]})
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert "prescribed_time =" not in str(raised.value)
    assert raised.value.advice == {}


@pytest.mark.slow
def test_no_room_for_a_circumvent_and_a_via_tube_too_fast_names_a_deadline():
    """stlpy's NonlinearReachAvoid as a differential drive: no circumvent fits, and the via
    tube is too fast for 100 Hz; the refusal is the via tube's (a slower tube cures it) and
    names the prescribed_time that is then certified within the base's limits."""
    from pathlib import Path
    spec = stt.load_spec(str(Path(__file__).parent / "specs"
                             / "nonlinear-reach-avoid-drive.toml"))
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert raised.value.kind is FailureKind.SAMPLING_RATE
    assert "cannot be circumvented" in str(raised.value)
    later = raised.value.advice["prescribed_time"]
    assert str(raised.value).endswith(f"prescribed_time = {later:g} s is certified")
    design = stt.design_tube(dataclasses.replace(spec, prescribed_time=later))
    assert design.certificate.passed and design.input_proof.meets(spec.input_bound)


@pytest.mark.parametrize("deadline, smallest", [(10.0, 19.0), (10.0, 11.0), (7.3, 29.0),
                                                (10.0, 160.0), (10.0, 161.0)])
def test_the_deadline_search_names_the_smallest_grid_time_a_monotone_search_certifies(
        deadline, smallest):
    """certified_time on a search that certifies every t_c >= ``smallest``: doubling finds
    a passing time, the bisection goes on to neighbouring grid values, and the time named is
    the smallest on the two-digit grid at or above ``smallest`` (three bisection steps named
    20 s for 19 s), or none beyond 16 times t_c; each trial is a spec moved there."""
    from stt_codegen.design.deadline import certified_time
    from stt_codegen.design.grid import grid_index, grid_value
    spec = dataclasses.replace(stt.load_spec("second-order-s1"), prescribed_time=deadline)
    tried = []

    def search(trial):
        tried.append(trial.prescribed_time)
        if trial.prescribed_time < smallest:
            raise stt.DesignError("too fast", kind=FailureKind.SAMPLING_RATE)
        return None

    named = certified_time(spec, search)
    if smallest > 16 * deadline:
        assert named is None
    else:
        assert named == grid_value(grid_index(smallest)) and named in tried
        assert all(t < smallest for t in tried if t < named)
