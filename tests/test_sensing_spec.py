"""The sensing envelope ``[sensing]``, a sensed obstacle and the envelope's checks
(docs/sensing.md, docs/spec-format.md)."""

from __future__ import annotations

import copy
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.spec.schema import json_schema
from stt_codegen.spec.sensing import Sensing, envelope_violations

HALL = {"name": "hall", "prescribed_time": 10.0,
        "state_space": {"lower": [0.0, 0.0], "upper": [6.0, 4.0]},
        "initial": {"lower": [0.0, 1.6], "upper": [0.6, 2.4]},
        "target": {"lower": [5.4, 1.6], "upper": [6.0, 2.4]},
        "plant": {"model": "single-integrator"}}
SENSING = {"range": 3.0, "latency": 0.1, "period": 0.5, "max_obstacle_radius": 0.4,
           "max_obstacle_speed": 0.6}
ENVELOPE = Sensing(range=3.0, latency=0.1, period=0.5, max_obstacle_radius=0.4,
                   max_obstacle_speed=0.6, replan_time=0.5, horizon=1.0, dims=(0, 1))


def spec_with(sensing: dict | None = None, **tables) -> stt.Spec:
    doc = {**copy.deepcopy(HALL), **tables}
    if sensing is not None:
        doc["sensing"] = sensing
    return stt.Spec.from_dict(doc)


def test_a_spec_without_sensing_has_none():
    assert spec_with().sensing is None


def test_the_defaults_and_the_rate():
    s = spec_with(SENSING).sensing
    assert (s.range, s.latency, s.period) == (3.0, 0.1, 0.5)
    assert (s.replan_time, s.horizon, s.dims) == (0.5, 1.0, (0, 1))     # one, two periods
    assert s.shortest_horizon == 0.5 and ENVELOPE.shortest_horizon == 0.5   # one period
    assert spec_with(SENSING | {"shortest_horizon": 1.0}).sensing.shortest_horizon == 1.0
    rate = {k: v for k, v in SENSING.items() if k != "period"} | {"update_rate_hz": 4.0}
    t = spec_with(rate).sensing
    assert t.period == 0.25 and t.update_rate_hz == 4.0 and t.horizon == 0.5


def test_the_acceleration_bound_and_the_velocity_error():
    assert (ENVELOPE.max_obstacle_acceleration, ENVELOPE.velocity_error) == (None, 0.0)
    s = spec_with(SENSING | {"max_obstacle_acceleration": 1.5}).sensing
    assert (s.max_obstacle_acceleration, s.velocity_error) == (1.5, 0.0)
    s = spec_with(SENSING | {"max_obstacle_acceleration": 1.5, "velocity_error": 0.1}).sensing
    assert (s.max_obstacle_acceleration, s.velocity_error) == (1.5, 0.1)


def test_the_robot_dims_are_the_sensing_dims():
    s = spec_with(SENSING, state_space={"lower": [0.0, 0.0, 0.0], "upper": [6.0, 4.0, 3.0]},
                  initial={"lower": [0.1, 1.6, 1.0], "upper": [0.6, 2.4, 2.0]},
                  target={"lower": [5.4, 1.6, 1.0], "upper": [5.9, 2.4, 2.0]},
                  robot={"radius": 0.1, "dims": [0, 2]}).sensing
    assert s.dims == (0, 2)


@pytest.mark.parametrize("change, field, words", [
    ({"period": None}, "sensing.period", "give update_rate_hz or period"),
    ({"update_rate_hz": 2.0}, "sensing.period", "not both"),
    ({"horizon": 0.25}, "sensing.horizon", "shorter than one update period"),
    ({"shortest_horizon": 0.25}, "sensing.shortest_horizon",
     "= 0.25 s must lie between one update period (0.5 s) and the horizon (1 s)"),
    ({"shortest_horizon": 1.5}, "sensing.shortest_horizon", "must lie between"),
    ({"shortest_horizon": 0.0}, "sensing.shortest_horizon", "must be positive"),
    ({"range": 0.9}, "sensing.range", "horizon) = 0.96: an obstacle unseen"),
    ({"latency": -0.1}, "sensing.latency", "must be non-negative"),
    ({"range": 0.0}, "sensing.range", "must be positive"),
    ({"max_obstacle_speed": "fast"}, "sensing.max_obstacle_speed", "must be a number"),
    ({"rnage": 3.0}, "sensing.rnage", "did you mean 'range'"),
    ({"max_obstacle_radius": None}, "sensing.max_obstacle_radius", "missing"),
    ({"velocity_error": 0.1}, "sensing.velocity_error", "only with max_obstacle_acceleration"),
    ({"max_obstacle_acceleration": 1.0, "velocity_error": 1.3}, "sensing.velocity_error",
     "more than twice max_obstacle_speed"),
    ({"max_obstacle_acceleration": -1.0}, "sensing.max_obstacle_acceleration",
     "must be non-negative"),
])
def test_bad_sensing_names_the_field(change, field, words):
    table = {k: v for k, v in {**SENSING, **change}.items() if v is not None}
    with pytest.raises(stt.SpecError) as caught:
        spec_with(table)
    assert caught.value.field == field and words in caught.value.reason, caught.value


