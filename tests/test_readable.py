"""Readable objects: a design, a run and a verification report say what they are in a few
lines (``summary()``, ``repr``, a notebook's Markdown), for every controller variant."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.proofs.check import Check, VerificationReport
from stt_codegen.spec.variants import variant_of

#: One bundled case of each controller variant.
VARIANT_CASES = {"first-order": "omnirobot-s1", "cascade": "second-order-s1",
                 "look-ahead": "office-base"}


@pytest.mark.parametrize("variant, name", VARIANT_CASES.items())
def test_a_design_summary_fits_a_screen_and_carries_its_figures(variant, name):
    design = design_of(name)
    assert variant_of(design.spec).name == variant
    text = design.summary()
    lines = text.splitlines()
    assert len(lines) <= 20 and max(map(len, lines)) <= 110
    assert lines[0].startswith(f"Design of {name}: {variant} ")
    assert f"the {design.method} method" in lines[0]
    assert f"gain k = {design.gain:.4g}, {design.tube.rate_hz:g} Hz" in text
    smallest = min(design.certificate.margins, key=lambda m: m.margin)
    assert re.search(rf"smallest margins: +{smallest.margin:.4g} {smallest.name} ", text)
    proved = sum(m.passed for m in design.certificate.margins)
    assert f"{proved} of {len(design.certificate.margins)} properties proved" in text
    for c in design.tube.circumvents[:3]:
        assert f"obstacle {c.obstacle}: x{c.dimension + 1} {c.side} side" in text
    if design.input_proof is not None:      # [actuator]: the proved peaks
        peaks = ", ".join(f"|{n}| {p:.4g} <= {b:g}" for n, p, b in zip(
            design.spec.input_names, design.input_proof.peak, design.spec.input_bound))
        assert re.search(rf"proved input peaks: +{re.escape(peaks)} ", text)
    short = repr(design)
    assert "\n" not in short and len(short) < 250
    assert short.startswith(f"Design(spec={name!r}, variant={variant!r}, ")
    assert f"certified={design.certificate.passed}" in short
    table = design._repr_markdown_()
    assert table.startswith(f"**Design of {name}") and "| controller |" in table


def test_the_variants_own_rows():
    """The cascade shows its certified second stage; the base its look-ahead point; law
    (13) on the plant's state neither."""
    cascade = design_of("second-order-s1")
    stage, derivation = cascade.second_stage
    assert f"k1 = {stage.position_gain:.4g}, k2 = {stage.velocity_gain:.4g}" in cascade.summary()
    peak = derivation["certificate"]["peak_input"][0]
    assert f"peak input |F1| {peak:.4g} N" in cascade.summary()
    base = design_of("office-base")
    assert f"look-ahead point:   l = {base.look_ahead.axle_offset:g} ahead" in base.summary()
    first = design_of("omnirobot-s1").summary()
    assert "second stage" not in first and "look-ahead" not in first


def test_a_run_reads_in_a_few_lines():
    design = design_of("omnirobot-s1")
    result = stt.simulate(design, backend="c", horizon=1.0)
    text = result.summary()
    assert len(text.splitlines()) <= 12
    assert text.splitlines()[0] == ("Run of omnirobot-s1 (backend c, 1000 steps): "
                                    "Definition 2.1 not satisfied")
    assert "not reached by t_c = 9 s" in text and "stayed inside" in text
    assert f"max |e| = {result.max_abs_e:.3g}" in text
    assert repr(result) == (f"SimulationResult(spec='omnirobot-s1', backend='c', "
                            f"satisfied=False, reached=False, stayed_in_tube=True, "
                            f"collision=False, steps=1000, max_abs_e={result.max_abs_e:.3g})")
    assert "| tube | stayed inside" in result._repr_markdown_()


def test_a_report_shows_its_failures_and_counts_the_rest():
    checks = tuple(Check(f"lemma3.3.part{k}", True, "proved") for k in range(4)) + (
        Check("tube.avoids_obstacle_0", False, "meets it at t = 2.1 s", {"margin": -0.2}),
        Check("tube.non-empty", True, "ok", {"margin": 0.5}),
        Check("sampled.tube_kept", True, "kept at 1000 Hz"))
    report = VerificationReport("corridor", checks)
    text = report.summary()
    assert text.splitlines()[0] == "corridor: 6 of 7 checks passed, 1 FAILED"
    assert "passed:          lemma3.3 4/4, tube 1/2, sampled 1/1" in text
    assert "FAIL:            tube.avoids_obstacle_0: meets it at t = 2.1 s" in text
    assert "smallest margin: -0.2 (tube.avoids_obstacle_0)" in text
    assert "PASS:            sampled.tube_kept: kept at 1000 Hz" in text
    assert "proved" not in text            # the lemmas' evidence is for --all
    assert repr(report) == "VerificationReport(spec='corridor', checks=7, passed=6, failed=1)"


def _verify(*options: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", "verify", "omnirobot-s1",
                           *options], capture_output=True, text=True, timeout=900)


@pytest.mark.slow
def test_verify_prints_the_summary_by_default_and_every_check_with_all():
    short, every = _verify(), _verify("--all")
    assert short.returncode == every.returncode == 0, short.stderr + every.stderr
    lines = short.stdout.splitlines()
    assert len(lines) <= 15, short.stdout
    count = every.stdout.count("\nPASS  ") + 1          # one line a check, then the total
    assert count > 40 and every.stdout.splitlines()[-1] == f"{count} passed, 0 failed"
    assert lines[0] == f"omnirobot-s1: {count} of {count} checks passed"
    assert "smallest margin:" in short.stdout and "sampled.tube_kept" in short.stdout
    assert short.stderr == every.stderr == ""        # not a terminal: no progress bar
