"""Obstacles sensed on three dimensions (docs/sensing.md, "In three dimensions"): a drone
under velocity control (tests/specs/drone-sensed.toml, ``[robot] dims = [0, 1, 2]``) and
rows of balls across its room that it only sees within 5 m. The reachable sets, the
certificates, the paths' levels and the escapes are 3-D; each run is judged here from its
own positions in 3-D; the plot and the log draw balls."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.sensed import ESCAPE_DIRECTIONS, escape_directions
from stt_codegen.design.sensed_path import LEVEL_STEP, levels
from stt_codegen.system import MissingTool
from stt_codegen.runtime.sensed import WalkingObstacle
from stt_codegen.runtime.walking_file import load_walking_obstacles

matplotlib.use("Agg")

SPEC = Path(__file__).parent / "specs" / "drone-sensed.toml"
#: Lamps hanging across the room, their centres 3 m up: the drone flies under them (a
#: file of ``--sensed``, the one of docs/sensing.md's command).
LAMPS_FILE = Path(__file__).parent / "specs" / "sensed" / "drone-lamps.toml"


def row(height: float, first: float, count: int) -> tuple[WalkingObstacle, ...]:
    """Standing balls of radius 0.4 every 0.8 m along the room's other diagonal
    (``x + y = 10``), their centres at ``height``: a row across every way in plan."""
    return tuple(WalkingObstacle((first + 0.8 * k, 10.0 - first - 0.8 * k, height), 0.4)
                 for k in range(count))


LAMPS = load_walking_obstacles(LAMPS_FILE)
#: Balls across the room at the drone's own height, floor to ceiling left open.
BARRIER = row(1.2, 0.6, 12)


@pytest.fixture(scope="module")
def drone():
    return stt.design_tube(stt.load_spec(SPEC))


@pytest.fixture(scope="module")
def under(drone):
    return stt.simulate_sensed(drone, LAMPS, backend="casadi")


def clearances(run, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The body's gap to each ball at each sample, in space and in plan (x, y), measured
    from the run's own positions."""
    x, centres = run.trajectory.x, run.trajectory.sensed_positions
    reach = radius + np.asarray(run.trajectory.sensed_radii)[None]
    space = np.linalg.norm(x[:, None, :] - centres, axis=2) - reach
    plan = np.linalg.norm(x[:, None, :2] - centres[:, :, :2], axis=2) - reach
    return space, plan


def test_escape_directions_go_over_and_under_on_a_third_dimension():
    """On two dimensions the 16 evenly spaced directions; on three, the same 16 flat, 8
    at 45 degrees up, 8 down, and straight up and down; on four, 0 on the fourth."""
    flat = escape_directions(2)
    assert flat.shape == (ESCAPE_DIRECTIONS, 2)
    angles = np.mod(np.arctan2(flat[:, 1], flat[:, 0]), 2 * math.pi)
    assert angles == pytest.approx(2 * math.pi * np.arange(ESCAPE_DIRECTIONS)
                                   / ESCAPE_DIRECTIONS, abs=1e-12)
    space = escape_directions(3)
    assert space.shape == (2 * ESCAPE_DIRECTIONS + 2, 3)
    assert np.linalg.norm(space, axis=1) == pytest.approx(1.0, abs=1e-12)
    assert np.array_equal(space[:ESCAPE_DIRECTIONS, :2], flat)
    heights = np.round(space[:, 2], 12)
    assert sorted(set(heights)) == [-1.0, -round(math.sqrt(0.5), 12), 0.0,
                                    round(math.sqrt(0.5), 12), 1.0]
    assert (heights > 0).sum() == (heights < 0).sum() == ESCAPE_DIRECTIONS // 2 + 1
    assert np.array_equal(escape_directions(4)[:, :3], space)
    assert not escape_directions(4)[:, 3].any()


def test_a_path_may_fly_at_the_start_height_or_every_level_step(drone):
    """The levels of a path's via boxes: the start's height, then one every
    ``LEVEL_STEP`` inside the room, the nearest first; none off the grid in 2-D."""
    spec = drone.spec
    found = levels(spec, (0, 1, 2))
    assert found[0] == pytest.approx([spec.initial_state[2]])
    heights = [float(v[0]) for v in found[1:]]
    assert np.diff(sorted(heights)) == pytest.approx(LEVEL_STEP)
    assert all(0.0 < h < 4.0 and abs(h - 1.0) >= LEVEL_STEP / 2 for h in heights)
    assert [abs(h - 1.0) for h in heights] == sorted(abs(h - 1.0) for h in heights)
    assert [v.size for v in levels(spec, (0, 1))] == [0]