def test_the_range_must_leave_room_for_the_robot():
    with pytest.raises(stt.SpecError) as caught:
        spec_with({**SENSING, "range": 1.0}, robot={"radius": 0.1},
                  initial={"lower": [0.1, 1.6], "upper": [0.6, 2.4]},
                  target={"lower": [5.4, 1.6], "upper": [5.9, 2.4]})
    assert caught.value.field == "sensing.range"
    assert "+ the robot's radius 0.1 = 1.06" in caught.value.reason


def test_other_variants_are_refused_by_their_variant():
    with pytest.raises(stt.SpecError) as caught:
        spec_with(SENSING, plant={"model": "double-integrator"})
    assert caught.value.field == "sensing"
    assert "a second-order plant (the cascade variant" in caught.value.reason


def test_timed_tasks_are_refused_with_sensing_before_any_design():
    """A replanned tube heads for the target only: a spec with [[tasks]] and [sensing] is
    bad input at load, not a failure of its first replanning."""
    with pytest.raises(stt.SpecError) as caught:
        spec_with(SENSING, tasks=[{"kind": "reach", "lower": [2.0, 1.6],
                                   "upper": [2.6, 2.4], "window": [2.0, 6.0]}])
    assert caught.value.field == "sensing"
    assert "does not take [[tasks]]" in caught.value.reason


def test_a_differential_drive_base_replans():
    """The base's look-ahead point replans as law (13)'s robot does (its variant's
    ``replans_sensed``); the cascade does not."""
    spec = spec_with(SENSING, plant={"model": "differential-drive", "axle_offset": 0.1,
                                     "track_width": 0.2},
                     initial={"lower": [0.3, 1.6], "upper": [0.9, 2.4], "heading": 0.0},
                     target={"lower": [5.0, 1.6], "upper": [5.6, 2.4]})
    assert spec.sensing is not None and spec.sensing.dims == (0, 1)


def test_sensing_changes_neither_the_design_nor_the_hash(tmp_path):
    plain, sensed = spec_with(), spec_with(SENSING)
    a, b = stt.design_tube(plain), stt.design_tube(sensed)
    assert a.tube == b.tube and a.certificate.passed and b.certificate.passed


