"""Design and verify under ``[actuator] input_bound``: the design meets
a bound the default tube exceeds, or refuses naming the ``prescribed_time`` that works;
``verify`` proves the bound (``sampled.input_bound``); the closed loop, with the generated
C, never exceeds it."""

from __future__ import annotations

import dataclasses
import math
import re
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from conftest import arena_toml

from stt_codegen.cli import main
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.input_bound import input_peak, phi
from stt_codegen.design.search import design_tube
from stt_codegen.design.samples import sample_tube
from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import run_closed_loop, simulate
from stt_codegen.spec.loader import load_spec, parse_spec
from stt_codegen.tube import reference as R
from stt_codegen.tube.parameters import STATUS_INPUT_CLAMPED, STATUS_OK, STATUS_OUTSIDE_TUBE
from stt_codegen.design.certificate.actuator import prove_input_bound, sampled_error_bound
from stt_codegen.verification.command import verify
from stt_codegen.design.certificate.sampled import check_sampled

SPECS = Path(__file__).parent / "specs"
ROBOT = SPECS / "actuator-s1.toml"


def small(bound: tuple[float, float] | None, prescribed_time: float = 3.0):
    """A cheap 2-D task: no obstacle, the paper's tube only, 200 Hz; its default tube asks
    up to 3.0 m/s (proved)."""
    extra = '[tube]\nmethod = "paper"\n[controller]\nrate_hz = 200.0\n'
    if bound is not None:
        extra += f"[actuator]\ninput_bound = [{bound[0]!r}, {bound[1]!r}]\n"
    return parse_spec(arena_toml("small", prescribed_time=prescribed_time, extra=extra))


def papers_default(spec):
    """The design ``design_within_bound`` starts from: the spec without ``[actuator]``, the
    paper's tube where it certifies (auto's smoother-tube preference plays no part under a
    bound; these specs' paper tubes are the ones auto finds first)."""
    free = dataclasses.replace(spec, input_bound=None)
    return design_tube(dataclasses.replace(free, tube=dataclasses.replace(free.tube,
                                                                          method="paper")))


@lru_cache(maxsize=None)
def robot():
    spec = load_spec(ROBOT)
    return spec, design_tube(spec)


def test_without_actuator_nothing_changes():
    design = design_tube(load_spec("omnirobot-s1"))
    assert design.input_proof is None and design.tube.input_bound is None
    assert "input_bound" not in design.to_json()


def test_the_peak_is_law_13s_input():
    """``input_peak`` is ``4 k phi(|e|) / gamma_d``: the reference law's ``|u|`` at that
    ``|e|`` and width."""
    design = design_tube(small(None))
    tube = design.tube
    t = np.array([0.7, 1.9])
    alpha = np.zeros((2, 4))
    g_l, g_u, _, _ = R.adaptive_tube(tube, t, alpha)
    e = np.array([[0.3, -0.8], [0.55, 0.05]])
    x = ((g_u - g_l) * e + (g_u + g_l)) / 2
    u = R.control(tube, x, t, alpha)
    proof = input_peak(tube.gain, np.abs(e), g_u - g_l, t, 2.0)
    assert np.allclose(proof.peak, np.abs(u).max(axis=0), rtol=1e-12)
    assert proof.time == (1.9, 0.7)
    assert proof.max_abs_e == 0.8             # the |e| bound the peak is proved from
    assert phi(0.0) == 0.0 and phi(0.5) == pytest.approx(2 * math.atanh(0.5) / 0.75)


def test_the_error_bound_is_read_from_the_sampled_check():
    tube = design_tube(small(None)).tube
    samples = sample_tube(tube)
    result = check_sampled(tube, samples, small(None).assumptions)
    per_sample = sampled_error_bound(result, samples)
    assert per_sample.shape == samples.gamma_lower.shape
    assert per_sample.max() == pytest.approx(result.level)
    # without the per-sample bound, the overall one at every sample: never smaller
    overall = sampled_error_bound(dataclasses.replace(result, abs_e=None), samples)
    assert np.all(overall >= per_sample) and overall.min() == result.level
    failed = dataclasses.replace(result, passed=False)
    assert sampled_error_bound(failed, samples) is None


