"""Via-point tubes, automatic sharpness, the design command, random arenas."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from random_arenas import arena_spec, disc_can_pass

from stt_codegen.design.certificate import MAX_MOVE_PER_SAMPLE, certify_tube
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import base_design, design_tube
from stt_codegen.design.via import via_design
from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import Box, load_spec, parse_spec
from stt_codegen.tube import reference as R

SERPENTINE = (Path(__file__).parent / "specs" / "serpentine.toml").read_text()
WALL = """
[[obstacles]]
lower = [2.0, 0.0]
upper = [2.5, 5.0]
"""


def serpentine():
    spec = parse_spec(SERPENTINE)
    return spec, design_tube(spec)


@pytest.mark.slow
def test_auto_uses_via_points_where_the_papers_tube_has_no_design():
    spec, design = serpentine()
    paper = dataclasses.replace(spec, tube=dataclasses.replace(spec.tube, method="paper"))
    with pytest.raises(DesignError):
        design_tube(paper)
    assert design.method == "via" and design.certificate.passed
    assert len(design.tube.segments) >= 3
    assert {s.profile for s in design.tube.segments} == {"smoothstep"}
    assert design.tube.segments[-1].end <= spec.prescribed_time
    assert design.to_json()["via"][0]["time"] == 0.0


def test_reach_tube_and_its_rate_are_continuous_at_every_via_point():
    _, design = serpentine()
    tube = design.tube
    scale = max(abs(v) for s in tube.segments for v in s.lower_to + s.upper_to)
    for seg in tube.segments[:-1]:
        eps = 1e-7 * seg.end
        before = R.reach_tube(tube, [seg.end - eps])
        after = R.reach_tube(tube, [seg.end + eps])
        for a, b in zip(before, after):
            assert np.max(np.abs(a - b)) < 1e-5 * scale
    # the rate is far from zero between via points: a jump would show
    mid = [0.5 * (s.start + s.end) for s in tube.segments]
    assert np.max(np.abs(R.reach_tube(tube, mid)[2])) > 0.1


@pytest.mark.slow
def test_a_via_tube_meeting_an_obstacle_between_two_samples_is_rejected():
    """A 0.1 mm obstacle that the via tube's corner clips for less than one 20 ms period."""
    spec, design = serpentine()
    slow = dataclasses.replace(design.tube, rate_hz=50.0)
    samples = sample_tube(slow, slow.prescribed_time)
    t = np.arange(0.0, samples.t[-1], 1e-5)
    alpha = np.column_stack([np.interp(t, samples.t, a) for a in samples.alpha.T])
    d_l, d_u, _, _ = R.adaptive_tube(slow, t, alpha)
    first = slow.segments[0]                             # moves up and right, fast
    i = int(0.5 * (first.start + first.end) * slow.rate_hz)
    k = int(np.searchsorted(t, samples.t[i] + 0.01))     # midway between two samples
    # just right of the leading x bound's side, just below the trailing lower y bound
    corner = (float(d_u[k, 0]) - 2e-4, float(d_l[k, 1]) - 1e-4)
    box = Box(corner, (corner[0] + 1e-4, corner[1] + 1e-4))
    hit_dense = np.all((d_l <= box.upper) & (d_u >= box.lower), axis=1)
    hit_samples = np.all((samples.gamma_lower <= box.upper)
                         & (samples.gamma_upper >= box.lower), axis=1)
    assert hit_dense.any() and hit_dense.sum() * 1e-5 < 0.02   # met, for less than a period
    assert not hit_samples.any()                                # every sample misses it
    clipped = parse_spec(SERPENTINE + f"""
[[obstacles]]
lower = [{box.lower[0]!r}, {box.lower[1]!r}]
upper = [{box.upper[0]!r}, {box.upper[1]!r}]
""")
    failure = certify_tube(slow, clipped).first_failure()       # the certificate catches it
    assert failure is not None and failure.name == "avoids obstacle 2"


