"""Force limits of a second-order plant (docs/second-order.md, "Force limits"):
``[actuator] input_bound`` bounds the physical input ``u`` (force, torque), one entry per
input of the model; the design keeps only a second stage whose certified peak ``|u_i|`` is
within it, slows the tube or refuses naming the ``prescribed_time`` that works; ``verify``
reports ``cascade.input_bound``; the closed loop stays within the bound."""

from __future__ import annotations

import dataclasses
import re
import shutil
import tomllib
from functools import lru_cache
from pathlib import Path

import pytest
from conftest import arena_toml, design_of

import stt_codegen as stt
from stt_codegen.cli import main
from stt_codegen.design.cascade_gain import SHAPES, certified_stage
from stt_codegen.design.failures import FailureKind
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.spec.loader import parse_spec
from stt_codegen.verification.cascade import cascade_input_bound_check
from stt_codegen.design.certificate.cascade_sampled import cascade_check_of

UMAZE = Path(__file__).parent / "specs" / "umaze-cascade.toml"
#: The cheap task's rate: its tube is certified there with one shape, (1.0, 5, 4).
RATE = 300.0


def small_text(bound: tuple[float, float] | None, prescribed_time: float = 3.0,
               name: str = "small-force") -> str:
    """A cheap 2-D task for a 1 kg double integrator: no obstacle, the paper's tube only,
    300 Hz; its certified second stage asks up to about 76 N at t_c = 3 s (at the start,
    where the velocity tube is least filled)."""
    extra = (f'[tube]\nmethod = "paper"\n[controller]\nrate_hz = {RATE!r}\n'
             '[plant]\nmodel = "double-integrator"\nparameters = [1.0]\n'
             "disturbance_amplitude = 0.1\n[assumptions]\ninput_gain = [0.8, 1.25]\n")
    if bound is not None:
        extra += f"[actuator]\ninput_bound = [{bound[0]!r}, {bound[1]!r}]\n"
    return arena_toml(name, prescribed_time=prescribed_time, extra=extra)


def small(bound: tuple[float, float] | None, prescribed_time: float = 3.0):
    return parse_spec(small_text(bound, prescribed_time))


@lru_cache(maxsize=None)
def free_design():
    """The small task designed without ``[actuator]``: its certified peak force."""
    return stt.design_tube(small(None))


def free_peak() -> tuple[float, ...]:
    return tuple(free_design().second_stage[1]["certificate"]["peak_input"])


def with_actuator(raw: dict, bound: list) -> dict:
    return {**raw, "actuator": {"input_bound": bound}}


def bundled(name: str) -> dict:
    from stt_codegen.cases import bundled_spec_bytes
    return tomllib.loads(bundled_spec_bytes(name).decode())


# -- the spec ---------------------------------------------------------------------------

@pytest.mark.parametrize("case, count, names, unit", [
    ("second-order-s1", 2, ("F1", "F2"), "N"),
    ("second-order-quadrotor", 3, ("thrust_x", "thrust_y", "thrust_z"), "N"),
])
def test_one_bound_per_physical_input(case, count, names, unit):
    raw = bundled(case)
    spec = stt.Spec.from_dict(with_actuator(raw, [2.5] * count))
    assert spec.input_bound == (2.5,) * count
    assert spec.input_names == names and spec.input_unit == unit
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(with_actuator(raw, [2.5] * (count + 1)))
    assert info.value.field == "actuator.input_bound"
    assert f"must have {count} entries" in str(info.value)
    assert f"{', '.join(names)} in {unit}" in str(info.value)


def test_the_arms_torques_are_named_in_newton_metres():
    raw = tomllib.loads((Path(__file__).parent / "specs" / "arm-joints.toml").read_text())
    spec = stt.Spec.from_dict(with_actuator(raw, [3.0, 2.0]))
    assert spec.input_names == ("tau1", "tau2") and spec.input_unit == "N m"
    with pytest.raises(SpecError, match=r"tau1, tau2 in N m\), got 1"):
        stt.Spec.from_dict(with_actuator(raw, [3.0]))


@pytest.mark.parametrize("bound, field, reason", [
    ([1.0, 0.0], "actuator.input_bound[1]", "must be positive"),
    ([-1.0, 1.0], "actuator.input_bound[0]", "must be positive"),
    ([1.0, float("inf")], "actuator.input_bound[1]", "must be finite"),
    ([1.0, "1"], "actuator.input_bound[1]", "must be a number"),
    ([], "actuator.input_bound", ""),
])
def test_a_bad_bound_names_the_field_and_the_reason(bound, field, reason):
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(with_actuator(bundled("second-order-s1"), bound))
    assert info.value.field == field and reason in str(info.value)