def test_the_command_line_names_the_field(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('name = "x"\nprescribed_time = 5.0\n[state_space]\nlower = [0.0, 0.0]\n'
                    'upper = [4.0, 4.0]\n[initial]\nlower = [0.0, 0.0]\nupper = [0.5, 0.5]\n'
                    '[target]\nlower = [3.5, 3.5]\nupper = [4.0, 4.0]\n[sensing]\nrange = 3.0\n'
                    'latency = 0.1\nperiod = 0.5\nmax_obstacle_radius = 0.4\n'
                    'max_obstacle_speed = 0.6\nhorizon = 0.1\n')
    run = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", str(path)],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert "sensing.horizon" in run.stderr


def test_the_json_schema_has_the_sensing_table():
    schema = json_schema()
    table = schema["$defs"]["SensingTable"]["properties"]
    assert {"range", "latency", "period", "update_rate_hz", "max_obstacle_radius",
            "max_obstacle_speed", "replan_time", "horizon", "shortest_horizon",
            "max_obstacle_acceleration",
            "velocity_error"} == set(table)
    assert "sensing" in schema["properties"]


# --------------------------------------------------------------------------- sensed obstacles

def test_a_sensed_ball_and_box():
    ball = stt.SensedObstacle.ball((2.0, 1.5), 0.3, seen_at=1.0, velocity=(0.0, 0.5), label=3)
    assert ball.half_size == (0.3, 0.3) and ball.extent == 0.3 and ball.label == 3
    assert ball.distance((2.0, 2.3)) == pytest.approx(0.5)
    lo, hi = ball.reach_box(2.0, 0.6)                # grown by 0.6 m over the second
    assert list(lo) == pytest.approx([1.1, 0.6]) and list(hi) == pytest.approx([2.9, 2.4])
    box = stt.SensedObstacle.box((1.0, 1.0), (1.6, 1.8))
    assert box.centre == pytest.approx((1.3, 1.4)) and box.extent == pytest.approx(0.5)
    assert box.distance((1.3, 1.4)) == 0.0 and box.distance((2.0, 1.4)) == pytest.approx(0.4)


@pytest.mark.parametrize("make, field", [
    (lambda: stt.SensedObstacle.ball((1.0, float("nan")), 0.3), "SensedObstacle.centre"),
    (lambda: stt.SensedObstacle.ball((1.0, 1.0), 0.0), "SensedObstacle.radius"),
    (lambda: stt.SensedObstacle.ball((1.0, 1.0), 0.2, velocity=(1.0,)),
     "SensedObstacle.velocity"),
    (lambda: stt.SensedObstacle.ball((1.0, 1.0), 0.2, seen_at=float("inf")),
     "SensedObstacle.seen_at"),
    (lambda: stt.SensedObstacle.ball((1.0, 1.0), 0.2, label=1.5), "SensedObstacle.label"),
    (lambda: stt.SensedObstacle.box((1.0, 1.0), (1.0, 2.0)), "SensedObstacle.upper"),
    (lambda: stt.SensedObstacle.box((1.0, 1.0), (2.0,)), "SensedObstacle.upper"),
    (lambda: stt.SensedObstacle.box((1.0, "a"), (2.0, 2.0)), "SensedObstacle.lower"),
])
def test_a_bad_sensed_obstacle_names_the_field(make, field):
    with pytest.raises(stt.SpecError) as caught:
        make()
    assert caught.value.field == field


# --------------------------------------------------------------------------- envelope checks

def ball(x, y, r=0.3, t=1.5, label=None, velocity=None):
    return stt.SensedObstacle.ball((x, y), r, seen_at=t, label=label, velocity=velocity)


def kinds(now, position=(1.0, 2.0), earlier=None):
    return [v.kind for v in envelope_violations(ENVELOPE, now, position, earlier)]


def test_a_measurement_within_the_envelope_passes():
    before = [ball(3.0, 2.0, t=1.0, label=1), ball(2.0, 0.5, t=1.0)]
    now = [ball(3.0, 2.29, label=1), ball(2.2, 0.6), ball(3.95, 3.0, label=2)]
    assert kinds(now, earlier=(1.0, (0.9, 2.0), before)) == []


def test_each_hypothesis_is_checked():
    assert kinds([ball(3.0, 2.0, r=0.5)]) == ["size"]
    assert kinds([ball(3.0, 2.0, velocity=(0.5, 0.5))]) == ["speed"]
    before = [ball(3.0, 2.0, t=1.0, label=1)]
    assert kinds([ball(3.0, 2.31, label=1)], earlier=(1.0, (0.9, 2.0), before)) == \
        ["displacement"]
    # a new obstacle 2.2 m from where the robot was: within R - V dt = 2.7, so it was in
    # range at the previous measurement and not seen
    assert kinds([ball(3.4, 2.0, label=2)], earlier=(1.0, (0.9, 2.0), before)) == ["appeared"]
    # the same obstacle without a label: it may be the earlier one, which moved
    assert kinds([ball(3.2, 2.0)], earlier=(1.0, (0.9, 2.0), before)) == []


def test_the_acceleration_hypothesis_is_checked_on_tracked_obstacles():
    """With ``A = 1`` and ``E = 0.05``: a person walking on at 0.5 m/s passes; one who turned
    back within the half second (their estimate flipped, and they are 0.25 m from where
    the last estimate put them) breaks it, twice; without the bound the same pair passes."""
    bounded = dataclasses.replace(ENVELOPE, max_obstacle_acceleration=1.0,
                                  velocity_error=0.05)
    before = [ball(3.0, 2.0, t=1.0, label=1, velocity=(0.0, 0.5))]
    walking = [ball(3.0, 2.25, label=1, velocity=(0.0, 0.5))]
    turned = [ball(3.0, 2.0, label=1, velocity=(0.0, -0.5))]
    earlier = (1.0, (0.9, 2.0), before)
    assert [v.kind for v in envelope_violations(bounded, walking, (1.0, 2.0), earlier)] == []
    found = envelope_violations(bounded, turned, (1.0, 2.0), earlier)
    assert [v.kind for v in found] == ["acceleration", "acceleration"]
    assert "from where its estimate put it" in found[0].detail
    assert "velocity estimate changed by 1" in found[1].detail
    assert kinds(turned, earlier=earlier) == []
    # without an estimate nothing about the acceleration can be shown
    blind = [ball(3.0, 2.0, label=1)]
    assert envelope_violations(bounded, blind, (1.0, 2.0), earlier) == []


def test_the_drift_box_holds_every_motion_within_the_bounds():
    """Points of the ball that move within ``E`` of the estimate when seen and accelerate
    at ``A`` in (seeded) random directions stay in the drift box over the span; the box is
    smaller than the speed bound's."""
    rng = np.random.default_rng(7)
    accel, error, speed = 1.0, 0.1, 1.5
    ob = stt.SensedObstacle.ball((2.0, 1.0), 0.3, seen_at=1.0, velocity=(0.8, -0.4))
    lo, hi = ob.drift_box(1.2, 1.7, accel, error)
    v_lo, v_hi = ob.reach_box(1.7, speed)
    assert np.all(hi - lo < v_hi - v_lo)
    dt = 0.01
    for _ in range(200):
        v = np.array(ob.velocity) + error * _unit(rng) * rng.uniform()
        p = np.array(ob.centre) + 0.3 * _unit(rng) * rng.uniform()
        for k in range(70):                             # t = 1.0 .. 1.7
            t = 1.0 + k * dt
            if t >= 1.2 - 1e-12:
                assert np.all(p >= lo - 1e-12) and np.all(p <= hi + 1e-12), (t, p)
            a = accel * _unit(rng)
            p = p + v * dt + 0.5 * a * dt * dt
            v = v + a * dt
    assert stt.SensedObstacle.ball((0.0, 0.0), 0.3).drift_box(0.0, 1.0, accel) is None


def _unit(rng):
    d = rng.normal(size=2)
    return d / np.linalg.norm(d)