def test_no_free_passage_says_where():
    """A gap of 0.2 in a wall: a point passes, a via box (half-width 0.1 and 0.05
    clearance) does not."""
    gap = """
[[obstacles]]
lower = [2.0, 0.0]
upper = [2.5, 2.4]
[[obstacles]]
lower = [2.0, 2.6]
upper = [2.5, 5.0]
"""
    spec = parse_spec(SERPENTINE.split("[[obstacles]]")[0] + gap)
    with pytest.raises(DesignError, match=r"no via-point path: .* comes closest to the target "
                                          r"at \(.*\); the passage is too narrow there") as info:
        via_design(spec, base_design(spec))
    assert info.value.kind is FailureKind.NO_PASSAGE


def test_a_wall_across_the_arena_is_not_called_a_narrow_passage():
    spec = parse_spec(SERPENTINE.split("[[obstacles]]")[0] + WALL)
    with pytest.raises(DesignError, match=r"no via-point path: (the target|x\(0\)) is walled "
                                          r"off from (x\(0\)|the target) by obstacle 0 and "
                                          r"the state-space boundary") as info:
        via_design(spec, base_design(spec))
    assert info.value.kind is FailureKind.WALLED_OFF
    assert "too narrow" not in str(info.value)


WALLED_TARGET = SERPENTINE.split("[[obstacles]]")[0] + """
[[obstacles]]
lower = [2.0, 0.0]
upper = [2.5, 1.0]
[[obstacles]]
lower = [3.8, 3.8]
upper = [4.0, 5.0]
[[obstacles]]
lower = [3.8, 3.8]
upper = [5.0, 4.0]
"""


@pytest.mark.parametrize("method", ["via", "auto"])
def test_a_walled_off_target_is_named_with_its_walls(method):
    """Obstacles 1 and 2 close the corner around the target: the refusal says so (it used
    to say that the passage is too narrow), naming them and not obstacle 0."""
    spec = parse_spec(WALLED_TARGET + f'[tube]\nmethod = "{method}"\n')
    with pytest.raises(DesignError) as info:
        design_tube(spec)
    message = str(info.value)
    assert message.startswith("no via-point path: the target is walled off from x(0) by "
                              "obstacles 1, 2 and the state-space boundary"), message
    assert "too narrow" not in message
    assert info.value.kind is FailureKind.WALLED_OFF


@pytest.mark.parametrize("index", range(8))
def test_automatic_sharpness_never_violates_the_sampling_rate_limit(index):
    """On the random arenas (no [tube] section) every circumvent's k^j is chosen by the
    design; the deployed tube, sampled independently of the certificate, moves at most
    MAX_MOVE_PER_SAMPLE tube widths per period."""
    spec = arena_spec(1, index)
    assert spec.tube.circumvent_sharpness is None
    try:
        design = design_tube(spec)
    except DesignError:
        pytest.skip("no design for this arena")
    assert design.certificate.max_move_ratio <= MAX_MOVE_PER_SAMPLE
    s = sample_tube(design.tube)
    width = s.gamma_upper - s.gamma_lower
    move = np.maximum(np.abs(s.gamma_lower_dot), np.abs(s.gamma_upper_dot)) / design.tube.rate_hz
    assert np.all(width > 0) and np.max(move / width) <= MAX_MOVE_PER_SAMPLE
    assert all(c.sharpness > 0 for c in design.tube.circumvents)


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args],
                          capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_design_json_fields_and_exit_codes(tmp_path):
    ok = run_cli("design", "omnirobot-s1", "--json")
    assert ok.returncode == 0, ok.stderr
    data = json.loads(ok.stdout)
    assert set(data) >= {"spec", "method", "circumvents", "via", "gain", "certificate",
                         "design_time_s"}
    assert data["spec"] == "omnirobot-s1" and data["method"] == "paper" and data["via"] == []
    c = data["circumvents"][0]
    assert set(c) == {"obstacle", "dimension", "side", "start", "end", "height", "sharpness"}
    assert (c["obstacle"], c["dimension"], c["side"], c["sharpness"]) == (0, 1, "upper", 0.1)
    props = {p["name"]: p for p in data["certificate"]["properties"]}
    assert props["avoids obstacle 0"]["passed"] and props["avoids obstacle 0"]["margin"] > 0
    assert data["certificate"]["horizon"] == "inf"
    assert data["design_time_s"] > 0 and data["gain"] > 0     # a duration: no bound on it

    blocked = tmp_path / "wall.toml"
    blocked.write_text(SERPENTINE.split("[[obstacles]]")[0] + WALL)
    no = run_cli("design", str(blocked))
    assert no.returncode == 1 and "Traceback" not in no.stderr
    assert len(no.stderr.strip().splitlines()) == 1 and "walled off" in no.stderr

    bad = tmp_path / "bad.toml"
    bad.write_text(SERPENTINE.replace("[[obstacles]]", "[tube]\nmethod = \"straight\"\n"
                                      "[[obstacles]]", 1))
    wrong = run_cli("design", str(bad))
    assert wrong.returncode == 2 and "tube.method" in wrong.stderr
    assert "Traceback" not in wrong.stderr
    assert run_cli("design", "omnirobot-s1", "--plot",
                   str(tmp_path / "missing" / "x.png")).returncode == 2


