"""``stt-codegen bench sensed`` (docs/sensing.md): Real-Time STT's 2-D scenario, the
warehouse floor, Real-Time STT's script and a drone's room in 3-D."""

from __future__ import annotations

import math

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen_bench.sensed_bench import (SCENARIO, format_sensed_report, moving_circles,
                                            run_sensed_bench, scenario_with)
from stt_codegen_bench.sensed_script import (CIRCLES, HEADING_JITTER, POSITION_JITTER,
                                             PURSUER_START, SCRIPT, script_circles)
from stt_codegen_bench.sensed_rooms import CLEAR_OF_START, ROOM, flying_balls
from stt_codegen_bench.sensed_warehouse import (AISLES, DEPTH, DOOR, RACK_END, RACKS, WAREHOUSE,
                                                WIDTH, aisle_people)


def test_the_circles_are_seeded_and_drawn_by_the_generator():
    a = moving_circles(np.random.default_rng([0, 5, 1]), 5, 17.0)
    assert a == moving_circles(np.random.default_rng([0, 5, 1]), 5, 17.0)
    assert a != moving_circles(np.random.default_rng([0, 5, 2]), 5, 17.0)
    for ob in moving_circles(np.random.default_rng(3), 40, 17.0):
        assert 0.1 <= ob.radius <= 0.4
        assert np.linalg.norm(np.subtract(ob.start, (1.0, 1.0))) >= 2.5 + ob.radius
        rows = np.array(ob.path)
        t = np.linspace(0.0, 17.0, 3401)
        centre = ob.scripted(t)
        # inside the arena, and no faster than the generator's largest speed sqrt(2)
        assert np.all(centre >= ob.radius - 1e-9) and np.all(centre <= 10 - ob.radius + 1e-9)
        speeds = np.linalg.norm(np.diff(rows[:, 1:], axis=0), axis=1) / np.diff(rows[:, 0])
        assert np.all(speeds <= math.sqrt(2.0) + 1e-9)
    assert stt.Spec.from_dict(SCENARIO).sensing.max_obstacle_speed == math.sqrt(2.0)


def test_turning_circles_keep_to_the_acceleration_bound():
    """With ``acceleration`` the circles turn back before the walls instead of bouncing: no
    faster than the generator's speed, their velocity changing by at most ``sqrt(2)``
    times the per-axis acceleration per second (inside the envelope's ``A`` of twice it),
    and they stay near the arena; the scenario's envelope then has ``A`` and ``E``."""
    for ob in moving_circles(np.random.default_rng(5), 30, 17.0, acceleration=1.0):
        rows = np.array(ob.path)
        step = np.diff(rows[:, 0])
        v = np.diff(rows[:, 1:], axis=0) / step[:, None]
        assert np.all(np.linalg.norm(v, axis=1) <= math.sqrt(2.0) + 1e-9)
        change = np.linalg.norm(np.diff(v, axis=0), axis=1) / step[1:]
        assert np.all(change <= math.sqrt(2.0) * 1.0 + 1e-6)
        assert np.all(rows[:, 1:] >= -0.5) and np.all(rows[:, 1:] <= 10.5)
    sensing = stt.Spec.from_dict(scenario_with(2.0)).sensing
    assert (sensing.max_obstacle_acceleration, sensing.velocity_error) == (2.0, 0.05)
    assert scenario_with(None) is SCENARIO


