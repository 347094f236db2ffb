"""``[robot] radius``: the obstacles inflated and the state space shrunk by the robot's size,
so that the tube of the reference point keeps the whole robot clear (docs/spec-format.md)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from stt_codegen.cli import main
from stt_codegen.design.search import design_tube
from stt_codegen.errors import SpecError
from stt_codegen.runtime import plots
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import parse_spec
from stt_codegen.tube import reference

RADIUS = 0.2

#: A 2-D arena with a box and a ball obstacle, the start and the target off the walls.
ROBOT_SPEC = f"""
name = "robot-arena"
prescribed_time = 8.0
[state_space]
lower = [0.0, 0.0]
upper = [5.0, 5.0]
[initial]
lower = [0.2, 0.2]
upper = [0.8, 0.8]
[target]
lower = [4.0, 4.0]
upper = [4.8, 4.8]
[[obstacles]]
lower = [2.0, 2.0]
upper = [3.0, 3.0]
[[obstacles]]
center = [1.0, 3.5]
radius = 0.4
[robot]
radius = {RADIUS!r}
"""


@pytest.fixture(scope="module")
def design():
    return design_tube(parse_spec(ROBOT_SPEC))


def test_the_loader_shrinks_the_state_space_and_inflates_the_obstacles():
    spec = parse_spec(ROBOT_SPEC)
    assert spec.robot.radius == RADIUS and spec.robot.dims == (0, 1)
    assert spec.robot.state_space.lower == (0.0, 0.0)
    assert spec.state_space.lower == (RADIUS, RADIUS)
    assert spec.state_space.upper == (5.0 - RADIUS, 5.0 - RADIUS)
    real_box, real_ball = spec.robot.unsafe_sets
    box, ball = spec.unsafe_sets
    assert real_box.shape.lower == (2.0, 2.0)
    assert box.shape.lower == (2.0 - RADIUS, 2.0 - RADIUS)
    assert box.shape.upper == (3.0 + RADIUS, 3.0 + RADIUS)
    assert real_ball.shape.radius == 0.4 and ball.shape.radius == pytest.approx(0.4 + RADIUS)
    # the covering boxes of the ball cover the inflated ball: its points at radius 0.6
    angles = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    rim = np.c_[1.0 + 0.59 * np.cos(angles), 3.5 + 0.59 * np.sin(angles)]
    boxes = [o for o in spec.obstacles if o.source == 1]
    for p in rim:
        assert any(all(lo <= v <= hi for v, lo, hi in zip(p, o.lower, o.upper))
                   for o in boxes)
    # a zero radius changes nothing
    point = parse_spec(ROBOT_SPEC.replace(f"radius = {RADIUS!r}", "radius = 0.0"))
    plain = parse_spec(ROBOT_SPEC.split("[robot]")[0])
    assert point.state_space == plain.state_space and point.obstacles == plain.obstacles


def _box_gap(lo, hi, olo, ohi) -> float:
    """Euclidean distance between two boxes (0 when they meet)."""
    gaps = np.maximum(np.maximum(np.array(olo) - hi, lo - np.array(ohi)), 0.0)
    return float(np.sqrt(np.sum(gaps ** 2)))


def _ball_gap(lo, hi, center, radius) -> float:
    nearest = np.clip(center, lo, hi)
    return float(np.linalg.norm(nearest - center) - radius)


@pytest.mark.slow
def test_the_tube_clears_the_real_obstacles_by_the_radius(design):
    spec = design.spec
    names = [m.name for m in design.certificate.margins]
    assert design.certificate.passed
    for j in (0, 1):            # certified against the inflated sets
        m = design.certificate.margins[names.index(f"avoids obstacle {j}")]
        assert m.margin >= 0
    # the tube of a closed-loop run, sampled, against the real obstacles
    result = simulate(design, backend="reference")
    assert result.satisfied and not result.collision
    traj = result.trajectory
    g_l, g_u, _, _ = reference.adaptive_tube(design.tube, traj.t, traj.alpha)
    real_box, real_ball = spec.robot.unsafe_sets
    ball = real_ball.shape
    box_gaps = [_box_gap(lo, hi, real_box.shape.lower, real_box.shape.upper)
                for lo, hi in zip(g_l, g_u)]
    ball_gaps = [_ball_gap(lo, hi, np.array(ball.center), ball.radius)
                 for lo, hi in zip(g_l, g_u)]
    assert min(box_gaps) >= RADIUS - 1e-9
    assert min(ball_gaps) >= RADIUS - 1e-9
    # and the robot's body (the disc around x) inside the real state space
    assert np.all(traj.x[:, :2] >= RADIUS - 1e-9) and np.all(traj.x[:, :2] <= 5 - RADIUS + 1e-9)


@pytest.mark.parametrize("text, field, words", [
    ("radius = -0.1", "robot.radius", "non-negative"),
    ("radius = inf", "robot.radius", "finite"),
    ("radius = nan", "robot.radius", "finite"),
    ("radius = 2.6", "robot.radius", "the state space"),
    ("radius = 0.25", "initial", "initial set"),     # the start set at the wall: move it
    ("radius = 0.1\ndims = [2]", "robot.dims", "dimension index"),
    ("radius = 0.1\ndims = [0, 0]", "robot.dims", "repeats"),
    ("radius = 0.1\nsize = 3", "robot.size", "unknown key"),
])
def test_bad_robot_is_refused_naming_the_field(text, field, words):
    with pytest.raises(SpecError) as info:
        parse_spec(ROBOT_SPEC.replace(f"radius = {RADIUS!r}", text))
    assert info.value.field == field
    assert words in info.value.reason


def test_an_inflated_obstacle_that_meets_the_target_is_refused():
    near = ROBOT_SPEC.replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]",
                              "lower = [3.5, 4.0]\nupper = [3.9, 4.5]")
    parse_spec(near.split("[robot]")[0])             # fine for a point robot
    with pytest.raises(SpecError) as info:
        parse_spec(near)
    assert info.value.field == "target"            # the robot fits at its centre: move it
    assert "meets the target set" in info.value.reason
    assert "obstacles[0]" in info.value.reason


def test_an_inflated_moving_obstacle_that_meets_the_start_is_refused():
    moving = ROBOT_SPEC.replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]",
                                "lower = [0.9, 0.3]\nupper = [1.2, 0.6]\nactive = [0.0, 2.0]")
    assert parse_spec(moving.split("[robot]")[0]).moving_obstacles
    spec = None
    with pytest.raises(SpecError) as info:
        spec = parse_spec(moving)
    assert spec is None
    assert info.value.field == "robot.radius"
    assert "initial set" in info.value.reason and "obstacles[0]" in info.value.reason


def test_design_json_reports_the_robot(tmp_path, capsys):
    path = tmp_path / "robot.toml"
    path.write_text(ROBOT_SPEC)
    assert main(["design", str(path), "--json"]) == 0
    robot = json.loads(capsys.readouterr().out)["robot"]
    assert robot["radius"] == RADIUS and robot["dims"] == [0, 1]
    assert robot["state_space"] == {"lower": [0.0, 0.0], "upper": [5.0, 5.0]}
    assert robot["shrunk_state_space"] == {"lower": [RADIUS, RADIUS],
                                           "upper": [5 - RADIUS, 5 - RADIUS]}
    first = robot["inflated_obstacles"][0]
    assert first["obstacle"] == 0
    assert first["lower"] == [2.0 - RADIUS, 2.0 - RADIUS]
    assert first["upper"] == [3.0 + RADIUS, 3.0 + RADIUS]
    assert {o["obstacle"] for o in robot["inflated_obstacles"]} == {0, 1}


@pytest.mark.slow          # about 25 s; test_plots.py keeps the figures' fast tests
def test_plots_draw_the_real_obstacles_and_their_margins(design):
    from matplotlib.patches import Circle, Rectangle
    run = simulate(design, backend="reference")
    for figure in (plots.design_figure(design, (0, 1)), plots.run_figure(design, run)):
        ax = figure.axes[0]
        margins = [p for p in ax.patches if p.get_gid() == "robot margin"]
        real = [p for p in ax.patches if p.get_gid() in ("obstacle 0", "obstacle 1")]
        assert len(margins) == 2 and len(real) == 2
        box = next(p for p in real if isinstance(p, Rectangle))
        disc = next(p for p in real if isinstance(p, Circle))
        assert box.get_xy() == (2.0, 2.0) and box.get_width() == 1.0
        assert disc.get_radius() == 0.4
        grown = next(p for p in margins if isinstance(p, Rectangle))
        assert grown.get_xy() == (2.0 - RADIUS, 2.0 - RADIUS)
        assert next(p for p in margins if isinstance(p, Circle)).get_radius() == \
            pytest.approx(0.4 + RADIUS)
        assert ax.get_xlim()[0] < 0.0 < RADIUS      # the real state space is in view
        assert math.isclose(ax.get_xlim()[1], 5.1)


def test_moving_obstacles_are_drawn_as_given_and_inflated():
    moving = ROBOT_SPEC.replace("lower = [2.0, 2.0]\nupper = [3.0, 3.0]",
                                "lower = [2.0, 2.0]\nupper = [3.0, 3.0]\nactive = [5.0, 6.0]")
    spec = parse_spec(moving)
    assert spec.moving_obstacles[0].half_size == (0.5 + RADIUS, 0.5 + RADIUS)
    assert spec.robot.moving_obstacles[0].half_size == (0.5, 0.5)
    from matplotlib.figure import Figure
    ax = Figure().subplots()
    plots.draw_arena(ax, spec, (0, 1))
    given = [p for p in ax.patches if p.get_gid() == "moving obstacle 0 as given"]
    inflated = [p for p in ax.patches if p.get_gid() == "moving obstacle 0"]
    assert given and len(given) == len(inflated)
    assert given[0].get_width() == pytest.approx(1.0)
    assert inflated[0].get_width() == pytest.approx(1.0 + 2 * RADIUS)


def test_a_polytope_is_inflated_by_the_cube():
    triangle = ROBOT_SPEC.replace("center = [1.0, 3.5]\nradius = 0.4",
                                  "vertices = [[0.8, 3.2], [1.4, 3.2], [1.0, 3.8]]")
    spec = parse_spec(triangle)
    inflated = spec.unsafe_sets[1].shape
    real = spec.robot.unsafe_sets[1].shape
    # every point within the radius of the real triangle is in the inflated one
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    for v in np.array(real.vertices):
        ring = v + 0.999 * RADIUS * np.c_[np.cos(angles), np.sin(angles)]
        assert np.all(inflated.signed_clearance(ring) <= 0)
    assert inflated.lower == pytest.approx((0.8 - RADIUS, 3.2 - RADIUS))
    assert real.lower == (0.8, 3.2)
