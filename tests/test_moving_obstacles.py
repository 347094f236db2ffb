"""Moving obstacles: the spec keys, the space-time certificate, the design,
the simulation, the generated C, in 2-D and 3-D (docs/moving-obstacles.md)."""

from __future__ import annotations

import copy
from dataclasses import replace
import math
import shutil
import subprocess
import tomllib

import numpy as np
import pytest
from codegen_helpers import COMPILERS, flags, write

import stt_codegen as stt
from stt_codegen.cases import bundled_spec_bytes
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.design import moving
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.moving import (MOTION_SPACE_TIME, MOTION_SWEPT, MOTION_TIMED_VIA,
                                       DURATION_FACTORS, TASK_HOLD_SHARE, static_part, retime,
                                       task_holds)
from stt_codegen.design.swept import swept_spec
from stt_codegen.design.search import check_tube
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.schema import json_schema
from stt_codegen.tube import reference
from stt_codegen.tube.parameters import CRUISE, ReachSegment

ARENA = {"name": "cross", "prescribed_time": 8.0,
         "state_space": {"lower": [0.0, 0.0], "upper": [5.0, 5.0]},
         "initial": {"lower": [0.0, 2.0], "upper": [0.5, 3.0]},
         "target": {"lower": [4.5, 2.0], "upper": [5.0, 3.0]},
         "plant": {"model": "single-integrator"}}


def with_obstacles(*obstacles: dict, base: dict = ARENA) -> dict:
    return {**copy.deepcopy(base), "obstacles": list(obstacles)}


# --------------------------------------------------------------------------- spec

def test_a_spec_without_motion_has_no_moving_obstacles():
    spec = stt.Spec.from_dict(with_obstacles({"lower": [2.0, 0.0], "upper": [2.5, 0.5]}))
    assert spec.moving_obstacles == () and len(spec.obstacles) == 1
    assert spec.unsafe_sets[0].source == 0


def test_moving_obstacles_keep_their_spec_index():
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [2.0, 4.0], "upper": [2.5, 4.5], "velocity": [0.0, -1.0], "active": [0.0, 3.0]},
        {"center": [3.5, 0.6], "radius": 0.3}))
    assert [o.source for o in spec.moving_obstacles] == [0]
    assert {o.source for o in spec.obstacles} == {1}
    assert [u.source for u in spec.unsafe_sets] == [1]


