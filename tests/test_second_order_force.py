"""Force limits for second-order plants: ``[actuator] input_bound`` bounds the physical
input ``u`` of the cascade, proved by its sampled-data certificate, clamped in the
generated code (docs/second-order.md, "Force limits")."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import pytest

import stt_codegen as stt
from stt_codegen.design.input_bound import InputProof
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.verify.actuator import input_bound_check

SPEC = Path(__file__).resolve().parent / "specs" / "umaze-cascade-force.toml"


@pytest.fixture(scope="module")
def design():
    return stt.design_tube(stt.load_spec(SPEC))


@pytest.mark.slow      # the design tries several certified stages
def test_the_bound_is_on_the_force_and_proved_by_the_certificate(design) -> None:
    """The U-maze at 1 kHz with the motors' range +-1: the second stage kept is certified
    with its peak |u_i| within the bound, the tube carries the bound (the generated code
    clamps u to it), and the design's proof is that certificate's peak."""
    bound = design.spec.input_bound
    assert bound == (1.0, 1.0) and design.tube.input_bound == bound
    stage, derivation = design.second_stage
    peak = derivation["certificate"]["peak_input"]
    assert all(p <= b for p, b in zip(peak, bound))
    assert design.input_proof.meets(bound) and list(design.input_proof.peak) == peak
    assert all(0.0 <= t <= design.input_proof.horizon for t in design.input_proof.time)
    assert design.to_json()["input_peak"]["margin"] > 0


@pytest.mark.slow      # the design tries several certified stages
def test_a_bound_below_the_certified_peak_is_refused_naming_what_works(design) -> None:
    """Below the certified peak, in the user's terms: the force needed, and that no longer
    prescribed_time lowers it enough (the drift and disturbance ask for it)."""
    peak = max(design.input_proof.peak)
    with pytest.raises(DesignError) as info:
        stt.design_tube(dataclasses.replace(design.spec, input_bound=(peak / 4,) * 2))
    message = str(info.value)
    assert info.value.kind.name == "INPUT_BOUND"
    assert "the cascade's input u" in message and "input_bound = [" in message


def test_the_input_bound_takes_one_entry_per_input() -> None:
    text = SPEC.read_text().replace("input_bound = [1.0, 1.0]", "input_bound = [1.0]")
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(__import__("tomllib").loads(text))
    assert info.value.field == "actuator.input_bound"


@pytest.mark.slow      # the design tries several certified stages
def test_the_verify_check_passes_and_fails_on_the_proved_peak(design) -> None:
    proof = design.input_proof
    check = input_bound_check(design.spec, proof)
    assert check.name == "cascade.input_bound" and check.passed
    assert "the cascade asks at most" in check.detail
    low = dataclasses.replace(design.spec, input_bound=tuple(p / 2 for p in proof.peak))
    failed = input_bound_check(low, proof)
    assert not failed.passed and "beyond the bound in u1, u2" in failed.detail
    unproved = InputProof(False, (float("inf"),) * 2, (0.0, 0.0), 0.0, reason="not certified")
    assert not input_bound_check(design.spec, unproved).passed


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_the_generated_cascade_keeps_the_bound_in_closed_loop(design) -> None:
    """The generated C with its clamp, on the spec's damped ball: satisfied in both tubes,
    |u| within the bound and never clamped (the certificate proved the clamp idle)."""
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_velocity_tube, result.to_json()
    assert all(u <= b for u, b in zip(result.max_abs_u, design.spec.input_bound))
    assert result.clamped_steps == 0