def test_a_bad_bound_exits_2_without_traceback(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(small_text(None) + "[actuator]\ninput_bound = [1.0, 2.0, 3.0]\n")
    assert main(["design", str(path)]) == 2
    err = capsys.readouterr().err
    assert "actuator.input_bound" in err and "F1, F2 in N" in err and "Traceback" not in err


# -- the design -------------------------------------------------------------------------

def test_a_bound_above_the_certified_peak_keeps_the_design_and_carries_the_bound():
    peak = free_peak()
    bound = tuple(round(1.05 * p, 1) for p in peak)
    design = stt.design_tube(small(bound))
    stage, derivation = design.second_stage
    assert derivation["certificate"]["passed"]
    # the same tube and stage as without the bound; the bound travels with the tube (the
    # generated cascade clamps u to it) and the design carries the proof
    assert design.tube == dataclasses.replace(free_design().tube, input_bound=bound)
    assert stage == free_design().second_stage[0]
    assert design.input_proof.peak == peak and design.input_proof.meets(bound)
    assert design.to_json()["input_bound"] == list(bound)


def _works(message: str) -> float:
    found = re.search(r"prescribed_time = ([0-9.]+) s works", message)
    assert found, message
    return float(found.group(1))


def test_refusal_names_a_prescribed_time_that_designs():
    bound = (40.0, 40.0)
    peak = free_peak()
    assert min(peak) > 40.0                  # the default design asks for more
    with pytest.raises(DesignError) as info:
        stt.design_tube(small(bound))
    error = info.value
    assert error.kind is FailureKind.INPUT_BOUND
    message = str(error)
    # in the user's words: the cascade's input, in newtons, the input's name
    assert "keeps the cascade's input u within actuator.input_bound = [40 N, 40 N]" in message
    assert f"asks up to {max(peak):.3g} N of input F" in message
    works = _works(message)
    assert works > 3.0
    design = stt.design_tube(small(bound, works))
    assert design.input_proof.meets(bound)
    certificate = design.second_stage[1]["certificate"]
    assert certificate["passed"]
    assert all(p <= b for p, b in zip(certificate["peak_input"], bound))
    assert design.spec.prescribed_time == works


@pytest.mark.slow
def test_the_named_prescribed_time_is_the_smallest_on_the_grid():
    with pytest.raises(DesignError) as info:
        stt.design_tube(small((40.0, 40.0)))
    works = _works(str(info.value))
    with pytest.raises(DesignError):
        stt.design_tube(small((40.0, 40.0), round(works - 0.1, 1)))


def test_second_stage_for_refuses_a_tube_whose_stages_exceed_the_bound():
    """A tube designed without the bound, paired with a spec whose bound is below every
    certified peak: the second stage is refused for the force, not for the rate."""
    design = dataclasses.replace(free_design(), spec=small((1.0, 1.0)))
    with pytest.raises(DesignError) as info:
        design.second_stage
    assert info.value.kind is FailureKind.INPUT_BOUND
    assert "actuator.input_bound = [1 N, 1 N]" in str(info.value)


def test_a_shape_that_cannot_beat_the_lowest_ratio_stops_and_the_lowest_is_kept():
    """With a bound no shape keeps (and advice wanted), a shape after one that keeps the
    tubes stops where its input passes the lowest peak-to-bound ratio so far times the
    bound (``second-order-s1``, whose tube every shape keeps, at 1 N): some are cut short,
    and the lowest ratio and its peaks are those of the shapes run whole (each certified
    alone, without a limit)."""
    from stt_codegen.design.cascade_gain import cascade_input_proof, derived_second_stage
    from stt_codegen.design.certificate.cascade_sampled import certify_stage
    design = design_of("second-order-s1")
    bound = (1.0, 1.0)
    free, spec = (dataclasses.replace(design.spec, input_bound=b) for b in (None, bound))
    order = free.second_order
    whole = []
    for shape in SHAPES:
        stage, _ = derived_second_stage(design.tube, design.check.min_width, order.input_gain,
                                        order.drift_bound + free.disturbance_amplitude,
                                        order.initial_velocity, shape)
        passed, report = certify_stage(design.tube, free, stage)
        assert passed
        whole.append(report["peak_input"])
    assert min(max(p) for p in whole) > 1.0                  # kept by all, bound by none
    stage, derivation = certified_stage(design.tube, spec, design.check.min_width, bound)
    assert stage is None and len(derivation["tried"]) == len(SHAPES)
    cut = [t for t in derivation["tried"] if not t["passed"]]
    assert len(cut) >= 3
    lowest = min(whole, key=max)
    for t in cut:                                            # stopped above the lowest ratio
        assert max(t["peak_input"]) > max(lowest)
    proof = cascade_input_proof(design.tube, spec, design.check.min_width)
    assert list(proof.peak) == list(lowest)


# -- verify -----------------------------------------------------------------------------

def test_verify_check_passes_with_the_certified_peak_and_its_margin():
    bound = (80.0, 80.0)
    design = stt.design_tube(small(bound))
    check = cascade_input_bound_check(design.spec, design.tube, design.check.min_width)
    assert check.passed and check.name == "cascade.input_bound"
    stage, _ = design.second_stage
    certificate = cascade_check_of(design.tube, design.spec, stage)
    assert check.data["peak"] == list(certificate.peak_input) == list(design.input_proof.peak)
    assert check.data["margin"] == pytest.approx(
        min((b - p) / b for p, b in zip(certificate.peak_input, bound)), rel=1e-12)
    assert check.data["inputs"] == ["F1", "F2"] and check.data["unit"] == "N"
    assert "|F1| <=" in check.detail and "(bound 80 N" in check.detail


def test_verify_check_fails_a_bound_below_the_certified_peak():
    peak = free_peak()
    bound = (0.9 * min(peak), 0.9 * min(peak))
    design = free_design()
    check = cascade_input_bound_check(small(bound), design.tube, design.check.min_width)
    assert not check.passed
    assert check.data["peak"] == list(peak)
    assert check.data["margin"] < 0
    assert "beyond the bound in F1, F2" in check.detail


@pytest.mark.slow
def test_verify_exits_0_and_reports_the_bound(tmp_path, capsys):
    path = tmp_path / "small.toml"
    path.write_text(small_text((80.0, 80.0)))
    assert main(["verify", str(path), "--all"]) == 0
    assert "PASS  cascade.input_bound: the cascade asks at most |F1| <=" in (
        capsys.readouterr().out)
    report = stt.verify(stt.design_tube(small((80.0, 80.0))))
    assert report.passed and report["cascade.input_bound"].passed


# -- the closed loop --------------------------------------------------------------------

@pytest.mark.slow
def test_the_closed_loop_stays_within_the_certified_peak_and_the_bound():
    bound = (80.0, 80.0)
    design = stt.design_tube(small(bound))
    for seed in (0, 1):
        result = stt.simulate(design, backend="reference", seed=seed)
        assert result.satisfied and result.stayed_in_tube
        assert all(u <= p <= b for u, p, b in zip(result.max_abs_u, design.input_proof.peak,
                                                   bound))


# -- the U-maze (PointMaze) at 1 kHz ----------------------------------------------------

def umaze(bound: list[float], rate_hz: float = 1000.0):
    raw = tomllib.loads(UMAZE.read_text())
    raw["controller"]["rate_hz"] = rate_hz
    return stt.Spec.from_dict(with_actuator(raw, bound))


@pytest.mark.slow
def test_umaze_with_a_one_newton_bound_is_certified_within_it():
    """The acceptance case: ``input_bound = [1, 1]`` at 1 kHz. Certified, the certified
    peak within 1 N; the damped member of the class (``f = -c x2``, the adversary of
    tests/test_cascade_sampled.py) and the spec's own plant stay within it."""
    from test_cascade_sampled import adversary_run

    from stt_codegen.design.certificate.cascade_sampled import cascade_class
    design = stt.design_tube(umaze([1.0, 1.0]))
    stage, derivation = design.second_stage
    certificate = derivation["certificate"]
    assert certificate["passed"]
    assert all(p <= 1.0 for p in certificate["peak_input"])
    assert design.tube.input_bound == (1.0, 1.0)
    _, _, u_damped = adversary_run(design, stage, cascade_class(design.spec), "damping")
    assert u_damped <= max(certificate["peak_input"]) <= 1.0
    result = stt.simulate(design, backend="reference")
    assert result.satisfied and max(result.max_abs_u) <= 1.0


@pytest.mark.slow
def test_umaze_a_bound_below_the_first_shapes_peak_takes_a_later_shape():
    """Between the certified peaks of two shapes: the first shape (certified, beyond the
    bound) is passed over for a later certified one within it."""
    free = stt.design_tube(umaze([1.0, 1.0]))
    first = max(free.second_stage[1]["certificate"]["peak_input"])
    spec = umaze([0.95 * first, 0.95 * first])
    design = stt.design_tube(spec)
    stage, derivation = design.second_stage
    assert derivation["shape"] != list(SHAPES[0])
    assert all(p <= b for p, b in zip(derivation["certificate"]["peak_input"],
                                      spec.input_bound))
    # the first shape is certified on this tube, and beyond the bound
    _, tried = certified_stage(design.tube, spec, design.check.min_width, (0.0, 0.0))
    assert tried["tried"][0]["passed"] and max(tried["tried"][0]["peak_input"]) > 0.95 * first


@pytest.mark.slow
def test_umaze_at_100_hz_with_a_bound_is_refused_for_the_rate_naming_one():
    """No second stage keeps the tubes at 100 Hz, bound or not: the refusal is the rate's
    (kind SAMPLING_RATE, naming a certified rate), not the bound's."""
    with pytest.raises(DesignError) as info:
        stt.design_tube(umaze([1.0, 1.0], rate_hz=100.0))
    assert info.value.kind is FailureKind.SAMPLING_RATE
    named = re.search(r"controller\.rate_hz = ([0-9.]+) is certified", str(info.value))
    assert named is not None
    assert info.value.advice["controller.rate_hz"] == float(named.group(1))


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_the_generated_cascade_with_its_clamp_keeps_the_bound_in_closed_loop():
    """The U-maze at 1 kHz with the motors' range as the bound, its generated C (which
    clamps u) on the spec's damped ball: satisfied in both tubes, within the bound, never
    clamped (the certificate proved the clamp idle)."""
    spec_file = Path(__file__).resolve().parent / "specs" / "umaze-cascade-force.toml"
    design = stt.design_tube(stt.load_spec(spec_file))
    assert design.tube.input_bound == design.spec.input_bound == (1.0, 1.0)
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_velocity_tube, result.to_json()
    assert all(u <= b for u, b in zip(result.max_abs_u, design.spec.input_bound))
    assert result.clamped_steps == 0


@pytest.mark.slow
def test_a_rate_that_keeps_the_tubes_but_not_the_bound_is_not_named_certified():
    """The hovercraft at 500 Hz with 1 N thrusters: the cascade's rate search finds a rate
    for the tubes, at which no design keeps the bound; the refusal says so, advises no
    rate, and the prescribed_time it names is then certified with the bound."""
    spec = stt.load_spec(str(Path(__file__).parent / "specs" / "hovercraft-force.toml"))
    with pytest.raises(DesignError) as info:
        stt.design_tube(spec)
    words = str(info.value)
    rate = re.search(r"controller\.rate_hz = ([0-9.]+) keeps the tubes but no design there "
                     r"keeps actuator\.input_bound", words)
    assert rate is not None, words
    assert "controller.rate_hz" not in info.value.advice
    with pytest.raises(DesignError):          # the rate is as the refusal says
        stt.design_tube(dataclasses.replace(spec, rate_hz=float(rate.group(1))))
    later = info.value.advice["prescribed_time"]
    assert f"prescribed_time = {later:g} s is certified" in words
    design = stt.design_tube(dataclasses.replace(spec, prescribed_time=later))
    assert design.certificate.passed and design.input_proof.meets(spec.input_bound)


@pytest.mark.slow
def test_a_bound_a_task_spec_cannot_keep_names_its_windows_not_a_later_deadline():
    """With [[tasks]] the legs are timed by the tasks' windows; where none of them ends at
    prescribed_time (tasks-visit's end at 5 and 9 s of 13 s) a later deadline moves none:
    the refusal says that a later prescribed_time does not slow them, and names none."""
    data = bundled("tasks-visit")
    data["actuator"] = {"input_bound": [0.05, 0.05, 0.05]}
    with pytest.raises(DesignError) as info:
        stt.design_tube(stt.Spec.from_dict(data))
    assert info.value.kind is FailureKind.INPUT_BOUND
    assert ("a longer prescribed_time does not slow the legs: their times are the "
            "[[tasks]] windows") in str(info.value)
    assert "prescribed_time" not in info.value.advice


def test_a_cascade_tries_via_points_timed_for_the_force_and_a_first_order_spec_does_not():
    """The cascade's input is a force: the design within [actuator] also tries via points
    whose moves are timed for the acceleration (docs/second-order.md, "Force limits"); law
    (13)'s input is a velocity, so a first-order spec does not."""
    from types import SimpleNamespace

    from stt_codegen.design.actuator import slower_variants
    default = SimpleNamespace(method="via", tube=SimpleNamespace(circumvents=()))
    cascade = dict(slower_variants(stt.load_spec(UMAZE), default))
    assert cascade["via points timed for the force"].tube.via_timing == "acceleration"
    assert cascade["via points timed for the force"].tube.method == "via"
    first = dict(slower_variants(stt.load_spec("omnirobot-s1"), default))
    assert "via points timed for the force" not in first
    assert all(v.tube.via_timing == "length" for v in first.values())


def _stay_then_target(prescribed_time: float) -> dict:
    """stlpy's EitherOr as a double integrator with its bounds (|u| <= 0.5 N, |v| <= 1 m/s):
    stay 5 s in either box within the run, then the target, around one obstacle."""
    return {"name": "either-or-force", "prescribed_time": prescribed_time,
            "state_space": {"lower": [0.0, 0.0], "upper": [10.0, 10.0],
                            "velocity_bound": [1.0, 1.0]},
            "initial": {"lower": [1.9, 1.9], "upper": [2.1, 2.1], "state": [2.0, 2.0]},
            "target": {"lower": [7.0, 8.0], "upper": [8.0, 9.0]},
            "obstacles": [{"lower": [3.0, 4.0], "upper": [5.0, 6.0]}],
            "tasks": [{"kind": "stay", "window": [0.0, prescribed_time], "duration": 5.0,
                       "any_of": [{"lower": [1.0, 6.0], "upper": [2.0, 7.0]},
                                  {"lower": [7.0, 4.5], "upper": [8.0, 5.5]}]}],
            "plant": {"model": "double-integrator", "parameters": [1.0]},
            "actuator": {"input_bound": [0.5, 0.5]}}


@pytest.mark.slow
def test_s_curve_legs_keep_a_bound_the_smooth_step_legs_exceed(monkeypatch):
    """At 26 s (1.3 times stlpy's horizon) the accepted design's moving legs are S-curves
    (peak acceleration 4.76 D / T^2); with the S-curve candidates and the blended corners
    taken away the design is refused for the force: the smooth-step legs (5.77 D / T^2)
    stopped at their corners are proved to ask more than 0.5 N with every second-stage
    shape. (At 28 s the smooth-step legs are certified with the slow outer loop of the
    last shapes.)"""
    import stt_codegen.design.actuator as actuator
    spec = stt.Spec.from_dict(_stay_then_target(26.0))
    design = stt.design_tube(spec)
    assert design.certificate.passed and design.input_proof.meets(spec.input_bound)
    assert {s.profile for s in design.tube.segments if s.lower_from != s.lower_to} == {
        "scurve"}
    real = actuator.slower_variants
    monkeypatch.setattr(actuator, "slower_variants", lambda spec, default, bound=None: [
        (label, variant) for label, variant in real(spec, default, bound)
        if variant.tube.via_profile != "scurve" and variant.tube.via_corners != "blend"])
    with pytest.raises(DesignError) as info:
        stt.design_tube(dataclasses.replace(spec))
    assert info.value.kind is FailureKind.INPUT_BOUND


@pytest.mark.slow
def test_task_legs_timed_for_the_force_keep_a_bound_the_cruise_legs_exceed(monkeypatch):
    """At 30 s (1.5 times stlpy's horizon) the cruise legs (timed by length) are proved to
    ask more than 0.5 N; the legs timed for the acceleration (smooth steps, each move's
    time by the square root of its length) are certified within it. (At 40 s the cruise
    legs are certified too, since the change of ``r`` is bounded with its causes
    together.)"""
    import stt_codegen.design.actuator as actuator
    spec = stt.Spec.from_dict(_stay_then_target(30.0))
    design = stt.design_tube(spec)
    assert design.certificate.passed and design.input_proof.meets(spec.input_bound)
    moving = {s.profile for s in design.tube.segments if s.lower_from != s.lower_to}
    assert moving == {"smoothstep"}
    real = actuator.variant_of
    monkeypatch.setattr(actuator, "variant_of",
                        lambda owner: dataclasses.replace(real(owner), via_timing="length"))
    with pytest.raises(DesignError) as info:
        stt.design_tube(spec)
    assert info.value.kind is FailureKind.INPUT_BOUND