@pytest.mark.parametrize("extra, field, reason", [
    ({"velocity": [0.0, 0.0]}, "obstacles[0].velocity", "never leaves the state space"),
    ({"active": [3.0, 1.0]}, "obstacles[0].active", "must be less than"),
    ({"active": [1.0]}, "obstacles[0].active", "array [t_on, t_off]"),
    ({"active": [-1.0, 1.0]}, "obstacles[0].active[0]", "non-negative"),
    ({"velocity": [1.0], "active": [0.0, 1.0]}, "obstacles[0].velocity", "2 entries"),
    ({"velocity": [1.0, 0.0], "path": [[0.0, 2.25, 4.25]], "active": [0.0, 1.0]},
     "obstacles[0].path", "not both"),
    ({"path": [[0.0, 2.25]]}, "obstacles[0].path", "row 0 must have 3 entries"),
    ({"path": [[0.0, 2.25, 4.25], [0.0, 3.0, 4.0]]}, "obstacles[0].path", "times must increase"),
    ({"path": [[0.0, 2.0, 4.0]]}, "obstacles[0].path", "is not the centre"),
    ({"path": 3.0}, "obstacles[0].path", "must be an array"),
])
def test_bad_motion_is_a_spec_error(extra, field, reason):
    doc = with_obstacles({"lower": [2.0, 4.0], "upper": [2.5, 4.5], **extra})
    with pytest.raises(stt.SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == field and reason in err.value.reason, str(err.value)


@pytest.mark.parametrize("velocity, t_off, end", [
    ([0.0, 1.0], 1.0, (2.25, 5.25)),       # up: its lower face 4.0 reaches the top 5.0
    ([0.0, -1.0], 4.5, (2.25, -0.25)),     # down: its upper face 4.5 reaches the floor 0.0
    ([1.0, -1.0], 3.0, (5.25, 1.25)),      # right first: 2.0 reaches 5.0 before 4.5 meets 0
])
def test_a_moving_box_without_active_moves_until_it_has_left_the_state_space(velocity, t_off,
                                                                             end):
    """A person crossing a corridor: no ``active``, the box is there from 0 until it is out."""
    spec = stt.Spec.from_dict(with_obstacles({"lower": [2.0, 4.0], "upper": [2.5, 4.5],
                                              "velocity": velocity}))
    (moving,) = spec.moving_obstacles
    assert moving.active == (0.0, t_off)
    assert moving.centres[-1] == pytest.approx(end)
    assert moving.times == (0.0, t_off)


@pytest.mark.slow          # about 20 s: a design and a closed loop; the other tests design fast
def test_a_box_crossing_without_active_is_designed_certified_and_avoided():
    spec = stt.Spec.from_dict(with_obstacles({"lower": [2.0, 4.0], "upper": [3.0, 5.0],
                                              "velocity": [0.0, -1.0]}))
    assert spec.moving_obstacles[0].active == (0.0, 5.0)
    design = stt.design_tube(spec)
    margin = design.certificate.margin("avoids moving obstacle 0")
    assert margin.passed and margin.margin > 0
    result = stt.simulate(design, backend="reference")
    assert result.satisfied and not result.collision


def test_balls_and_polytopes_cannot_move():
    with pytest.raises(stt.SpecError) as err:
        stt.Spec.from_dict(with_obstacles({"center": [2.0, 4.0], "radius": 0.3,
                                           "velocity": [1.0, 0.0]}))
    assert err.value.field == "obstacles[0].velocity"
    assert "box obstacles only" in err.value.reason


def test_a_moving_box_at_the_start_at_time_zero_is_refused():
    with pytest.raises(stt.SpecError, match="meets the initial set at t = 0"):
        stt.Spec.from_dict(with_obstacles({"lower": [0.2, 2.2], "upper": [0.4, 2.4],
                                           "velocity": [1.0, 0.0], "active": [0.0, 2.0]}))
    # the same box switched on later is allowed (the design must avoid it)
    stt.Spec.from_dict(with_obstacles({"lower": [0.2, 2.2], "upper": [0.4, 2.4],
                                       "active": [3.0, 4.0]}))


def test_a_moving_box_in_the_target_after_t_c_is_refused_before_it_is_not():
    # from y = 0 upwards at 0.5 m/s through the target's x: in it on [4, 6] s (before t_c = 8)
    early = {"lower": [4.6, 0.0], "upper": [4.9, 0.0 + 0.3], "velocity": [0.0, 0.5],
             "active": [0.0, 9.0]}
    stt.Spec.from_dict(with_obstacles(early))
    late = {**early, "velocity": [0.0, 0.25]}          # in it on [6.8, 12] s: after t_c too
    with pytest.raises(stt.SpecError, match=r"meets the target set on \[8, 9\] s"):
        stt.Spec.from_dict(with_obstacles(late))


def test_json_schema_has_the_motion_keys():
    box = json_schema()["$defs"]["BoxObstacle"]["properties"]
    assert {"active", "velocity", "path"} <= set(box)
    assert "velocity" not in json_schema()["$defs"]["BallObstacle"]["properties"]


def test_hull_and_meeting_times_are_exact():
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [1.0, 4.0], "upper": [1.5, 4.5], "path": [[1.0, 1.25, 4.25], [3.0, 3.25, 4.25],
                                                             [5.0, 3.25, 0.25]]}))
    (ob,) = spec.moving_obstacles
    lo, hi, present = ob.hull([0.0, 2.0, 0.0], [0.5, 4.0, math.inf])
    assert present.all()
    assert np.allclose(lo[0], [1.0, 4.0]) and np.allclose(hi[0], [1.5, 4.5])   # held
    assert np.allclose(lo[1], [2.0, 2.0]) and np.allclose(hi[1], [3.5, 4.5])   # knot at 3 s
    assert np.allclose(lo[2], [1.0, 0.0]) and np.allclose(hi[2], [3.5, 4.5])   # everything
    # the box's x range is [t, t + 0.5] on [1, 3] s at y in [4, 4.5]: it meets the box
    # [2.5, 2.6] x [4.4, 5] on [2.0, 2.6] s
    (times,) = ob.meeting_times((2.5, 4.4), (2.6, 5.0), 0.0, math.inf)
    assert times == pytest.approx((2.0, 2.6))
    # then down at 2 m/s from y = 4 at 3 s, held from 5 s at [3, 3.5] x [0, 0.5]: it meets
    # [3.4, 4] x [0.4, 0.45] once its lower edge 4 - 2 (t - 3) is at 0.45: from 4.775 s on
    times = ob.meeting_times((3.4, 0.4), (4.0, 0.45), 0.0, math.inf)
    assert times[0] == pytest.approx((4.775, 5.0)) and times[1] == (5.0, math.inf)
    assert ob.meeting_times((3.4, 0.4), (4.0, 0.45), 0.0, 4.7) == []
    assert ob.meeting_times((0.0, 0.0), (0.5, 0.5), 0.0, math.inf) == []