def test_a_drone_flies_under_a_row_of_lamps_certified_throughout(drone, under):
    """The lamps block every way in plan. The drone passes under one of them (its disc
    meets the lamp's in plan view, and they are apart in space), certified at every
    instant, in its tubes, and reaches the target by t_c; the clearance measured here is
    the record's. A planner that took the balls for columns would never get past them."""
    run, record = under, under.sensing
    assert record.guaranteed and record.uncertified == [] and not record.outside_envelope
    assert record.failures == 0 and record.switches > 0
    assert not record.sensed_collision and not run.collision and run.stayed_in_tube
    assert run.satisfied and run.reach_time <= drone.spec.prescribed_time
    space, plan = clearances(run, drone.spec.robot.radius)
    assert space.min() > 0.0 and plan.min() < 0.0
    assert 0.0 < record.min_sensed_clearance <= space.min() + 1e-12


@pytest.mark.slow
def test_a_drone_climbs_over_a_row_at_its_height_and_the_generated_code_flies_it(drone):
    """The row at the drone's height blocks every way in plan at its level: the path
    climbs to a level above it in the start's cell, then flies over (the body's disc
    meets a ball's in plan, apart in space), and reaches the target by t_c with no
    contact. The spec's Python module and C with the tube as data, each switched tube
    loaded into them and each switch decided by their own switch test, fly the CasADi
    model's run bit for bit."""
    run = stt.simulate_sensed(drone, BARRIER, backend="casadi")
    record = run.sensing
    assert not record.sensed_collision and not run.collision and run.stayed_in_tube
    assert run.satisfied and not record.outside_envelope
    space, plan = clearances(run, drone.spec.robot.radius)
    assert space.min() > 0.0 and plan.min() < 0.0
    over = plan.min(axis=1) < 0.0                    # above a ball in plan view
    assert run.trajectory.x[over, 2].min() > 1.2 + 0.4 + drone.spec.robot.radius
    from stt_codegen.runtime.compiled import compiler
    for backend in ("python", "c"):
        if backend == "c":
            try:
                compiler()
            except MissingTool as exc:
                pytest.skip(f"no C compiler ({exc}): install gcc")
        flown = stt.simulate_sensed(drone, BARRIER, backend=backend)
        for name in ("x", "u", "alpha", "tube"):
            assert np.array_equal(getattr(flown.trajectory, name),
                                  getattr(run.trajectory, name)), (backend, name)
        assert [e.event for e in flown.sensing.events] == [e.event for e in record.events]


def test_the_lamps_file_is_the_row_and_the_command_flies_under_it(capsys):
    """``simulate SPEC --sensed FILE`` with 3-D balls: the file lists the row of lamps, and
    the command's run is the library's (satisfied, certified throughout)."""
    import json

    from stt_codegen.cli import main
    assert np.allclose([ob.start + (ob.radius,) for ob in LAMPS],
                       [ob.start + (ob.radius,) for ob in row(3.0, 1.0, 11)], atol=1e-12)
    assert all(ob.velocity is None and ob.path is None for ob in LAMPS)
    assert main(["simulate", str(SPEC), "--sensed", str(LAMPS_FILE), "--backend", "casadi",
                 "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert run["satisfied"] and run["sensing"]["uncertified"] == []
    assert run["sensed_obstacles"] == {"count": 11, "source": "file"}


@pytest.mark.parametrize("dims", [(0, 1), (0, 2), (1, 2)])
def test_the_plot_draws_each_ball_on_any_two_of_its_axes(drone, under, dims):
    """A projection on any two sensing axes draws each ball's section (it raised a
    ``ValueError`` on a 3-D centre)."""
    from matplotlib.patches import Circle

    from stt_codegen.runtime.plots import run_figure
    fig = run_figure(drone, under, dims)
    discs = [p for p in fig.axes[0].patches if isinstance(p, Circle)]
    every = int(round(2.0 * drone.spec.rate_hz))
    samples = len(range(0, len(under.trajectory.t), every))
    assert len(discs) >= len(LAMPS) * samples
    ball = under.trajectory.sensed_positions[every, 0]
    assert any(np.allclose(d.center, ball[list(dims)]) for d in discs)
    matplotlib.pyplot.close(fig)