@pytest.mark.slow
def test_huge_prescribed_time_designs_and_simulate_refuses_with_exit_2(tmp_path):
    spec_text = SERPENTINE.replace("prescribed_time = 12.0", "prescribed_time = 1e9")
    path = tmp_path / "long.toml"
    path.write_text(spec_text)
    design = design_tube(parse_spec(spec_text))
    assert design.certificate.passed and design.certificate.intervals < 5000
    out = run_cli("simulate", str(path), "--backend", "reference")
    assert out.returncode == 2 and "prescribed_time" in out.stderr
    assert "budget" in out.stderr and "Traceback" not in out.stderr


#: Arenas 0 and 1 in the fast tier, the others in the slow one (a closed loop each).
ARENAS = [0, 1] + [pytest.param(k, marks=pytest.mark.slow) for k in range(2, 12)]


@pytest.mark.parametrize("index", ARENAS)
def test_random_arena_with_a_corridor_is_satisfied(index):
    """5-8 random boxes (0.4-1.4 m), random start and target, no [tube] section: wherever
    a disc of radius 0.15 m can move from x(0) to the target centre, the designed
    controller (generated C) satisfies the task."""
    spec = arena_spec(0, index)
    if not disc_can_pass(spec):
        pytest.skip("no corridor for a 0.15 m disc")
    design = design_tube(spec)
    result = simulate(design, backend="c", seed=index)
    assert result.satisfied, (design.method, result)


def test_a_convex_wall_across_the_straight_path_is_passed_with_via_points():
    """docs/spec-format.md's example (tests/specs/diagonal-wall.toml): the paper's method has no
    design (one bump per covering box cannot detour around the wall's end); via points do,
    and the generated-C closed loop is satisfied without touching the wall."""
    spec = load_spec(Path(__file__).parent / "specs" / "diagonal-wall.toml")
    paper = dataclasses.replace(spec, tube=dataclasses.replace(spec.tube, method="paper"))
    with pytest.raises(DesignError):
        design_tube(paper)
    design = design_tube(spec)
    assert design.method == "via" and design.certificate.passed
    result = simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_tube and not result.collision
    assert result.min_obstacle_clearance > 0.0