# --------------------------------------------------------------------------- certificate

@pytest.fixture(scope="module")
def straight():
    """The tube for the empty arena (no obstacle), designed once."""
    return stt.design_tube(stt.Spec.from_dict(with_obstacles()))


def _centre(tube, t: float) -> np.ndarray:
    """A point inside the tube at ``t`` whatever ``alpha >= 0`` is: the centre of the tube
    for ``alpha = 0``, which every tube with ``alpha >= 0`` contains."""
    with reference.numpy_math():
        g_l, g_u, _, _ = reference.adaptive_tube(tube, [t], np.zeros(2 * tube.dimension))
    return 0.5 * (g_l[0] + g_u[0])


@pytest.mark.parametrize("kind", ["flash", "fast"])
def test_a_tube_meeting_a_moving_box_between_two_samples_is_rejected(straight, kind):
    """A box present only between two sampling instants (``flash``), or crossing the tube
    so fast that it is on one side at one instant and on the other at the next (``fast``),
    is met by the tube at no sampling instant; the certificate still rejects the tube."""
    tube = straight.tube
    dt = 1.0 / tube.rate_hz
    k = 3000                                   # t = 3 s, mid-way
    t_mid = (k + 0.5) * dt
    c = _centre(tube, t_mid)
    if kind == "flash":
        ob = {"lower": list(c - 0.01), "upper": list(c + 0.01),
              "active": [(k + 0.2) * dt, (k + 0.8) * dt]}
    else:   # 10 km/s along y: from 5 m below the centre at k dt to 5 m above at (k + 1) dt
        ob = {"lower": [c[0] - 0.01, c[1] - 5.01], "upper": [c[0] + 0.01, c[1] - 4.99],
              "velocity": [0.0, 10.0 / dt], "active": [k * dt, (k + 1) * dt]}
    spec = stt.Spec.from_dict(with_obstacles(ob))
    # at no sampling instant is the box present within 1 m of the tube's centre
    (moving,) = spec.moving_obstacles
    times = np.arange(int(round(8.0 / dt)) + 1) * dt
    near = moving.is_active(times) & (np.abs(moving.centre(times) - c).max(axis=1) < 1.0)
    assert not near.any()
    check = check_tube(tube, spec)
    assert not check.passed and check.kind is FailureKind.MOVING_OBSTACLE, check.reason
    margin = check.certificate.margin("avoids moving obstacle 0")
    assert not margin.passed and margin.time <= t_mid <= margin.time + 2 * dt
    # the same box 1.2 m further along x is proven clear: the rejection is not vacuous
    lifted = copy.deepcopy(ob)
    lifted["lower"][0] += 1.2
    lifted["upper"][0] += 1.2
    assert check_tube(tube, stt.Spec.from_dict(with_obstacles(lifted))).passed


def test_the_static_part_of_a_moving_spec_is_certified_as_before(straight):
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [2.0, 4.4], "upper": [2.6, 5.0], "active": [0.0, 0.5]}))
    check = check_tube(straight.tube, spec)
    plain = straight.certificate
    names = [m.name for m in check.certificate.margins]
    assert names == ["non-empty", "initial state inside", "inside state space",
                     "avoids moving obstacle 0", "inside target after t_c", "sampling rate"]
    for m in plain.margins:
        assert check.certificate.margin(m.name) == m


# --------------------------------------------------------------------------- design

def test_the_crossing_is_designed_by_re_timing_and_certified():
    spec = stt.load_spec("crossing-moving")
    # neither the static design nor the swept regions give a tube here
    static = stt.design_tube(static_part(spec))
    assert not check_tube(static.tube, spec).passed
    swept, _ = swept_spec(spec)
    with pytest.raises(stt.DesignError):
        stt.design_tube(swept)
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    doc = design.to_json()
    assert doc["motion"] == MOTION_TIMED_VIA
    assert [m["obstacle"] for m in doc["moving_obstacles"]] == [0, 1]
    assert all(m["margin"] > 0 for m in doc["moving_obstacles"])
    assert design.tube.segments[0].start > 0.0        # it waits before it crosses
    again = stt.design_tube(spec)
    assert again.tube == design.tube                 # deterministic