def test_the_script_circles_are_the_scripts_moved_and_turned_within_the_envelope():
    """Real-Time STT's five circles: each episode moves a start by at most
    ``POSITION_JITTER`` per axis and turns a heading by at most ``HEADING_JITTER``, keeping
    the script's radius and speed, within the envelope's ``r_max`` and ``V``; episodes
    differ; the target lies inside the script's disc and the pursuer starts at its
    centre."""
    a = script_circles(np.random.default_rng([0, 5, 1]))
    assert a == script_circles(np.random.default_rng([0, 5, 1]))
    assert a != script_circles(np.random.default_rng([0, 5, 2]))
    sensing = stt.Spec.from_dict(SCRIPT).sensing
    for e in range(50):
        for ob, (x, y, radius, vx, vy) in zip(script_circles(np.random.default_rng(e)),
                                               CIRCLES, strict=True):
            assert ob.radius == radius <= sensing.max_obstacle_radius
            assert np.all(np.abs(np.subtract(ob.start, (x, y))) <= POSITION_JITTER)
            assert math.isclose(math.hypot(*ob.velocity), math.hypot(vx, vy))
            assert math.hypot(*ob.velocity) <= sensing.max_obstacle_speed
            turn = math.atan2(vx * ob.velocity[1] - vy * ob.velocity[0],
                              vx * ob.velocity[0] + vy * ob.velocity[1])
            assert abs(turn) <= HEADING_JITTER + 1e-12
    corners = np.array([[SCRIPT["target"][k][0], SCRIPT["target"][j][1]]
                        for k in ("lower", "upper") for j in ("lower", "upper")])
    assert np.all(np.linalg.norm(corners - (7.0, 10.0), axis=1) <= 1.0)
    assert PURSUER_START == (7.0, 10.0)


def test_the_script_as_written_is_crossed_certified_throughout():
    """The script's own circles, unmoved and unturned: the robot reaches the target by t_c,
    certified throughout, with no collision and no measurement outside the envelope."""
    from stt_codegen.runtime.sensed import WalkingObstacle
    circles = [WalkingObstacle((x, y), radius, velocity=(vx, vy))
               for x, y, radius, vx, vy in CIRCLES]
    run = stt.simulate_sensed(stt.design_tube(stt.Spec.from_dict(SCRIPT)), circles)
    record = run.sensing
    assert not record.outside_envelope and record.switches >= 1
    assert record.guaranteed and record.uncertified == []
    assert not record.sensed_collision and not run.collision
    assert run.reached and run.reach_time <= SCRIPT["prescribed_time"]


def test_the_script_refuses_other_counts_by_its_flag(capsys):
    from stt_codegen.cli import main
    assert main(["bench", "sensed", "--script", "--obstacles", "5,20"]) == 2
    assert "--script:" in capsys.readouterr().err
    with pytest.raises(ValueError, match="script"):
        run_sensed_bench(1, 0, counts=(5,), script=True, acceleration=2.0)


def test_the_warehouse_people_are_seeded_within_the_envelope_and_clear_of_the_racks():
    """Each person walks one straight line in an aisle, door to door, at most at the
    envelope's speed, is no larger than its ``r_max``, never overlaps a rack, and is on the
    floor only while walking."""
    a = aisle_people(np.random.default_rng([0, 6, 1]), 6, 40.0)
    assert a == aisle_people(np.random.default_rng([0, 6, 1]), 6, 40.0)
    assert a != aisle_people(np.random.default_rng([0, 6, 2]), 6, 40.0)
    sensing = stt.Spec.from_dict(WAREHOUSE).sensing
    t = np.linspace(0.0, 45.0, 901)
    kinds = set()
    for person in aisle_people(np.random.default_rng(7), 60, 40.0):
        rows = np.array(person.path)
        assert person.radius <= sensing.max_obstacle_radius
        speed = np.linalg.norm(rows[1, 1:] - rows[0, 1:]) / (rows[1, 0] - rows[0, 0])
        assert speed <= sensing.max_obstacle_speed + 1e-12 and rows[0, 0] <= 24.0
        centre = person.scripted(t)
        on_floor = np.all((centre >= 0.0) & (centre <= (WIDTH, DEPTH)), axis=1)
        assert np.all((t[on_floor] > rows[0, 0]) & (t[on_floor] < rows[1, 0]))
        assert np.all(np.abs(centre - np.clip(centre, 0.0, (WIDTH, DEPTH))) <= DOOR + 1e-12)
        for lo, hi in RACKS:            # racks span y in [0, RACK_END]
            inside_x = (centre[:, 0] + person.radius > lo) & (centre[:, 0] - person.radius < hi)
            assert not np.any(inside_x & (centre[:, 1] - person.radius < RACK_END))
        kinds.add("aisle" if rows[0, 1] in AISLES else "cross")
    assert kinds == {"aisle", "cross"}


