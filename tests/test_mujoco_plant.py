"""MuJoCo as the plant of the one closed loop (runtime/mujoco_plant.py): dynamics nobody in
the project wrote, stepped at the model's timestep with the input held between samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.simulate import run_closed_loop

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed: pip install . (a dependency; CI installs it)")

from stt_codegen.runtime.mujoco_plant import MujocoPlant  # noqa: E402  (after the skip)

HERE = Path(__file__).resolve().parent
VELOCITY = HERE / "models" / "umaze-ball-velocity.xml"
MOTOR = HERE / "models" / "umaze-ball-motor.xml"
JOINTS = ["ball_x", "ball_y"]


def test_the_first_order_law_drives_the_ball_through_its_velocity_servos() -> None:
    """The U-maze designed for a first-order plant (the ball's size in the spec), its
    generated C run on MuJoCo's ball with velocity servos: satisfied, no wall contact."""
    design = stt.design_tube(stt.load_spec(HERE / "specs" / "umaze-first-order.toml"))
    plant = MujocoPlant(VELOCITY, JOINTS, ["vel_x", "vel_y"])
    result = run_closed_loop(design.spec, design.tube, plant=plant, backend="c")
    assert result.satisfied and result.contacts == 0 and result.first_contact is None
    assert result.stayed_in_tube and result.min_obstacle_clearance > 0.1
    data = result.to_json()
    assert data["contacts"] == 0 and "max_abs_velocity" not in data


@pytest.mark.slow
def test_the_cascade_drives_pointmazes_force_motors_at_1_khz() -> None:
    """The U-maze's second-order spec at 1 kHz, certified for the declared class of
    PointMaze's ball (x2_dot = 23.9 u - 0.24 x2), on MuJoCo's ball with its motors
    (ctrlrange +-1): satisfied in both tubes, no contact, within the motors' range."""
    spec = stt.Spec.from_dict({**_toml(HERE / "specs" / "umaze-cascade.toml"),
                               "controller": {"rate_hz": 1000.0}})
    design = stt.design_tube(spec)
    plant = MujocoPlant(MOTOR, JOINTS, ["motor_x", "motor_y"], order=2)
    result = run_closed_loop(spec, design.tube, stage=design.second_stage[0], plant=plant,
                             backend="c")
    assert result.satisfied and result.contacts == 0, result.to_json()
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    assert max(result.max_abs_u) < 1.0
    # the velocities the loop saw are MuJoCo's qvel of the ball's joints
    assert result.trajectory.velocity.shape == result.trajectory.x.shape


class _Push:
    """Not a controller: a constant velocity command into the wall, to test the judge."""

    name = "push"

    def step(self, x, t, dt, alpha):
        return np.array([0.0, -0.5]), alpha, 0


def test_a_wall_contact_is_judged_like_a_collision() -> None:
    design = stt.design_tube(stt.load_spec(HERE / "specs" / "umaze-first-order.toml"))
    plant = MujocoPlant(VELOCITY, JOINTS, ["vel_x", "vel_y"])
    result = run_closed_loop(design.spec, design.tube, plant=plant, controller=_Push(),
                             backend="push", horizon=2.0)
    assert result.contacts > 0 and not result.satisfied
    t, geom1, geom2 = result.first_contact
    assert {geom1, geom2} == {"wall", "particle_geom"} and 0.0 < t < 2.0


def test_bad_mujoco_plants_name_the_field(tmp_path) -> None:
    for kwargs, field in (({"joints": ["ball_z", "ball_y"]}, "plant.joints"),
                          ({"actuators": ["vel_x", "thrust"]}, "plant.actuators"),
                          ({"order": 3}, "plant.order"),
                          ({"timestep": -1.0}, "plant.timestep"),
                          ({"mjcf": tmp_path / "none.xml"}, "plant.mjcf")):
        args = {"mjcf": VELOCITY, "joints": JOINTS, "actuators": ["vel_x", "vel_y"], **kwargs}
        with pytest.raises(SpecError) as info:
            MujocoPlant(**args)
        assert info.value.field == field
    plant = MujocoPlant(VELOCITY, JOINTS, ["vel_x", "vel_y"], timestep=0.0003)
    with pytest.raises(SpecError) as info:
        plant.steps_per_period(0.001)
    assert info.value.field == "controller.rate_hz"
    assert plant.steps_per_period(0.0009) == 3


def _toml(path: Path) -> dict:
    import tomllib
    return tomllib.loads(path.read_text())
