"""Obstacles sensed at run time with MuJoCo as the plant (docs/sensing.md): the U-maze of
gymnasium-robotics with a sensing envelope; a person crosses its corridor ahead of the
ball, which waits, stays certified, and goes on when the way is clear."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.runtime.sensed import WalkingObstacle

pytest.importorskip("mujoco", reason="MuJoCo missing: pip install '.[mujoco]'")

SPEC = Path(__file__).parent / "specs" / "pointmaze-sensed.toml"


@pytest.mark.slow
def test_a_person_crossing_the_corridor_ahead_on_mujoco():
    """The person (0.15 m, 0.3 m/s, the envelope's speed) walks up across the top corridor
    at x = 0.5 m and out of the maze. The ball stops short of them (certified throughout,
    no contact), goes on once they are out, and reaches the target by t_c (its late plan
    replaced by a sooner path once the person is gone). The generated C with the tube as
    data and the CasADi model drive MuJoCo through the same states, bit for bit."""
    design = stt.design_tube(stt.load_spec(SPEC))
    person = WalkingObstacle((0.5, 0.9), 0.15, velocity=(0.0, 0.3))
    runs = [stt.simulate_sensed(design, [person], backend=b, horizon=20.0)
            for b in ("casadi", "c")]
    run, record = runs[1], runs[1].sensing
    assert record.guaranteed and record.uncertified == [] and not record.outside_envelope
    assert not record.sensed_collision and not run.collision and run.stayed_in_tube
    assert record.switches >= 3 and record.refused == 0
    t, x = run.trajectory.t, run.trajectory.x
    crossing = t <= 2.0                      # the person is in the corridor (y < 1.5 m)
    assert x[crossing, 0].max() < 0.5 - 0.15 - 0.11     # the ball waited short of them
    target = design.spec.target_set
    inside = np.all((x >= target.lower) & (x <= target.upper), axis=1)
    assert run.reached and t[np.argmax(inside)] <= design.spec.prescribed_time
    for name in ("x", "u", "alpha", "tube"):
        assert np.array_equal(getattr(runs[0].trajectory, name),
                              getattr(run.trajectory, name)), name


@pytest.mark.slow
def test_a_base_on_mujoco_waits_for_a_person_crossing_the_office():
    """The office's differential-drive base on MuJoCo (tests/specs/office-drive.xml, its
    wheels' velocity actuators), within [actuator] [1.2 m/s, 12 rad/s], with a person
    (0.25 m, 0.4 m/s) walking north through the gap between the desks at x = 4.25 m: the
    base replans around them, every tube proved from where the last one's proof leaves the
    state, certified throughout, in its tubes, no contact, at the target by t_c."""
    spec = Path(__file__).parent / "specs" / "office-drive-mujoco-sensed.toml"
    design = stt.design_tube(stt.load_spec(spec))
    person = WalkingObstacle((4.25, 0.3), 0.25, velocity=(0.0, 0.4))
    run = stt.simulate_sensed(design, [person])
    record = run.sensing
    assert record.guaranteed and record.uncertified == [] and not record.outside_envelope
    assert not record.sensed_collision and not run.collision and run.stayed_in_tube
    assert record.switches >= 3 and record.refused == 0 and record.failures == 0
    assert run.satisfied and run.reach_time <= design.spec.prescribed_time
