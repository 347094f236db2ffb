"""A later deadline moves the ``[[tasks]]`` windows that end at it (stt_codegen/spec/deadline.py,
docs/design.md, "Actuator limits"): the spec so moved, and a refusal for the force that
names such a deadline with ``tasks.window_end``, then certified."""

from __future__ import annotations

import pytest
from test_force_limits import _stay_then_target

import stt_codegen as stt
from stt_codegen.design.failures import FailureKind
from stt_codegen.spec.deadline import WINDOW_END, ending_windows, with_deadline


def _doors(prescribed_time: float = 20.0) -> dict:
    """Two reach tasks (one by the deadline, one by 12 s), two doors that last until the
    first (one still, one moving), and a target of two boxes."""
    return {"name": "doors", "prescribed_time": prescribed_time,
            "state_space": {"lower": [0.0, 0.0], "upper": [10.0, 10.0]},
            "initial": {"lower": [1.0, 1.0], "upper": [2.0, 2.0]},
            "target": {"any_of": [{"lower": [8.0, 8.0], "upper": [9.0, 9.0]},
                                  {"lower": [8.0, 1.0], "upper": [9.0, 2.0]}]},
            "obstacles": [{"lower": [5.0, 4.0], "upper": [6.0, 6.0], "active_until": "T1"},
                          {"lower": [3.0, 6.0], "upper": [3.5, 6.5], "velocity": [0.1, 0.0],
                           "active_until": "T1"}],
            "tasks": [{"kind": "reach", "window": [0.0, prescribed_time],
                       "lower": [1.0, 8.0], "upper": [2.0, 9.0]},
                      {"kind": "reach", "window": [2.0, 12.0],
                       "lower": [4.0, 1.0], "upper": [5.0, 2.0]}]}


def test_the_windows_that_end_at_the_deadline_move_with_it_and_no_other() -> None:
    spec = stt.Spec.from_dict(_doors())
    assert ending_windows(spec) == (0,)
    later = with_deadline(spec, 30.0)
    assert later.prescribed_time == 30.0
    assert [t.window for t in later.tasks] == [(0.0, 30.0), (2.0, 12.0)]
    # the doors last until the first task, so until its window's new end at the latest;
    # the one that moves moves on until then
    assert [ob.active for ob in later.moving_obstacles] == [(0.0, 30.0), (0.0, 30.0)]
    assert later.moving_obstacles[1].centres[-1] == pytest.approx((3.25 + 3.0, 6.25))
    # each target box is a spec of its own, moved alike; the spec written at 30 s is the same
    written = stt.Spec.from_dict({**_doors(30.0), "tasks": [
        {**_doors()["tasks"][0], "window": [0.0, 30.0]}, _doors()["tasks"][1]]})
    for (q, moved), (p, own) in zip(later.target_any_of, written.target_any_of):
        assert q == p and moved.tasks == own.tasks
        assert moved.moving_obstacles == own.moving_obstacles
    assert later.tasks == written.tasks and later.moving_obstacles == written.moving_obstacles
    with pytest.raises(ValueError, match="below the spec's"):
        with_deadline(spec, 10.0)
    # a spec whose windows all end earlier moves its prescribed_time alone
    fixed = stt.Spec.from_dict({**_doors(), "tasks": [
        {**_doors()["tasks"][0], "window": [0.0, 15.0]}, _doors()["tasks"][1]]})
    assert ending_windows(fixed) == ()
    assert with_deadline(fixed, 30.0).tasks == fixed.tasks


@pytest.mark.slow
def test_a_force_refusal_names_a_deadline_that_moves_the_windows_then_certified() -> None:
    """stlpy's EitherOr as a double integrator at its own 20 s, |u| <= 0.5 N: refused for
    the force, naming at most 30 s (1.5 times the horizon; 28 s with the S-curve legs)
    with the stay window that ends at 20 s ending at it; the spec so moved is certified within the bound. The same spec with the
    window ending at 19 s names no time (a later deadline does not move that window)."""
    spec = stt.Spec.from_dict(_stay_then_target(20.0))
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(spec)
    assert info.value.kind is FailureKind.INPUT_BOUND
    named = info.value.advice["prescribed_time"]
    assert info.value.advice[WINDOW_END] == named and 20.0 < named <= 30.0
    assert "windows that end at 20 s ending at it too" in str(info.value)
    design = stt.design_tube(with_deadline(spec, named))
    assert design.certificate.passed and design.input_proof.meets(spec.input_bound)
    assert design.spec.tasks[0].window == (0.0, named)
    doc = _stay_then_target(20.0)
    doc["tasks"][0]["window"] = [0.0, 19.0]
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(stt.Spec.from_dict(doc))
    assert "prescribed_time" not in info.value.advice
    assert "none of which ends at prescribed_time" in str(info.value)


def test_a_deadline_too_short_for_the_rate_moves_the_windows_that_end_at_it() -> None:
    """The shared deadline search (design/deadline.py) follows the same rule as the force's:
    a tube too fast for 1 kHz, with a task window that ends at ``t_c``, is refused naming a
    later time with ``tasks.window_end``; the spec so moved is certified. With the window
    ending earlier, no time is named (a later ``t_c`` does not move it)."""
    doc = {"name": "rushed-task", "prescribed_time": 0.05,
           "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 1.0]},
           "initial": {"lower": [0.0, 0.0], "upper": [0.5, 1.0]},
           "target": {"lower": [3.5, 0.0], "upper": [4.0, 1.0]},
           "tasks": [{"kind": "reach", "window": [0.0, 0.05],
                      "lower": [2.0, 0.0], "upper": [2.5, 1.0]}]}
    spec = stt.Spec.from_dict(doc)
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(spec)
    assert info.value.kind is FailureKind.SAMPLING_RATE
    named = info.value.advice["prescribed_time"]
    assert info.value.advice[WINDOW_END] == named > 0.05
    assert "windows that end at 0.05 s ending at it too is certified" in str(info.value)
    design = stt.design_tube(with_deadline(spec, named))
    assert design.certificate.passed and design.spec.tasks[0].window == (0.0, named)
    doc["tasks"][0]["window"] = [0.0, 0.04]
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(stt.Spec.from_dict(doc))
    assert "prescribed_time" not in info.value.advice