def test_a_proof_stopped_at_a_limit_keeps_the_verdict():
    """``prove_input_bound``'s ``limit``: above the whole proof's peak the check runs whole
    and the proof is the same; below it the check stops at the first sample over it, the
    proof is partial (it meets no bound), its peaks those of the whole proof up to there,
    and the sampled check's bounds up to there are the whole check's."""
    from stt_codegen.design.certificate import sampled
    spec = small(None)
    tube = design_tube(spec).tube
    sampled._KEPT.clear()
    whole = prove_input_bound(tube, spec)
    top = np.array(whole.peak)
    assert whole.complete
    half = 0.5 * top
    # the whole check it ran is kept: asked again, the whole proof at once
    assert prove_input_bound(tube, spec, limit=lambda u: bool(np.any(u > half))) == whole
    sampled._KEPT.clear()
    part = prove_input_bound(tube, spec, limit=lambda u: bool(np.any(u > half)))
    assert part.proved and not part.complete and not part.meets(tuple(10 * top))
    assert np.any(np.array(part.peak) > half) and np.all(np.array(part.peak) <= top)
    assert "stopped there" in part.reason and part.horizon == whole.horizon
    assert sampled.cached_check(tube, spec, False) is None     # a stopped check is not kept
    samples = sample_tube(tube)
    full = check_sampled(tube, samples, spec.assumptions)
    stopped = check_sampled(tube, samples, spec.assumptions, stop=lambda k, e: k == 40)
    assert not stopped.passed and stopped.data["stopped_at"] == samples.t[40]
    assert np.array_equal(stopped.abs_e, full.abs_e[:41])


@pytest.mark.slow
def test_a_bases_proof_is_the_per_axis_arguments(monkeypatch):
    """A base's proof (``point_proof``: ``per_axis_first``) asks the per-axis argument
    alone where it passes, with a limit or without: where its bounds keep the limit its
    whole proof is the answer (here the same as the balls'); where they break it, its
    proof stopped there; no check with the balls runs in either case. Law (13)'s proof
    (S1) goes to the balls at once."""
    from stt_codegen.design import look_ahead
    from stt_codegen.design.actuator import law13_input_proof
    from stt_codegen.design.certificate import sampled
    from stt_codegen.design.failures import without_advice
    spec = load_spec(SPECS / "office-drive.toml")
    base = design_tube(spec)
    tube = base.tube
    sampled._KEPT.clear()
    balls = prove_input_bound(tube, spec)
    axis = prove_input_bound(tube, spec, per_axis_first=True)
    assert axis == balls                                   # the same, bit for bit
    above, below = np.array(axis.peak) * 1.01, np.array(balls.peak) * 0.5
    asked = []
    check = sampled.check_sampled

    def recorded(*args, **kwargs):
        asked.append(kwargs.get("lyapunov", True))
        return check(*args, **kwargs)

    monkeypatch.setattr(sampled, "check_sampled", recorded)
    sampled._KEPT.clear()
    assert look_ahead.point_proof(tube, spec) == axis
    sampled._KEPT.clear()
    assert look_ahead.point_proof(tube, spec, lambda u: bool(np.any(u > above))) == axis
    sampled._KEPT.clear()
    part = look_ahead.point_proof(tube, spec, lambda u: bool(np.any(u > below)))
    assert asked == [False, False, False]                       # no check with the balls
    assert not part.complete and np.any(np.array(part.peak) > below)
    assert np.all(np.array(part.peak) <= np.array(axis.peak))
    monkeypatch.undo()
    # the base's role asks it so: within a verdict search, the same per-axis proof
    sampled._KEPT.clear()
    at_base = look_ahead.look_ahead_input_proof(axis, spec.drive.axle_offset)  # (v, omega)
    capped = dataclasses.replace(spec, input_bound=tuple(2.0 * v for v in at_base.peak))
    with without_advice():
        role = look_ahead.look_ahead_design_proof(base, capped)
    assert role == at_base
    assert sampled.cached_check(tube, capped, False) is None
    s1, design = robot()
    sampled._KEPT.clear()
    top = np.array(prove_input_bound(design.tube, s1).peak) * 1.01
    sampled._KEPT.clear()
    bounded = dataclasses.replace(s1, input_bound=tuple(float(v) for v in top))
    with without_advice():
        assert law13_input_proof(design, bounded).complete
    assert sampled.cached_check(design.tube, bounded, False) is not None  # the balls at once
    assert sampled.cached_check(design.tube, bounded, True) is None