def test_an_obstacle_that_passes_before_the_tube_arrives_is_avoided_in_space_time(straight):
    # the box crosses the straight path at x = 4 m during [0, 1] s, long before the tube
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [3.8, 4.4], "upper": [4.2, 5.0], "velocity": [0.0, -4.4], "active": [0.0, 1.0]}))
    design = stt.design_tube(spec)
    assert design.motion == MOTION_SPACE_TIME
    assert design.tube == straight.tube


def test_a_box_present_late_is_avoided_as_swept_when_the_rest_fails():
    # a still box on the straight path, active from 1 s for ever: re-timing cannot pass
    # through it; as a static box the design goes around it
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [2.2, 1.8], "upper": [2.8, 3.2], "active": [1.0, 100.0]}))
    design = stt.design_tube(spec)
    assert design.motion == MOTION_SWEPT and design.certificate.passed


def test_a_moving_obstacle_that_cannot_be_avoided_is_a_design_error():
    # a wall across the arena, switched on at 1 s: the target is cut off in space-time
    spec = stt.Spec.from_dict(with_obstacles(
        {"lower": [2.2, 0.0], "upper": [2.8, 5.0], "active": [1.0, 100.0]}))
    with pytest.raises(stt.DesignError, match="moving obstacles") as err:
        stt.design_tube(spec)
    assert err.value.tried is not None


# --------------------------------------------------------------------------- simulation

@pytest.mark.slow
def test_simulation_counts_a_collision_where_the_obstacle_is(straight):
    """The straight tube run against a box that crosses its way while it is there: a
    collision; the same box switched off before the robot comes: none."""
    tube = straight.tube
    t = 4.0
    c = _centre(tube, t)
    box = {"lower": list(c - 0.3), "upper": list(c + 0.3)}
    hit = stt.Spec.from_dict(with_obstacles({**box, "active": [t - 0.5, t + 0.5]}))
    result = run_closed_loop(hit, tube, backend="python")
    assert result.collision and not result.satisfied and result.min_obstacle_clearance < 0
    gone = stt.Spec.from_dict(with_obstacles({**box, "active": [0.0, 0.2]}))
    result = run_closed_loop(gone, tube, backend="python")
    assert not result.collision and result.satisfied and result.min_obstacle_clearance > 0


@pytest.mark.slow
def test_the_crossing_is_satisfied_in_closed_loop():
    design = stt.design_tube(stt.load_spec("crossing-moving"))
    result = stt.simulate(design, backend="python")
    assert result.satisfied and not result.collision, result.to_json()
    assert result.min_obstacle_clearance > 0


@pytest.mark.slow
@pytest.mark.skipif(not COMPILERS, reason="no C compiler: install the Debian package gcc")
def test_the_crossing_is_satisfied_with_the_c_backend():
    design = stt.design_tube(stt.load_spec("crossing-moving"))
    result = stt.simulate(design, backend="c")
    assert result.satisfied and not result.collision, result.to_json()


@pytest.mark.skipif(not COMPILERS, reason="no C compiler: install the Debian package gcc")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_generated_c_of_a_moving_spec_passes_its_vectors(precision, tmp_path):
    design = stt.design_tube(stt.load_spec("crossing-moving"))
    spec = design.spec
    files = generate_files(spec, design.tube, Options(("c",), precision))
    folder = write(tmp_path / precision, files)
    build = subprocess.run([COMPILERS[0], *flags(precision), f"{spec.c_name}.c",
                            f"{spec.c_name}_selftest.c", "-o", "selftest", "-lm"],
                           cwd=folder, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run(["./selftest"], cwd=folder, capture_output=True, text=True)
    assert run.returncode == 0 and " 0 failed" in run.stdout, run.stdout[-2000:]


# --------------------------------------------------------------------------- 3-D

ARENA_3D = {"name": "cross3", "prescribed_time": 8.0,
            "state_space": {"lower": [0.0, 0.0, 0.0], "upper": [5.0, 5.0, 5.0]},
            "initial": {"lower": [0.0, 2.0, 2.0], "upper": [0.5, 3.0, 3.0]},
            "target": {"lower": [4.5, 2.0, 2.0], "upper": [5.0, 3.0, 3.0]},
            "plant": {"model": "single-integrator"}}


@pytest.mark.slow
def test_moving_obstacles_in_three_dimensions():
    """As in 2-D: a box crossing the straight path in z while the tube is there is rejected
    by the certificate, the design re-times around it, and the closed loop avoids it where
    it is."""
    crossing = {"lower": [2.2, 2.2, 4.4], "upper": [2.8, 2.8, 5.0], "velocity": [0.0, 0.0, -0.9],
                "active": [0.0, 6.0]}
    spec = stt.Spec.from_dict(with_obstacles(crossing, base=ARENA_3D))
    assert len(spec.moving_obstacles) == 1 and spec.moving_obstacles[0].dims == (0, 1, 2)
    static = stt.design_tube(static_part(spec))
    assert check_tube(static.tube, spec).kind is FailureKind.MOVING_OBSTACLE
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    result = stt.simulate(design, backend="python")
    assert result.satisfied and result.min_obstacle_clearance > 0, result.to_json()


@pytest.mark.embedded
@pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None
                    or shutil.which("qemu-system-arm") is None,
                    reason="needs the Debian packages gcc-arm-none-eabi, libnewlib-arm-none-eabi "
                           "and qemu-system-arm")
