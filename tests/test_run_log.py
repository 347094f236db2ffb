"""A run out: ``stt-codegen simulate --log run.mcap`` writes ROS 2 messages that the mcap
reader decodes into the documented topics and types, one message a sample."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.run_log import TOPICS, check_log_path, write_run_log
from stt_codegen.tube import reference

mcap_ros2 = pytest.importorskip(
    "mcap_ros2.decoder", reason="mcap-ros2-support is not installed: pip install '.[ros]'")


def _simulate(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", "simulate", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=600)


def _decoded(path) -> dict[str, list]:
    """``{topic: [(log_time, schema name, decoded message), ...]}`` read back with mcap's
    reader and mcap-ros2-support's decoder."""
    from mcap.reader import make_reader
    found: dict[str, list] = {}
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[mcap_ros2.DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            found.setdefault(channel.topic, []).append((message.log_time, schema.name,
                                                        decoded))
    return found


@pytest.mark.slow
def test_the_command_writes_one_message_a_sample_on_each_topic(tmp_path):
    out = _simulate("omnirobot-s1", "--backend", "c", "--horizon", "0.5", "--log", "run.mcap",
                    cwd=tmp_path)
    assert out.returncode == 1, out.stderr            # 0.5 s: the target not yet reached
    assert "run written to run.mcap" in out.stdout
    found = _decoded(tmp_path / "run.mcap")
    assert set(found) == set(TOPICS)
    samples = 501                                     # 0.5 s at 1 kHz, t = 0 included
    for topic, kind in TOPICS.items():
        assert {name for _, name, _ in found[topic]} == {kind}
        assert len(found[topic]) == (1 if topic == "/stt/path" else samples), topic
    stamps = [t for t, _, _ in found["/stt/state"]]
    assert stamps == [round(k * 1e6) for k in range(samples)]      # t_k in ns
    # the run itself, as the library gives it
    design = design_of("omnirobot-s1")
    result = stt.simulate(design, backend="c", horizon=0.5)
    x, u = result.trajectory.x, result.trajectory.u
    for k in (0, 250, 500):
        pose = found["/stt/state"][k][2].pose.position
        assert [pose.x, pose.y, pose.z] == x[k].tolist()
        assert list(found["/stt/command"][k][2].data) == u[k].tolist()
    path = found["/stt/path"][0][2]
    assert len(path.poses) == samples and path.poses[-1].pose.position.x == x[-1, 0]
    g_l, g_u, _, _ = reference.adaptive_tube(design.tube, result.trajectory.t,
                                             result.trajectory.alpha)
    markers = found["/stt/markers"][300][2].markers
    tube = next(m for m in markers if m.ns == "tube")
    centre = (g_l[300] + g_u[300]) / 2
    assert [tube.pose.position.x, tube.pose.position.y, tube.pose.position.z] == \
        pytest.approx(centre.tolist(), abs=1e-12)
    assert tube.scale.x == pytest.approx(g_u[300, 0] - g_l[300, 0], abs=1e-12)
    assert sum(m.ns == "obstacles" for m in markers) == len(design.spec.obstacle_boxes())
    assert all(m.header.frame_id == "map" for m in markers)


def test_a_plane_run_lies_at_z_0(tmp_path):
    design = design_of("office-base")             # a differential-drive base, 2 dimensions
    result = stt.simulate(design, backend="c", horizon=0.2)
    write_run_log(design, result, tmp_path / "base.mcap")
    found = _decoded(tmp_path / "base.mcap")
    assert len(found["/stt/state"]) == len(result.trajectory.t)
    assert {m[2].pose.position.z for m in found["/stt/state"]} == {0.0}
    tube = found["/stt/markers"][0][2].markers[0]
    assert tube.ns == "tube" and tube.scale.z > 0.0      # drawn as a thin box


def test_a_sensed_run_draws_the_active_tube_and_the_people_where_they_are(tmp_path):
    """With obstacles sensed at run time the tube changes: the log draws the one active at
    each sample (not the design's), and each person as an upright cylinder where they are
    then, across the state space's heading axis."""
    from stt_codegen.runtime.sensed import bundled_people
    design = design_of("hall-crossing")
    result = stt.simulate_sensed(design, bundled_people("hall-crossing"), horizon=8.0)
    trajectory = result.trajectory
    write_run_log(design, result, tmp_path / "hall.mcap")
    found = _decoded(tmp_path / "hall.mcap")
    assert len(found["/stt/markers"]) == len(trajectory.t)
    switched = np.flatnonzero(trajectory.tube > 0)
    assert switched.size > 0                      # the run switched tubes before 8 s
    g_l, g_u, _, _ = reference.adaptive_tube(design.tube, trajectory.t, trajectory.alpha)
    k = int(switched[len(switched) // 2])
    assert not np.allclose(g_l[k], trajectory.gamma_L[k])       # the design's is elsewhere
    space = design.spec.state_space
    for k in (0, k, len(trajectory.t) - 1):
        markers = found["/stt/markers"][k][2].markers
        tube = next(m for m in markers if m.ns == "tube")
        centre = (trajectory.gamma_L[k] + trajectory.gamma_U[k]) / 2
        assert [tube.pose.position.x, tube.pose.position.y, tube.pose.position.z] == \
            pytest.approx(centre.tolist(), abs=1e-12)
        people = [m for m in markers if m.ns == "sensed"]
        assert [m.id for m in people] == [0, 1] and {m.type for m in people} == {3}
        for m in people:
            assert [m.pose.position.x, m.pose.position.y] == pytest.approx(
                trajectory.sensed_positions[k, m.id].tolist(), abs=1e-12)
            assert m.scale.x == pytest.approx(2 * trajectory.sensed_radii[m.id])
            assert m.scale.z == pytest.approx(space.upper[2] - space.lower[2])


def test_balls_sensed_on_three_axes_are_drawn_as_spheres(tmp_path):
    """A drone's sensed balls (tests/specs/drone-sensed.toml, sensed on x, y and z): each
    a sphere of its diameter at its centre, not a column across the room."""
    from pathlib import Path

    from stt_codegen.runtime.sensed import WalkingObstacle
    spec = Path(__file__).parent / "specs" / "drone-sensed.toml"
    design = stt.design_tube(stt.load_spec(spec))
    balls = [WalkingObstacle((5.0, 5.0, 3.0), 0.4, velocity=(0.0, 0.0, -0.2)),
             WalkingObstacle((3.0, 7.0, 1.0), 0.25)]
    result = stt.simulate_sensed(design, balls, horizon=1.0)
    write_run_log(design, result, tmp_path / "drone.mcap")
    found = _decoded(tmp_path / "drone.mcap")
    trajectory = result.trajectory
    for k in (0, len(trajectory.t) - 1):
        drawn = [m for m in found["/stt/markers"][k][2].markers if m.ns == "sensed"]
        assert [m.id for m in drawn] == [0, 1] and {m.type for m in drawn} == {2}
        for m in drawn:
            centre = trajectory.sensed_positions[k, m.id]
            assert [m.pose.position.x, m.pose.position.y, m.pose.position.z] == \
                pytest.approx(centre.tolist(), abs=1e-12)
            assert [m.scale.x, m.scale.y, m.scale.z] == \
                pytest.approx([2 * trajectory.sensed_radii[m.id]] * 3)


@pytest.mark.parametrize("path, message", [("run.bag", "must end in .mcap"),
                                           ("missing/run.mcap", "does not exist")])
def test_a_bad_log_path_is_refused_before_any_work(tmp_path, path, message):
    out = _simulate("omnirobot-s1", "--log", path, cwd=tmp_path)
    assert out.returncode == 2 and "error: --log: " in out.stderr and message in out.stderr
    assert "Traceback" not in out.stderr and list(tmp_path.iterdir()) == []


def test_without_the_package_the_message_names_it(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "mcap_ros2.writer", None)     # import fails
    with pytest.raises(SpecError, match=r"mcap-ros2-support is not installed.*\.\[ros\]"):
        check_log_path(tmp_path / "run.mcap")