def test_a_search_without_advice_stops_each_proof_at_the_bound():
    """Within ``without_advice`` (a verdict only) law (13)'s and the base's proofs stop at
    the bound: a design the bound refuses is refused all the same ("at least"), one it
    accepts is the same design with the same whole proof."""
    from stt_codegen.design.failures import without_advice
    accepted = design_tube(small((3.5, 3.5)))
    with without_advice():
        again = design_tube(small((3.5, 3.5)))
        with pytest.raises(DesignError) as refused:
            design_tube(small((0.5, 0.5), prescribed_time=3.0))
    assert again.tube == accepted.tube and again.input_proof == accepted.input_proof
    assert again.input_proof.complete
    assert refused.value.kind is FailureKind.INPUT_BOUND
    assert "asks at least" in str(refused.value)


def test_a_re_timing_searched_for_a_verdict_stops_its_proof_at_the_bound():
    """``retimed_design`` (the fleet's and the moving obstacles' re-timing) refuses a
    re-timed tube whose input passes the bound: with the whole proof's peaks, or within
    ``without_advice`` (the fleet's placement) from a proof stopped at the first sample
    over the bound, which says where it stopped; the verdict is the same."""
    from stt_codegen.design.certificate import sampled
    from stt_codegen.design.failures import without_advice
    from stt_codegen.design.moving import retimed_design
    from stt_codegen.design.search import check_tube
    free = small(None)
    via = design_tube(dataclasses.replace(free, tube=dataclasses.replace(free.tube,
                                                                         method="via")))
    spec = small((1.0, 1.0))                 # the via tube asks about 2 of each input
    sampled._KEPT.clear()
    whole = retimed_design(via, spec, spec, check_tube, 0.0)
    sampled._KEPT.clear()
    with without_advice():
        part = retimed_design(via, spec, spec, check_tube, 0.0)
    assert isinstance(whole, str) and isinstance(part, str)
    assert "not proved within actuator.input_bound" in whole and "stopped" not in whole
    peaks = [float(v) for v in re.findall(r"\|u\d\| <= ([0-9.]+)", whole)]
    assert min(peaks) > 1.0
    assert "not proved within actuator.input_bound" in part and "where the proof stopped" in part
    stopped = [float(v) for v in re.findall(r"\|u\d\| <= ([0-9.]+)", part)]
    assert max(stopped) > 1.0 and all(a <= b for a, b in zip(stopped, peaks))


def test_a_bound_the_default_design_meets_keeps_its_tube():
    default = design_tube(small(None))
    bounded = design_tube(small((3.5, 3.5)))
    assert bounded.tube == dataclasses.replace(default.tube, input_bound=(3.5, 3.5))
    assert bounded.input_proof.meets((3.5, 3.5))
    # the proof bounds what the law really asks along a run, and is not vacuous
    run = simulate(bounded, backend="reference")
    assert np.all(np.array(run.max_abs_u) <= np.array(bounded.input_proof.peak))
    assert max(bounded.input_proof.peak) > 0.5 * 3.5


@pytest.mark.slow
def test_a_bound_the_default_design_exceeds_gets_a_slower_tube():
    spec, design = robot()
    bound = spec.input_bound
    default = papers_default(spec)
    before = prove_input_bound(default.tube, spec)
    assert before.proved and before.peak[1] > 4 * bound[1]          # v2 on O1's flank
    assert design.tube.input_bound == bound and design.input_proof.meets(bound)
    assert design.method == "via" and design.tube != default.tube
    # the accepted tube is the first slower one proved within the bound: its proof is the
    # prover's on that tube, and its margin is the room left by the worst input
    assert design.input_proof == prove_input_bound(design.tube, spec)
    document = design.to_json()
    assert document["input_bound"] == list(bound)
    assert document["input_peak"]["peak"] == list(design.input_proof.peak)
    margin = 1 - max(p / b for p, b in zip(design.input_proof.peak, bound))
    assert document["input_peak"]["margin"] == pytest.approx(margin, rel=1e-12) and margin >= 0