def test_the_crossing_on_the_cortex_m4f(tmp_path):
    """The single-precision controller of the crossing on QEMU mps2-an386: every vector
    passes, the closed loop on the target follows the host run, which meets no moving
    obstacle."""
    from stt_codegen.embedded.deploy import run_embedded
    design = stt.design_tube(stt.load_spec("crossing-moving"))
    report = run_embedded(design, tmp_path / "build")
    assert report["ok"] and report["vectors_failed"] == 0 and report["vectors_passed"] > 500
    assert report["closed_loop_satisfied"] and report["host_satisfied"]
    assert report["max_state_deviation"] < 1e-3


def test_routes_go_around_fewer_obstacles_first():
    from stt_codegen.design.moving import routes
    assert routes(0) == []
    assert routes(3) == [(), (0,), (1,), (2,), (0, 1), (0, 2), (1, 2)]
    assert len(routes(6)) == 16


@pytest.mark.slow
def test_going_around_one_moving_obstacle_and_timing_the_others():
    """Random arena 43 of seed 0 with its random moving obstacles (the moving-obstacle
    study): neither the static tube nor the swept regions give a tube; going around the
    swept region of some and timing the others does."""
    from stt_codegen_bench.arenas import arena_spec
    spec = arena_spec("moving", 0, 43)
    assert not check_tube(stt.design_tube(static_part(spec)).tube, spec).passed
    swept, _ = swept_spec(spec)
    with pytest.raises(stt.DesignError):
        stt.design_tube(swept)
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    result = stt.simulate(design, backend="python")
    assert result.satisfied and result.min_obstacle_clearance > 0


def test_the_paper_method_is_kept_with_moving_obstacles():
    """``tube.method = "paper"``: no re-timed via tube; the crossing then has no design (its
    swept regions wall the target off), and the message says so."""
    doc = tomllib.loads(bundled_spec_bytes("crossing-moving").decode())
    doc["tube"] = {"method": "paper"}
    with pytest.raises(stt.DesignError, match="no swept design|swept regions") as err:
        stt.design_tube(stt.Spec.from_dict(doc))
    assert "re-timed" not in str(err.value) and "re-timing" not in str(err.value)


def test_a_certified_moving_obstacle_is_missed_on_a_dense_grid(straight):
    """Soundness against sampling: 40 random moving boxes near the straight tube; for each
    one the certificate accepts, the tube (deployed ``alpha``, linear between instants, as
    the certificate models it) misses the box at every sampling instant and every midpoint.
    Both verdicts occur (the draw is not vacuous)."""
    from stt_codegen.design.samples import sample_tube
    tube = straight.tube
    s = sample_tube(tube, horizon=9.0)
    mid_t = 0.5 * (s.t[1:] + s.t[:-1])
    with reference.numpy_math():
        m_l, m_u, _, _ = reference.adaptive_tube(tube, mid_t, 0.5 * (s.alpha[1:] + s.alpha[:-1]))
    t = np.concatenate([s.t, mid_t])
    g_l = np.vstack([s.gamma_lower, m_l])
    g_u = np.vstack([s.gamma_upper, m_u])
    rng = np.random.default_rng(21)
    verdicts = []
    for _ in range(40):
        corner = rng.uniform([1.0, 0.0], [4.0, 4.6])
        side = float(rng.uniform(0.2, 0.5))
        t_on = float(rng.uniform(0.0, 6.0))
        ob = {"lower": list(corner), "upper": list(corner + side),
              "velocity": list(rng.uniform(-1.5, 1.5, size=2)),
              "active": [t_on, t_on + float(rng.uniform(0.5, 3.0))]}
        try:
            spec = stt.Spec.from_dict(with_obstacles(ob))
        except stt.SpecError:
            continue                     # meets the start at 0 or the target after t_c
        passed = check_tube(tube, spec).passed
        verdicts.append(passed)
        if passed:
            (moving,) = spec.moving_obstacles
            centre, half = moving.centre(t), np.array(moving.half_size)
            overlap = np.all((g_l < centre + half) & (g_u > centre - half), axis=1)
            assert not np.any(overlap & moving.is_active(t)), ob
    assert any(verdicts) and not all(verdicts)