def test_box_obstacle_meeting_is_the_definition():
    """The via planner's overlap test (one obstacle column at a time) says box k widened by
    the margin meets obstacle b exactly when it does so strictly in every dimension, on
    boxes placed to touch, overlap and miss."""
    from stt_codegen.design import via
    rng = np.random.default_rng(2)
    for n, count, boxes in ((2, 400, 4), (3, 200, 3), (2, 5, 0), (2, 0, 2)):
        # corners on a 0.05 grid, so that many boxes touch an obstacle exactly
        lower = np.round(rng.uniform(0.0, 5.0, (count, n)) * 20) / 20
        upper = lower + np.round(rng.uniform(0.05, 1.0, (count, n)) * 20) / 20
        ob_lo = np.round(rng.uniform(0.0, 4.0, (boxes, n)) * 20) / 20
        obstacles = np.stack([ob_lo, ob_lo + 1.0], axis=1)
        for margin in (0.0, 0.05):
            meets = via._meets(lower, upper, obstacles, margin)
            assert meets.shape == (count, boxes)
            for k in range(count):
                for b in range(boxes):
                    strict = all(lower[k, i] - margin < obstacles[b, 1, i]
                                 and upper[k, i] + margin > obstacles[b, 0, i] for i in range(n))
                    assert meets[k, b] == strict
            if count and boxes:
                assert meets.any() and not meets.all()


@pytest.mark.parametrize("n", [1, 2, 3])
def test_free_boxes_and_move_lengths_are_the_row_wise_ones(n):
    """The via planner's free-box test and move lengths, column by column, answer as the
    row-wise formulas (all corners inside the state space, no obstacle met with the margin,
    touching not counted; the max norm of the centres' difference), also for boxes that
    touch an obstacle or the boundary exactly."""
    from stt_codegen.design import via
    rng = np.random.default_rng(5)
    k = 3000
    # corners on a 0.05 grid, so many boxes touch obstacles and the boundary exactly
    lower = np.round(rng.uniform(-0.5, 5.0, (k, n)) / 0.05) * 0.05
    upper = lower + np.round(rng.uniform(0.0, 1.0, (k, n)) / 0.05) * 0.05
    corner = np.round(rng.uniform(0.0, 4.0, (4, n)) / 0.05) * 0.05
    obstacles = np.stack([corner, corner + 1.0], axis=1)                 # (B, 2, n)
    space = (np.zeros(n), np.full(n, 5.0))
    for margin in (0.0, 0.05):
        plain = (np.all((lower >= space[0]) & (upper <= space[1]), axis=1)
                 & ~via._meets(lower, upper, obstacles, margin).any(axis=1))
        assert np.array_equal(via._free(lower, upper, obstacles, space, margin), plain)
        assert 0 < plain.sum() < k
    a, b = rng.integers(0, k, 500), rng.integers(0, k, 500)
    assert np.array_equal(via._max_distance(lower, a, b),
                          np.max(np.abs(lower[a] - lower[b]), axis=1))


# --------------------------------------------------------------------------- timed for a force


def _force_spec(velocity_bound: list | None, timing: str = "acceleration",
                profile: str = "smoothstep"):
    """A 2-D double integrator with a velocity bound, timed for the acceleration."""
    bound = "" if velocity_bound is None else f"velocity_bound = {velocity_bound!r}\n"
    spec = parse_spec(f"""
name = "timed-moves"
prescribed_time = 20.0
[state_space]
lower = [0.0, 0.0]
upper = [10.0, 10.0]
{bound}
[initial]
lower = [0.9, 0.9]
upper = [1.1, 1.1]
[target]
lower = [8.0, 8.0]
upper = [9.0, 9.0]
[plant]
model = "double-integrator"
parameters = [1.0]
""")
    return dataclasses.replace(spec, tube=dataclasses.replace(
        spec.tube, method="via", via_timing=timing, via_profile=profile))


#: Three moves: one long enough that its smooth step in its square-root share of 20 s
#: would pass 1 m/s, two short.
MOVES = [np.array([0.5, 0.2]), np.array([9.0, 0.0]), np.array([0.0, 1.0])]


def test_timed_moves_of_no_length_share_the_time_equally():
    from stt_codegen.design.via import timed_moves
    still = [np.zeros(2), np.zeros(2)]
    assert timed_moves(_force_spec([1.0, 1.0]), still, 6.0, "scurve") == (
        [3.0, 3.0], ["scurve", "scurve"])