@pytest.mark.slow
def test_a_bound_smooth_step_via_points_exceed_gets_cruise_segments():
    """With ``|v1|, |v2| <= 1.4``, the paper's tube, its softer circumvents and the
    smooth-step via tube all exceed the bound (the last asks 1.55 of v1); the via tube
    with cruise segments (the same boxes and times, peak rate 1.25 instead of 1.875 times
    the mean) is proved within it and certified."""
    spec, _ = robot()
    bound = (1.4, 1.4, 1.0)
    spec = dataclasses.replace(spec, input_bound=bound)
    free = dataclasses.replace(spec, input_bound=None)
    smooth = design_tube(dataclasses.replace(free, tube=dataclasses.replace(
        free.tube, method="via")))
    assert {s.profile for s in smooth.tube.segments} == {"smoothstep"}
    assert prove_input_bound(smooth.tube, spec).peak[0] > bound[0]
    design = design_tube(spec)
    assert design.method == "via" and design.certificate.passed
    assert {s.profile for s in design.tube.segments} == {"cruise"}
    assert design.input_proof.meets(bound)
    # the same via boxes and times as the smooth-step tube
    assert [(s.start, s.end, s.lower_to) for s in design.tube.segments] == [
        (s.start, s.end, s.lower_to) for s in smooth.tube.segments]


@pytest.mark.slow
def test_softer_circumvents_keep_the_papers_tube():
    """Where a softer circumvent suffices the design keeps the paper's method and slows
    the circumvent only (the sharpness is left to the design in this spec)."""
    spec = load_spec(SPECS / "actuator-softer-s3.toml")
    default = papers_default(spec)
    design = design_tube(spec)
    assert default.method == design.method == "paper"
    assert prove_input_bound(default.tube, spec).peak[0] > 3 * spec.input_bound[0]
    before = max(c.sharpness for c in default.tube.circumvents)
    after = {c.sharpness for c in design.tube.circumvents}
    assert len(after) == 1 and after.pop() > before
    assert design.input_proof.meets(spec.input_bound)


@pytest.mark.slow
def test_verify_proves_the_bound():
    spec, design = robot()
    report = verify(design)
    check = report["sampled.input_bound"]
    assert check.passed and report.passed, [str(c) for c in report.failed]
    assert check.data["inputs"] == ["v1", "v2", "omega"]
    # verify proves again, independently of the design, the peak the design proved
    assert check.data["peak"] == list(design.input_proof.peak)
    assert all(p <= b for p, b in zip(check.data["peak"], spec.input_bound))
    margin = 1 - max(p / b for p, b in zip(check.data["peak"], spec.input_bound))
    assert check.data["margin"] == pytest.approx(margin, rel=1e-12) and margin >= 0
    assert "|v2| <=" in check.detail


def test_verify_fails_a_tube_beyond_the_bound():
    """The default tube of the small task asks 3 m/s: against a bound of 1.5 the check
    fails and names the inputs beyond it."""
    spec = small((1.5, 1.5))
    default = design_tube(small(None))
    report = verify(dataclasses.replace(default, spec=spec))
    check = report["sampled.input_bound"]
    assert not check.passed and "beyond the bound in u1, u2" in check.detail
    # the peak verify proves is the one the design proves for that tube (a bound it
    # keeps, test_a_bound_the_default_design_meets_keeps_its_tube)
    peak = design_tube(small((3.5, 3.5))).input_proof.peak
    assert check.data["peak"] == list(peak) and min(peak) > 1.5
    assert check.data["margin"] == pytest.approx(1 - max(peak) / 1.5, rel=1e-12)


@pytest.mark.slow
def test_the_closed_loop_with_the_generated_c_stays_within_the_bound():
    spec, design = robot()
    result = simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_tube and result.clamped_steps == 0
    assert all(u <= b for u, b in zip(result.max_abs_u, spec.input_bound))
    assert set(result.trajectory.status) == {STATUS_OK}