@pytest.mark.slow
def test_tasks_and_moving_obstacles_together():
    """A spec with ``[[tasks]]`` and a moving obstacle: the tasks' plan is checked in
    space-time, so the design reports both (each task's box and margin, the obstacle's
    margin) and the run meets both; the same obstacle active longer, across the tasks'
    plan, is designed by the re-timing that keeps each waypoint's hold in its window
    (docs/moving-obstacles.md, "With [[tasks]]"); a box present over a task's whole box
    for its whole window is refused."""
    doc = tomllib.loads(bundled_spec_bytes("crossing-moving").decode())
    doc.update(name="crossing_tasks", tube={"method": "auto"})
    doc["obstacles"] = [{"lower": [1.7, 3.4], "upper": [2.3, 4.0], "velocity": [0.0, -0.6],
                         "active": [0.0, 1.5]}]
    doc["tasks"] = [{"kind": "reach", "window": [0.6, 1.2], "lower": [1.0, 1.7],
                     "upper": [1.6, 2.3]},
                    {"kind": "reach", "window": [5.0, 6.0], "lower": [3.0, 1.7],
                     "upper": [3.6, 2.3]}]
    design = stt.design_tube(stt.Spec.from_dict(doc))
    assert design.motion == MOTION_SPACE_TIME
    data = design.to_json()
    assert [t["task"] for t in data["tasks"]] == ["T1", "T2"]
    assert all(t["certified"] and t["margin"] > 0 for t in data["tasks"])
    assert data["moving_obstacles"][0]["margin"] > 0
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and all(t.met for t in run.tasks)
    doc["obstacles"][0]["active"] = [0.0, 8.0]      # now it crosses the tasks' plan
    spec = stt.Spec.from_dict(doc)
    planned = stt.design_tube(static_part(spec)).tube
    assert not check_tube(planned, spec).passed
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA
    # the re-timing keeps the segments (index k is the plan's segment k), moves their times
    assert len(design.tube.segments) == len(planned.segments)
    holds = task_holds(planned.segments, spec)
    assert [t.label for t in holds.values()] == ["T1", "T2"]
    for k, task in holds.items():                   # each hold serves its window
        seg = design.tube.segments[k]
        assert seg.lower_from == seg.lower_to == planned.segments[k].lower_from
        t0, t1 = task.window
        assert min(seg.end, t1) - max(seg.start, t0) >= TASK_HOLD_SHARE * (t1 - t0) - 1e-9
    data = design.to_json()
    assert all(t["certified"] and t["margin"] > 0 for t in data["tasks"])
    assert data["moving_obstacles"][0]["margin"] > 0
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and all(t.met for t in run.tasks)
    # a box over T2's whole box for all of T2's window: no tube can meet T2
    doc["obstacles"] = [{"lower": [2.9, 1.6], "upper": [3.7, 2.4], "active": [4.5, 6.5]}]
    with pytest.raises(stt.DesignError) as info:
        stt.design_tube(stt.Spec.from_dict(doc))
    assert info.value.kind is FailureKind.MOVING_OBSTACLE


def _lane(*obstacles: dict) -> tuple[dict, tuple[ReachSegment, ...]]:
    """A 6 m x 4 m floor in 10 s, and five 1 s legs along its middle from the start box to
    the target box (0.4 m boxes)."""
    doc = {**with_obstacles(*obstacles), "prescribed_time": 10.0,
           "state_space": {"lower": [0.0, 0.0], "upper": [6.0, 4.0]},
           "initial": {"lower": [0.1, 1.8], "upper": [0.5, 2.2]},
           "target": {"lower": [5.5, 1.8], "upper": [5.9, 2.2]}}
    xs = [0.3, 1.2, 2.1, 3.9, 4.8, 5.7]
    return doc, tuple(ReachSegment(float(k), float(k + 1), (a - 0.2, 1.8), (a + 0.2, 2.2),
                                   (b - 0.2, 1.8), (b + 0.2, 2.2), CRUISE)
                      for k, (a, b) in enumerate(zip(xs, xs[1:])))