def test_the_warehouse_refuses_an_adversary_by_its_flag(capsys):
    from stt_codegen.cli import main
    assert main(["bench", "sensed", "--warehouse", "--acceleration", "2"]) == 2
    assert "--warehouse:" in capsys.readouterr().err


def test_the_balls_are_seeded_within_the_envelope_and_clear_of_the_start():
    """Each ball flies straight at under ``V``, is no larger than ``r_max``, and starts in
    the room at least 2.5 m from the start's centre; the same seed draws the same balls."""
    spec = stt.load_spec(ROOM)
    space, sensing = spec.state_space, spec.sensing

    def draw(*seed):
        return flying_balls(np.random.default_rng(seed), 8, space.lower, space.upper,
                            spec.initial_state, sensing.max_obstacle_radius)
    assert draw(0, 8, 1) == draw(0, 8, 1) and draw(0, 8, 1) != draw(0, 8, 2)
    for ball in draw(3):
        centre = np.array(ball.start)
        assert len(centre) == 3 == len(ball.velocity)
        assert np.all((centre >= space.lower) & (centre <= space.upper))
        assert np.linalg.norm(centre - spec.initial_state) >= CLEAR_OF_START
        assert 0.1 <= ball.radius <= sensing.max_obstacle_radius
        assert np.linalg.norm(ball.velocity) < sensing.max_obstacle_speed


def test_the_rooms_refuse_an_adversary_by_their_flag(capsys):
    from stt_codegen.cli import main
    assert main(["bench", "sensed", "--rooms", "--adversary"]) == 2
    assert "--rooms:" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("floor,count,options,title", [
    ("warehouse", 6, {"warehouse": True}, "the warehouse floor, people crossing its aisles"),
    ("rooms", 5, {"rooms": True}, "a drone's room in 3-D, balls flying through it"),
    ("script", 5, {"script": True, "adversary": True}, "Real-Time STT's script")])
def test_one_episode_of_each_floor_is_reported(floor, count, options, title):
    report = run_sensed_bench(1, 0, counts=(count,), **options)
    row = report["rows"][0]
    assert report["floor"] == floor and row["episodes"] == 1
    assert row["outside_envelope"] == 0 and row["collisions_certified"] == 0
    assert row["on_time"] + row["late"] + row["not_reached"] == 1
    assert title in format_sensed_report(report)


def _pursued_run(seed: int, episode: int):
    """An episode of Real-Time STT's script with its pursuer, as ``bench sensed --script
    --adversary`` runs it."""
    from stt_codegen.runtime.sensed import WalkingObstacle
    from stt_codegen_bench.sensed_script import PURSUER_RADIUS
    circles = script_circles(np.random.default_rng([seed, 5, episode]))
    circles.append(WalkingObstacle(PURSUER_START, PURSUER_RADIUS,
                                   pursuit_speed=SCRIPT["sensing"]["max_obstacle_speed"]))
    return stt.simulate_sensed(stt.design_tube(stt.Spec.from_dict(SCRIPT)), circles,
                               seed=episode)


@pytest.mark.slow
@pytest.mark.parametrize("seed,episode", [(0, 16), (1, 127), (1, 340), (1, 477), (0, 236)])
def test_a_robot_in_the_target_steps_away_from_a_pursuer_closing_on_it(seed, episode):
    """Real-Time STT's script with its pursuer (0.45 m/s, from the target's centre). In
    seed 0, episode 16 and seed 1, episode 127 the robot reached the target, stepped
    aside along a path planned against the pursuer's straight walk, kept it while the
    pursuer turned after it, and was reached when no tube was certified any more; in seed
    1, episodes 340 and 477 it was pinned against the north wall, its escapes ranked by
    the ball the pursuer may reach; in seed 0, episode 236 (escapes ranked by the pursuit
    alone) it came back to the target along the east wall past the pursuer. Taking a slow
    obstacle closing on a robot that has been in the target to pursue it, in its escapes
    too, the robot keeps away: certified throughout, no collision."""
    run = _pursued_run(seed, episode)
    record = run.sensing
    assert not record.outside_envelope and record.escapes >= 1
    assert not record.sensed_collision and not run.collision
    assert record.guaranteed and record.uncertified == [] and run.reached


