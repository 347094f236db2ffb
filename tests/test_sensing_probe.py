"""Independent probes of what is proved with obstacles sensed at run time (docs/sensing.md,
"What is proved"): in random worlds inside the envelope, at every sample some certificate
covered, the robot's body is clear of every obstacle, measured here from the run's own
positions (not from the record's verdict), and the robot is in the tube active then.

The worlds are drawn by Hypothesis (derandomized under CI): one to three people in
``hall-crossing`` (its envelope: radius at most 0.4 m, speed at most 0.8 m/s), each walking
straight at a random heading or heading for the robot, from anywhere in the hall; and one
to four balls in the drone's room (tests/specs/drone-sensed.toml, sensed on three
dimensions: radius at most 0.5 m, speed at most 1 m/s), each flying straight in a random
direction or heading for the drone, from anywhere in the room.
Uncertified spans are allowed (replanning may fail, and the run says so); a body that
meets an obstacle inside a certified span is a failure of the proof or of its code.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import design_of
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import stt_codegen as stt
from stt_codegen.runtime.sensed import WalkingObstacle

#: Simulated time of each world, s (the hall's t_c is 20 s; the people cross it in 10;
#: the drone's t_c is 14 s).
HORIZON = 10.0
#: The drone's room: obstacles sensed on three dimensions.
DRONE = str(Path(__file__).parent / "specs" / "drone-sensed.toml")


@st.composite
def people(draw) -> list[WalkingObstacle]:
    spec = design_of("hall-crossing").spec
    sensing = spec.sensing
    out = []
    for _ in range(draw(st.integers(1, 3))):
        start = (draw(st.floats(0.5, 9.5)), draw(st.floats(0.5, 5.5)))
        radius = draw(st.floats(0.1, sensing.max_obstacle_radius))
        speed = draw(st.floats(0.1, sensing.max_obstacle_speed))
        if draw(st.booleans()):
            heading = draw(st.floats(0.0, 2.0 * math.pi))
            out.append(WalkingObstacle(start, radius, velocity=(speed * math.cos(heading),
                                                                speed * math.sin(heading))))
        else:
            out.append(WalkingObstacle(start, radius, pursuit_speed=speed))
    return out


@st.composite
def balls(draw) -> list[WalkingObstacle]:
    spec = design_of(DRONE).spec
    sensing, space = spec.sensing, spec.state_space
    out = []
    for _ in range(draw(st.integers(1, 4))):
        start = tuple(draw(st.floats(lo, hi)) for lo, hi in zip(space.lower, space.upper))
        radius = draw(st.floats(0.1, sensing.max_obstacle_radius))
        speed = draw(st.floats(0.1, sensing.max_obstacle_speed))
        if draw(st.booleans()):
            azimuth = draw(st.floats(0.0, 2.0 * math.pi))
            rise = draw(st.floats(-1.0, 1.0))           # the sine of the elevation
            flat = math.sqrt(1.0 - rise * rise)
            out.append(WalkingObstacle(start, radius, velocity=(
                speed * flat * math.cos(azimuth), speed * flat * math.sin(azimuth),
                speed * rise)))
        else:
            out.append(WalkingObstacle(start, radius, pursuit_speed=speed))
    return out


def check_run(walkers: list[WalkingObstacle], world: str = "hall-crossing") -> None:
    design = design_of(world)
    spec = design.spec
    run = stt.simulate_sensed(design, walkers, horizon=HORIZON)
    record, trajectory = run.sensing, run.trajectory
    assert not record.script_outside_envelope and not record.outside_envelope, \
        record.violations                       # the worlds keep to the envelope
    assert run.stayed_in_tube                   # in the active tube at every sample
    covered = np.array([not any(a <= t <= b for a, b in record.uncertified)
                        for t in trajectory.t])
    dims = list(spec.sensing.dims)
    gaps = (np.linalg.norm(trajectory.x[:, None, dims] - trajectory.sensed_positions, axis=2)
            - trajectory.sensed_radii[None] - spec.robot.radius)
    worst = gaps.min(axis=1)
    assert np.all(worst[covered] > 0.0), (
        f"the body meets an obstacle at a certified sample: t = "
        f"{trajectory.t[covered][np.argmin(worst[covered])]:.2f} s, gap "
        f"{worst[covered].min():.4f} m")
    assert not record.collision_certified


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(people())
def test_no_certified_sample_meets_an_obstacle(walkers):
    check_run(walkers)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(people())
def test_no_certified_sample_meets_an_obstacle_in_more_worlds(walkers):
    check_run(walkers)


@pytest.mark.slow
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(balls())
def test_no_certified_sample_meets_a_ball_in_three_dimensions(flying):
    check_run(flying, DRONE)


@pytest.mark.slow
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(balls())
def test_no_certified_sample_meets_a_ball_in_more_rooms(flying):
    check_run(flying, DRONE)


def test_a_contact_counts_as_certified_wherever_a_certificate_covered_it():
    """Every instant of contact is judged, not only the first: a run whose first contact
    falls in an uncertified span and a later one in a certified span has a certified
    contact (the proof failed there)."""
    from stt_codegen.runtime.sensed import _certified_contact
    uncertified = [[0.5, 2.0]]
    assert not _certified_contact(np.array([1.0, 1.5]), uncertified)
    assert _certified_contact(np.array([1.0, 5.0]), uncertified)
    assert _certified_contact(np.array([0.2]), uncertified)
    assert not _certified_contact(np.array([]), uncertified)