def test_with_an_actuator_the_retiming_drives_no_leg_faster_than_waiting_needs():
    """Five 1 s legs along a lane that a box closes until t = 4 s: without [actuator] the
    earliest arrival drives the legs after the wait at twice their planned speed; with it,
    the timing of least speed-up waits and drives every leg at most at its planned speed,
    and still arrives by t_c."""
    doc, legs = _lane({"lower": [2.7, 1.0], "upper": [3.3, 3.0], "active": [0.0, 4.0]})
    free = retime(legs, stt.Spec.from_dict(doc))
    bounded = retime(legs, stt.Spec.from_dict({**doc, "actuator": {"input_bound": [2, 2]}}))

    def moves(timing):
        return [s for s in timing if s.lower_from != s.lower_to]

    assert len(moves(free)) == len(moves(bounded)) == len(legs)
    assert min(s.end - s.start for s in moves(free)) < 0.75      # earliest: faster legs
    assert all(s.end - s.start >= 1.0 - 1e-9 for s in moves(bounded))
    # both pass the box after it has gone and arrive by t_c, the bounded one later
    for timing in (free, bounded):
        crossing = next(s for s in timing if s.lower_from[0] < 2.7 < s.lower_to[0])
        assert crossing.end >= 4.0 and timing[-1].end <= 10.0
    assert bounded[-1].end > free[-1].end


def test_with_an_actuator_the_timing_levels_its_legs_where_they_keep_clear(monkeypatch):
    """The lane closed until t = 4 s: the grid's timing of least speed-up waits whole steps
    and then drives the long leg in one step (1.8 m/s); levelled, every leg shares the
    whole 10 s at one speed (0.54 m/s), each move still judged clear of the box, the
    crossing leg entering the box's place after it has gone, and the tube certified."""
    doc, legs = _lane({"lower": [2.7, 1.0], "upper": [3.3, 3.0], "active": [0.0, 4.0]})
    spec = stt.Spec.from_dict({**doc, "actuator": {"input_bound": [2, 2]}})
    levelled = retime(legs, spec)
    monkeypatch.setattr(moving, "LEVEL_WINDOWS", ())
    searched = retime(legs, spec)

    def speeds(timing):
        return [abs(s.lower_to[0] - s.lower_from[0]) / (s.end - s.start) for s in timing
                if s.lower_from != s.lower_to]

    assert max(speeds(searched)) == pytest.approx(1.8)
    assert max(speeds(levelled)) == pytest.approx(min(speeds(levelled))) == pytest.approx(
        5.4 / 10.0)
    assert levelled[0].start == 0.0 and levelled[-1].end == 10.0
    assert all(moving._moves_clear(levelled, spec))
    crossing = next(s for s in levelled if s.lower_from[0] < 2.7 < s.lower_to[0])
    at_four = reference.segments_progress((crossing,), np.array([[4.0]]))[0, 0]
    assert crossing.upper_from[0] + at_four * (crossing.upper_to[0] - crossing.upper_from[0]) \
        < 2.7                                           # short of the box's place at 4 s
    monkeypatch.undo()
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed


def test_the_retiming_arrives_later_where_the_target_is_taken_after_the_earliest_arrival():
    """A box stands on the target from 6 s to 8 s: the earliest arrival (before 6 s) would
    wait there while it stands, so the timing arrives after it has gone (the search kept
    no timing at all when its earliest arrival's wait was not clear)."""
    doc, legs = _lane({"lower": [5.2, 1.4], "upper": [6.0, 2.6], "active": [6.0, 8.0]})
    assert retime(legs, stt.Spec.from_dict(_lane()[0]))[-1].end < 6.0    # no box
    timed = retime(legs, stt.Spec.from_dict(doc))
    assert timed is not None and 8.0 <= timed[-1].end <= 10.0


def test_factor_sets_sharing_their_judged_moves_time_as_each_alone(monkeypatch):
    """The re-timings of one via design at several factor sets share one memo of judged
    moves: each gives the timing it gives alone, and a later set judges only the moves the
    earlier ones did not."""
    doc, legs = _lane({"lower": [2.7, 1.0], "upper": [3.3, 3.0], "active": [0.0, 4.0]},
                      {"lower": [5.2, 1.4], "upper": [6.0, 2.6], "active": [6.0, 7.0]})
    spec = stt.Spec.from_dict({**doc, "actuator": {"input_bound": [2, 2]}})
    memo: dict = {}
    sizes = []
    for factors in ((1.0, 1.5, 2.0), (1.0, 0.75, 1.5, 2.0), DURATION_FACTORS):
        shared = retime(legs, spec, None, factors, memo)
        assert shared == retime(legs, spec, None, factors)
        assert shared is not None and shared[-1].end <= 10.0
        sizes.append(len(memo))
    assert 0 < sizes[0] < sizes[1] < sizes[2]
    # a memo that says every move is clear is read, not judged again: the search's timing
    # changes (the levelling after the search judges its own moves: left out here)
    monkeypatch.setattr(moving, "LEVEL_WINDOWS", ())
    lied = {key: True for key in memo}
    assert retime(legs, spec, None, DURATION_FACTORS, lied) != retime(
        legs, spec, None, DURATION_FACTORS)