def test_on_a_plant_of_the_assumptions_the_loop_stays_below_the_proved_peak():
    """The single integrator with the spec's disturbance is a plant of the default
    [assumptions]: its inputs stay below the proved peak, not only below the bound."""
    spec = small((3.5, 3.5))
    design = design_tube(spec)
    for seed in (0, 1, 2):
        result = simulate(design, backend="c", seed=seed)
        assert result.satisfied and result.clamped_steps == 0
        assert all(u <= p for u, p in zip(result.max_abs_u, design.input_proof.peak))


def test_the_clamp_acts_and_reports_on_a_tube_beyond_the_bound():
    """The default tube of the small task (proved peak 3.0 m/s) with a clamp below it: the
    generated C clamps and says so (STATUS_INPUT_CLAMPED), and |u| never exceeds the
    bound. A clamp a little below the peak leaves the state in the tube; far below it the
    saturated law loses the tube (reported OUTSIDE_TUBE): the clamp is a last line of
    defence, the guarantee is the design's."""
    spec = small(None)
    tube = design_tube(spec).tube
    near = run_closed_loop(spec, dataclasses.replace(tube, input_bound=(2.8, 2.8)),
                           backend="c")
    assert near.clamped_steps > 0 and STATUS_INPUT_CLAMPED in near.trajectory.status
    assert max(near.max_abs_u) == 2.8 and near.stayed_in_tube
    far = run_closed_loop(spec, dataclasses.replace(tube, input_bound=(1.5, 1.5)),
                          backend="c")
    assert far.clamped_steps > 0 and max(far.max_abs_u) == 1.5
    assert not far.stayed_in_tube and STATUS_OUTSIDE_TUBE in far.trajectory.status


def _works(message: str) -> float:
    found = re.search(r"prescribed_time = ([0-9.]+) s works", message)
    assert found, message
    return float(found.group(1))


def test_refusal_names_the_smallest_prescribed_time_that_works(capsys):
    with pytest.raises(DesignError) as info:
        design_tube(small((1.5, 1.5)))
    error = info.value
    assert error.kind is FailureKind.INPUT_BOUND and error.tried is not None
    message = str(error)
    assert "asks up to 3 of input u1 (bound 1.5)" in message
    works = _works(message)
    assert 3.0 < works < 9.0
    # it works there, and not at the two-significant-digit value below
    assert design_tube(small((1.5, 1.5), works)).input_proof.meets((1.5, 1.5))
    with pytest.raises(DesignError):
        design_tube(small((1.5, 1.5), round(works - 0.1, 1)))
    # or, at t_c = 3 s, the bound it names
    needs = re.search(r"or input_bound = \[([0-9.]+), ([0-9.]+)\]", message).groups()
    assert design_tube(small(tuple(map(float, needs)))).input_proof is not None


def test_refusal_when_no_prescribed_time_within_the_search_works():
    """0.05 m/s is below the disturbance bound (0.14 m/s): no prescribed_time works, and the
    refusal says how far it looked, with the bound the design within t_c needs."""
    with pytest.raises(DesignError) as info:
        design_tube(small((0.05, 0.05)))
    message = str(info.value)
    assert info.value.kind is FailureKind.INPUT_BOUND
    assert "no prescribed_time up to 48 s meets it" in message and "works (" not in message
    assert "input_bound = [3, 3] works with this prescribed_time" in message


def test_the_command_line(tmp_path, capsys):
    path = tmp_path / "small.toml"
    path.write_text(arena_toml("small", prescribed_time=3.0, extra=(
        '[tube]\nmethod = "paper"\n[controller]\nrate_hz = 200.0\n'
        "[actuator]\ninput_bound = [1.5, 1.5]\n")))
    assert main(["design", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: no design within prescribed_time")
    assert _works(err) > 3.0
    path.write_text(path.read_text().replace("[1.5, 1.5]", "[3.5, 3.5]"))
    assert main(["design", str(path)]) == 0
    peaks = ", ".join(f"|u{i + 1}| {p:.4g} <= 3.5"
                      for i, p in enumerate(design_tube(small((3.5, 3.5))).input_proof.peak))
    assert f"PASS  input bound: law (13) asks at most [{peaks}] (proved)" in capsys.readouterr().out
