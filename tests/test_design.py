"""Tube design: windows of eq. (5), the circumvent search, and the design check."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import arena_toml, designed
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from stt_codegen.design.failures import FailureKind
from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import MAX_MOVE_PER_SAMPLE, base_design, check_tube, design_tube
from stt_codegen.design.windows import overlap_interval, progress_time
from stt_codegen.errors import DesignError
from stt_codegen.spec.loader import Box, load_spec, parse_spec

TWO_D = arena_toml("corridor", 8.0)


def literal_window(design, box):
    """Eq. (5) read literally (valid only when every ratio lies in (0, 1))."""
    t_c = design.prescribed_time
    mins, maxs = [], []
    for i in range(design.dimension):
        xl, xu = design.initial_lower[i], design.initial_upper[i]
        tl, tu = design.target_lower[i], design.target_upper[i]
        ratios = [(box.lower[i] - xl) / (tl - xl), (box.upper[i] - xl) / (tl - xl),
                  (box.lower[i] - xu) / (tu - xu), (box.upper[i] - xu) / (tu - xu)]
        bars = [math.atanh(r) / (1 + math.atanh(r)) for r in ratios]
        mins.append(min(bars))
        maxs.append(max(bars))
    return max(mins) * t_c, min(maxs) * t_c


@settings(max_examples=200, deadline=None)
@given(lo=st.tuples(st.floats(0.7, 3.5), st.floats(0.7, 3.5)),
       size=st.tuples(st.floats(0.1, 0.9), st.floats(0.1, 0.9)))
def test_robust_window_equals_the_literal_eq5_where_that_is_defined(lo, size):
    design = base_design(parse_spec(TWO_D))
    box = Box(lo, tuple(a + b for a, b in zip(lo, size)))
    assume(all(box.upper[i] < design.target_lower[i] - 1e-3 for i in range(2)))
    interval = overlap_interval(design, box, 0.0)
    expected = literal_window(design, box)
    if expected[0] > expected[1]:
        assert interval is None
        return
    assert interval is not None
    got = tuple(progress_time(design, s) for s in interval)
    assert got == pytest.approx(expected, abs=1e-9)


def test_window_on_a_degenerate_dimension_has_no_zero_over_zero():
    """Start and target at the same height: eq. (5) is 0/0 in x2; the robust window is not."""
    text = TWO_D.replace("[initial]\nlower = [0.0, 0.0]\nupper = [0.5, 0.5]",
                         "[initial]\nlower = [0.0, 4.5]\nupper = [0.5, 5.0]")
    design = base_design(parse_spec(text))
    assert design.initial_lower[1] == design.target_lower[1]
    wall = Box((1.0, 4.0), (2.0, 5.0))            # the x2 range always overlaps
    interval = overlap_interval(design, wall, 0.0)
    assert interval is not None
    s_lo, s_hi = interval
    # only x1 decides: rho_U(x1) reaches 1.0 and rho_L(x1) leaves 2.0
    assert s_lo == pytest.approx((1.0 - 0.45) / 4.5) and s_hi == pytest.approx((2.0 - 0.05) / 4.5)
    below = Box((1.0, 0.0), (2.0, 1.0))           # never overlaps in x2
    assert overlap_interval(design, below, 0.0) is None


def test_bundled_designs_pass_their_check(case):
    spec, design, check = designed(case)
    assert check.passed and check.reason == ""
    assert check.min_clearance > 0 and check.min_width > 0
    assert check.max_move_ratio <= MAX_MOVE_PER_SAMPLE
    assert design.gain > 0 and design.circumvents
    # the wall O1 is passed underneath from S1 (x2, upper side): the literal eq. (6)
    # would pick x1 and let the robot cross O1 (docs/decisions.md, decision 6)
    if case == "omnirobot-s1":
        c = [c for c in design.circumvents if c.obstacle == 0][0]
        assert (c.dimension, c.side) == (1, "upper")


def test_design_is_deterministic():
    spec = load_spec("omnirobot-s2")
    assert design_tube(spec) == design_tube(spec)


@pytest.mark.slow
def test_papers_sharpness_fails_with_a_reason_naming_the_obstacle():
    spec = load_spec("omnirobot-s1")
    paper = dataclasses.replace(spec, tube=dataclasses.replace(
        spec.tube, circumvent_sharpness=0.01, method="paper"))
    with pytest.raises(DesignError, match=r"obstacle 0: a tube bound moves .* tube widths"):
        design_tube(paper)
    # the default method falls back on via points, whose tube needs no circumvent
    auto = dataclasses.replace(paper, tube=dataclasses.replace(paper.tube, method="auto"))
    found = design_tube(auto)
    assert found.method == "via" and found.certificate.passed and not found.tube.circumvents


def test_check_detects_a_tube_through_an_obstacle():
    spec, design, _ = designed("omnirobot-s1")
    bare = dataclasses.replace(design, circumvents=())
    check = check_tube(bare, spec)
    assert not check.passed and "may meet obstacle 0" in check.reason
    assert check.min_clearance < 0


def test_check_detects_a_tube_outside_the_target_at_t_c():
    spec, design, _ = designed("omnirobot-s2")
    last = dataclasses.replace(design.segments[-1], lower_to=(4.2, 4.55, -0.5))  # T is [4.5, 5]
    wide = dataclasses.replace(design, segments=design.segments[:-1] + (last,))
    check = check_tube(wide, spec, obstacles=[])
    assert not check.passed and "inside target after t_c fails" in check.reason


def test_empty_tube_is_reported():
    spec, design, _ = designed("omnirobot-s2")
    blunt = dataclasses.replace(design, smoothness=2.0)   # bias ln2/nu = 0.35 per side
    check = check_tube(blunt, spec)
    assert not check.passed


def test_sampled_alpha_starts_at_zero_and_stays_valid(case):
    _, design, _ = designed(case)
    samples = sample_tube(design)
    assert np.all(samples.alpha[0] == 0)
    assert np.all(samples.alpha >= 0)


def test_a_start_at_the_tube_edge_is_rejected():
    """Random arena 233: its first candidate's window opens before t = 0, so x(0) starts at
    the edge of the narrowed tube; deployed, the first input was 1e8 and the state left the
    arena in one period. The check refuses it, and the search finds another design."""
    from stt_codegen_bench.arenas import arena_spec
    from stt_codegen.design.search import MAX_INITIAL_ERROR
    from stt_codegen.design.windows import candidates
    spec = arena_spec("paper", 0, 233)
    base = base_design(spec)
    first = candidates(base, spec, 1, spec.tube.delta_b)[0]
    assert first.start < 0
    check = check_tube(dataclasses.replace(base, circumvents=(first,)), spec)
    assert check.initial_error > MAX_INITIAL_ERROR
    assert not check.passed and "x(0) starts at |e| =" in check.reason
    found = design_tube(spec)
    accepted = found.check
    assert accepted.passed and accepted.initial_error <= MAX_INITIAL_ERROR


def test_the_gain_comes_from_the_tubes_width_not_from_a_loose_enclosure():
    """Random arena 178 of seed 0: on one sampling period where both bounds move fast the
    partition's enclosure of the width is 5 mm, the tube itself is 38 mm wide. A gain
    derived from 5 mm (0.0017) left the state lagging at |e| = 0.95 until the tube moved
    past it (the only arena A* satisfied and the toolkit did not); from the sharpened
    bound the loop is satisfied (the paper's method; ``auto`` now reaches via points first
    on this arena, within its work budget)."""
    from stt_codegen_bench.arenas import arena_spec
    from stt_codegen.runtime.simulate import simulate
    spec = arena_spec("paper", 0, 178)
    spec = dataclasses.replace(spec, tube=dataclasses.replace(spec.tube, method="paper"))
    found = design_tube(spec)
    assert found.method == "paper"
    enc = found.check.certificate.enclosure
    assert float((enc.upper_min - enc.lower_max).min()) < 0.01
    assert found.check.min_width > 0.03
    result = simulate(found, backend="c")
    assert result.satisfied and result.stayed_in_tube


# --------------------------------------------------------------------------- failures


@pytest.mark.slow
def test_every_refusal_carries_a_kind_and_the_tube_tried():
    """Callers branch on DesignError.kind, never on the message."""
    spec = load_spec("omnirobot-s1")
    paper = dataclasses.replace(spec, tube=dataclasses.replace(
        spec.tube, circumvent_sharpness=0.01, method="paper"))
    with pytest.raises(DesignError) as info:
        design_tube(paper)
    assert info.value.kind is FailureKind.SAMPLING_RATE
    assert info.value.tried is not None and info.value.tried.circumvents
    # the tube has circumvents, so a smoother bump is offered too
    assert "tube.circumvent_sharpness" in str(info.value)


def _rate_spec(rate_hz: float, method: str = "paper"):
    return parse_spec(arena_toml("open", 2.0, f"[tube]\nmethod = \"{method}\"\n"
                                 f"[controller]\nrate_hz = {float(rate_hz)!r}\n"))


def test_a_rate_refusal_without_obstacles_names_the_lowest_rate_that_passes():
    """No obstacle, so no circumvent: the refusal used to suggest tube.circumvent_sharpness
    and no rate. It names the lowest two-digit rate that passes: designing with it
    passes, and with the two-digit rate below it fails for the sampling rate again."""
    with pytest.raises(DesignError) as info:
        design_tube(_rate_spec(10.0))
    message = str(info.value)
    assert info.value.kind is FailureKind.SAMPLING_RATE
    assert "circumvent_sharpness" not in message
    found = re.search(r"passes its check from controller\.rate_hz = ([0-9.e+]+) \(the lowest",
                      message)
    assert found, message
    rate = float(found.group(1))
    assert rate > 10.0
    design = design_tube(_rate_spec(rate))
    assert design.certificate.passed and design.tube.rate_hz == rate
    below = rate - 10.0 ** (math.floor(math.log10(rate)) - 1)
    with pytest.raises(DesignError) as lower:
        design_tube(_rate_spec(below))
    assert lower.value.kind is FailureKind.SAMPLING_RATE
    # the default method (via points next) passes at that rate too
    assert design_tube(_rate_spec(rate, "auto")).certificate.passed


@pytest.mark.parametrize("g, eigenvalue", [("[[-1.0, 0.0], [0.0, -1.0]]", "-1"),
                                           ("[[1.0, 0.0], [0.0, -0.5]]", "-0.5"),
                                           ("[[0.0, 1.0], [-1.0, 0.0]]", "0")])
def test_a_linear_plant_breaking_assumption_2_is_refused(g, eigenvalue):
    """g = -I used to design (exit 0) and fail in simulation without a reason."""
    spec = parse_spec(arena_toml("reversed", 9.0,
                                 f"[plant]\nmodel = \"linear\"\ng = {g}\n"))
    with pytest.raises(DesignError) as info:
        design_tube(spec)
    assert info.value.kind is FailureKind.PLANT and info.value.tried is None
    message = str(info.value)
    assert message.startswith("plant.g: ") and "Assumption 2" in message
    assert re.search(rf"eigenvalue {re.escape(eigenvalue)}\b", message), message


def test_the_linear_plant_check_on_the_command_line(tmp_path):
    path = tmp_path / "reversed.toml"
    path.write_text(arena_toml("reversed", 9.0,
                               '[plant]\nmodel = "linear"\ng = [[-1.0, 0.0], [0.0, -1.0]]\n'))
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", str(path)],
                         capture_output=True, text=True)
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr.startswith("error: plant.g: ") and out.stderr.count("\n") == 1
    assert "Traceback" not in out.stderr
    # a positive definite g with a skew part designs
    ok = parse_spec(arena_toml("skewed", 9.0,
                               '[plant]\nmodel = "linear"\ng = [[1.0, 0.5], [-0.5, 1.0]]\n'))
    assert design_tube(ok).certificate.passed


@pytest.mark.parametrize("index, kind", [(2, FailureKind.SEARCH_BUDGET),
                                         (6, FailureKind.INITIAL_STATE),
                                         pytest.param(26, FailureKind.NON_EMPTY,
                                                      marks=pytest.mark.slow)])
def test_paper_search_refusals_are_typed(index, kind):
    """Random arenas the paper's method alone cannot design (seed 1): the kind says why
    (the search's budget, or the first obstacle's failure in the message), and the tube
    tried is the one that chose circumvents for the most obstacles."""
    from random_arenas import arena_toml as random_arena
    spec = parse_spec(random_arena(1, index) + '[tube]\nmethod = "paper"\n')
    with pytest.raises(DesignError) as info:
        design_tube(spec)
    assert info.value.kind is kind
    tried = info.value.tried
    assert tried is not None and tried.circumvents and not check_tube(tried, spec).passed