@pytest.mark.slow
@pytest.mark.parametrize("seed,episode", [(0, 181), (0, 343), (1, 461), (0, 401)])
def test_with_no_certified_plan_the_robot_runs_from_the_pursuer_all_the_same(seed, episode):
    """Real-Time STT's script with its pursuer. In these episodes no plan was certified for
    a while (seed 0, episode 181: cornered in the target's north-east corner; 343: beside a
    circle leaving through the north wall, whose reachable set covered the robot; seed 1,
    episode 461: on its way, the pursuer's reachable box over the robot's), the robot held
    its last tube, and the pursuer reached it. Each failure now carries a best-effort
    escape (``ReplanFailure.fallback``), which the robot runs: no collision. In seed 0,
    episode 401 the escape went past the pursuer, whose estimate pointed at where the
    robot was and not where it would be at the switch (not closing, ranked as a straight
    walk): closing on either, no collision. The spans it runs uncertified are reported as
    such."""
    run = _pursued_run(seed, episode)
    record = run.sensing
    assert not record.outside_envelope and record.best_effort >= 1
    assert not record.sensed_collision and not run.collision and run.reached
    switched = [ev for ev in record.events if "best-effort" in ev.detail]
    assert len(switched) == record.best_effort
    # a best-effort escape runs where no certificate covers the run
    assert all(any(a <= ev.time <= b for a, b in record.uncertified) for ev in switched)


@pytest.mark.parametrize("gap, meets", [(1.35, True), (1.40, False)])
def test_a_pursuer_heading_at_the_robot_within_1_35_m_leaves_no_tube_to_certify(gap, meets):
    """docs/sensing.md, "Not done yet" (a pursuer): under the circles' envelope with its
    acceleration bound, the reachable box of a pursuer (radius 0.3 m, at ``V``) seen
    heading straight at the robot meets the robot's start box (the spec's half width
    0.2 m around it) over the first 0.25 s after the switch once it is within 1.35 m, so
    no tube from there is certified; at 1.4 m it does not."""
    from stt_codegen.design.sensed import reachable_boxes, switch_time
    spec = stt.Spec.from_dict(scenario_with(2.0))
    sensing = spec.sensing
    speed = sensing.max_obstacle_speed
    robot = np.array([5.0, 5.0])
    half = np.array(spec.initial_half_width)
    pursuer = stt.SensedObstacle.ball((5.0 + gap, 5.0), 0.3, seen_at=0.0,
                                      velocity=(-speed, 0.0))
    t_s = switch_time(sensing, 0.0, spec.rate_hz)
    boxes = reachable_boxes([pursuer], speed, spec.robot.radius, sensing.dims, t_s, 0.0,
                            sensing.horizon, 0,
                            acceleration=sensing.max_obstacle_acceleration,
                            velocity_error=sensing.velocity_error)
    first = [b for b in boxes if b.active[0] == 0.0]
    assert len(first) == 1 and first[0].active[1] == pytest.approx(0.25)
    assert bool(first[0].meeting_times(robot - half, robot + half, 0.0, 0.0)) is meets


def test_the_report_columns_line_up():
    """Each value of a row ends where its column's title ends (the table is read by eye
    and copied into docs/performance.md)."""
    import re
    row = {"obstacles": 5, "episodes": 500, "collisions": 1, "collisions_certified": 0,
           "on_time": 495, "late": 2, "uncertified_runs": 41, "outside_envelope": 3,
           "switches": 6253, "escapes": 1597, "best_effort": 58, "shortened": 67,
           "failures": 59, "replan_cpu_p95_s": 0.174, "replan_cpu_max_s": 0.965}
    lines = format_sensed_report({"seed": 0, "adversary": True, "rows": [row]}).splitlines()
    head, values = lines[1], lines[2]
    titles = ["N", "episodes", "collisions", "(certified)", "on time", "late", "uncert.",
              "outside", "switches", "escapes", "best", "short", "failed",
              "replan p95 [s]", "max [s]"]
    ends, at = [], 0
    for title in titles:
        at = head.index(title, at) + len(title)
        ends.append(at)
    assert ends[-1] == len(head)
    assert [m.end() for m in re.finditer(r"\S+", values)] == ends
    assert values.split()[9:13] == ["1597", "58", "67", "59"]