@pytest.mark.slow
def test_a_detour_around_where_a_moving_obstacle_crosses_the_tasks_plan():
    """Problem 148 of ``bench tasks --seed 2``: the only moving obstacle drifts across a
    leg's lane while that leg must be under way, so neither the tasks' plan (step 1) nor any
    timing of its via boxes misses it, and the region it sweeps meets the start set (no
    swept design). Planning around the box it sweeps over 1 s either side of where the
    plan meets it, and timing that plan against it as it moves, gives a certified tube."""
    from stt_codegen_bench.arenas import arena_spec
    spec = arena_spec("tasks", 2, 148)
    assert len(spec.moving_obstacles) == 1 and swept_spec(spec)[0] is None
    planned = stt.design_tube(static_part(spec))
    assert not check_tube(planned.tube, spec).passed
    assert retime(planned.tube.segments, spec) is None
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    data = design.to_json()
    assert all(t["certified"] and t["margin"] > 0 for t in data["tasks"])
    assert data["moving_obstacles"][0]["margin"] > 0
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and all(t.met for t in run.tasks)


def _crossing_with_actuator(bound: list[float]) -> stt.Spec:
    data = tomllib.loads(bundled_spec_bytes("crossing-moving").decode())
    data["actuator"] = {"input_bound": bound}
    return stt.Spec.from_dict(data)


@pytest.mark.slow
def test_a_wait_for_a_moving_obstacle_is_kept_under_an_actuator_bound():
    """With [actuator], the re-timed via plan (wait, then cross) is accepted with its own
    input proof: the bundled crossing, which the static and swept designs cannot do."""
    from stt_codegen.design.actuator import law13_input_proof
    spec = _crossing_with_actuator([3.0, 3.0])
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    assert design.tube.input_bound == (3.0, 3.0)            # the generated code clamps
    proof = law13_input_proof(design, spec)
    assert design.input_proof == proof and proof.meets(spec.input_bound)
    # the re-timed tube is not the static design's: its proof is its own
    assert design.tube.segments[0].start > 0.0              # it waits at the start


def test_a_re_timed_plan_drives_its_legs_no_faster_than_the_bound_allows():
    """With [actuator] the re-timing leaves out the fast segments until the proof keeps
    the bound: at 1.5 the earliest plan (a leg at half its planned duration) is beyond
    it, a later one with cruise segments is within it."""
    spec = _crossing_with_actuator([1.5, 1.5])
    design = stt.design_tube(spec)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    assert design.input_proof.meets(spec.input_bound)
    assert {seg.profile for seg in design.tube.segments} == {"cruise"}


def test_a_levelled_timing_that_fails_its_check_gives_way_to_the_searched_one():
    """Levelling judges each move as the search does, not the whole check: where the
    levelled timing (the crossing's leg until t_c = 10 s) fails the check, the search's
    own timing (the leg ending at 9.67 s) is checked, and kept when it passes."""
    from stt_codegen.design.moving import design_moving
    from stt_codegen.design.search import _position_stage
    spec = _crossing_with_actuator([3.0, 3.0])
    ends: list[float] = []

    def check(tube, checked):
        ends.append(tube.segments[-1].end)
        found = check_tube(tube, checked)
        return replace(found, passed=False) if tube.segments[-1].end == 10.0 else found

    design = design_moving(spec, _position_stage, check)
    assert design.motion == MOTION_TIMED_VIA and design.certificate.passed
    assert design.tube.segments[-1].end == pytest.approx(9.6667, abs=1e-3)
    assert ends.index(10.0) < ends.index(design.tube.segments[-1].end)


@pytest.mark.slow
def test_a_re_timed_plan_beyond_the_bound_is_refused_saying_so():
    spec = _crossing_with_actuator([1.0, 1.0])
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert ("the re-timed via tube around none fails: its input is not proved within "
            "actuator.input_bound (|u1| <= ") in str(raised.value)