def test_timed_moves_without_a_velocity_bound_are_the_square_root_shares_bit_for_bit():
    from stt_codegen.design.via import move_weight, timed_moves
    for spec in (_force_spec(None), _force_spec([1.0, 1.0], timing="length")):
        durations, profiles = timed_moves(spec, MOVES, 20.0, "smoothstep")
        weights = [move_weight(float(np.max(np.abs(m))), spec.tube.via_timing) for m in MOVES]
        assert durations == [w / sum(weights) * 20.0 for w in weights]
        assert profiles == ["smoothstep"] * 3


@pytest.mark.parametrize("profile", ["smoothstep", "scurve"])
def test_timed_moves_keep_the_velocity_bound_and_one_peak_acceleration_elsewhere(profile):
    """Under |v_i| <= 1: each move's profile's peak rate is within the bound; the moves the
    bound does not hold share one peak acceleration (the least that fits 20 s); a move
    takes a profile of higher acceleration only where the earlier ones would pass the
    bound at its duration. Without the bound the long move's smooth step would pass it:
    the test can fail."""
    from stt_codegen.design.via import ACCELERATION_PROFILES, timed_moves
    from stt_codegen.tube.parameters import peak_acceleration_factor, peak_rate_factor
    free, _ = timed_moves(_force_spec(None), MOVES, 20.0, profile)
    assert peak_rate_factor(profile) * 9.0 / free[1] > 1.0
    durations, profiles = timed_moves(_force_spec([1.0, 1.0]), MOVES, 20.0, profile)
    assert abs(sum(durations) - 20.0) < 1e-12
    tried = ACCELERATION_PROFILES[ACCELERATION_PROFILES.index(profile):]
    accelerations = []
    for move, d, p in zip(MOVES, durations, profiles):
        length = float(np.max(np.abs(move)))
        assert p in tried
        assert peak_rate_factor(p) * length / d <= 1.0 + 1e-9
        for earlier in tried[:tried.index(p)]:      # cheaper, but too fast at d
            assert peak_rate_factor(earlier) * length / d > 1.0 - 1e-9
        accelerations.append(peak_acceleration_factor(p) * length / d**2)
    unheld = [a for a, move, d, p in zip(accelerations, MOVES, durations, profiles)
              if peak_rate_factor(p) * float(np.max(np.abs(move))) / d < 1.0 - 1e-6]
    assert len(unheld) >= 2 and max(unheld) - min(unheld) <= 1e-6 * max(unheld)
    assert max(accelerations) <= max(unheld) * (1.0 + 1e-6)


def test_a_via_tube_timed_for_a_force_keeps_its_profiles_peak_rate_within_the_bound():
    """The via design itself: every segment's peak rate within |v| <= 0.5 (its smooth
    steps timed by square roots alone would pass it), and the tube still ends at t_c."""
    from stt_codegen.tube.parameters import peak_rate_factor
    spec = _force_spec([0.5, 0.5])
    design = via_design(spec, base_design(spec))
    assert design.segments[-1].end == spec.prescribed_time
    rates = []
    for seg in design.segments:
        move = max(abs(0.5 * (b + d) - 0.5 * (a + c)) for a, c, b, d in
                   zip(seg.lower_from, seg.upper_from, seg.lower_to, seg.upper_to))
        rates.append(peak_rate_factor(seg.profile) * move / (seg.end - seg.start))
    assert max(rates) <= 0.5 * (1.0 + 1e-9)
    free = via_design(_force_spec(None), base_design(_force_spec(None)))
    assert max(peak_rate_factor(s.profile) * max(
        abs(0.5 * (b + d) - 0.5 * (a + c)) for a, c, b, d in
        zip(s.lower_from, s.upper_from, s.lower_to, s.upper_to)) / (s.end - s.start)
        for s in free.segments) > 0.5