def test_each_rate_is_reported_with_its_exact_interval():
    """The report gives each rate's 95 % interval, so that two runs of the bench are
    compared by more than their counts. With no event in ``n`` episodes the exact
    interval's upper end is ``1 - 0.025^(1/n)`` (closed form); with every episode, the
    lower end is ``0.025^(1/n)``."""
    row = {"obstacles": 5, "episodes": 1000, "collisions": 0, "collisions_certified": 0,
           "on_time": 1000, "late": 0, "uncertified_runs": 12, "outside_envelope": 0,
           "switches": 1, "failures": 0, "replan_cpu_p95_s": 0.1, "replan_cpu_max_s": 0.1}
    text = format_sensed_report({"seed": 0, "adversary": False, "rows": [row]})
    line = next(x for x in text.splitlines() if x.startswith("N = 5, 95 % intervals"))
    upper = 100.0 * (1.0 - 0.025 ** (1.0 / 1000))
    lower = 100.0 * 0.025 ** (1.0 / 1000)
    assert f"collisions 0.0-{upper:.1f} %" in line
    assert f"on time {lower:.1f}-100.0 %" in line
    low, high = (float(v) for v in line.split("uncertified ")[1].rstrip(" %").split("-"))
    assert 0.5 < low < 1.2 < high < 2.5


@pytest.mark.slow
def test_one_episode_is_reported():
    report = run_sensed_bench(1, 0, counts=(5,))
    row = report["rows"][0]
    assert row["episodes"] == 1 and row["outside_envelope"] == 0
    assert row["collisions_certified"] == 0
    assert row["on_time"] + row["late"] + row["not_reached"] == 1
    assert len(row["collided_episodes"]) == row["collisions"]
    assert len(row["uncertified_episodes"]) == row["uncertified_runs"]
    assert "bench sensed: seed 0" in format_sensed_report(report)
    row = {**row, "episodes": 18, "collisions": 2, "collided_episodes": [3, 17]}
    assert "N = 5: collisions in episodes 3, 17" in format_sensed_report(
        {**report, "rows": [row]})


@pytest.mark.slow
@pytest.mark.parametrize("episode", [249, 256])
def test_a_robot_cornered_by_two_circles_escapes_the_way_they_are_not_headed(episode):
    """Seed 0's episodes 249 (the start's wall) and 256 (the target's corner) of
    ``bench sensed --acceleration 2``: two circles head into the corner where the robot
    is. Ranked by the reachable ball, the escapes went deeper into it and the circles
    reached the robot there after every replanning had failed; ranked by where the circles
    are headed, the robot escapes the other way, stays certified throughout, and reaches
    the target by t_c."""
    design = stt.design_tube(stt.Spec.from_dict(scenario_with(2.0)))
    circles = moving_circles(np.random.default_rng([0, 5, episode]), 5, 17.0, 1.0)
    run = stt.simulate_sensed(design, circles, seed=episode)
    record = run.sensing
    assert not record.outside_envelope and not record.script_outside_envelope
    assert record.escapes >= 1
    assert not record.sensed_collision and not run.collision
    assert record.guaranteed and record.uncertified == [] and run.reached


@pytest.mark.embedded
def test_the_controller_cost_on_the_cortex_m4f_is_reported():
    """``--cortex-m4f``: the scenario's controller with the tube as data, counted on the
    emulated Cortex-M4F: a step with 16 windows open costs more than one on the scenario's
    tube, and the report prints both."""
    from stt_codegen_bench.sensed_bench import target_costs
    costs = target_costs()
    assert costs["self_test"] == "567/567"
    assert costs["step_16_windows"] > costs["step"] > 0
    assert costs["switch_16_windows"] > costs["switch"] > 0
    text = format_sensed_report({"seed": 0, "adversary": False, "rows": [],
                                 "cortex_m4f": costs})
    assert "instructions per step on the scenario's tube" in text
    missing = format_sensed_report({"seed": 0, "adversary": False, "rows": [],
                                    "cortex_m4f": {"missing": "install qemu-system-arm"}})
    assert "not measured (install qemu-system-arm)" in missing
