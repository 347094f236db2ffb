"""The timing contract of the generated code: every variant's header and Python module
carry the period, the delay and the jitter the certificate covers (the spec's
``[controller]``), with the contract's words, and a generation with a delay compiles and
passes its self-test."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
import types

import pytest

import stt_codegen as stt

CASES = [("omnirobot-s1", 0.0002, 0.00001),     # law (13)
         ("office-base", 0.0005, 0.0),          # the look-ahead law
         ("second-order-s1", 0.0, 0.0)]         # the cascade (no delay in its certificate)


def _macro(header: str, prefix: str, name: str) -> float:
    found = re.search(rf"^#define {prefix}_{name} ([0-9.eE+-]+)f?$", header, flags=re.M)
    assert found is not None, name
    return float(found.group(1))


@pytest.mark.parametrize("case, delay, jitter", CASES)
def test_the_header_and_module_state_the_timing_the_proof_covers(tmp_path, case, delay,
                                                                 jitter):
    spec = stt.load_spec(case)
    design = stt.design_tube(spec)
    if delay or jitter:
        design = dataclasses.replace(design, spec=dataclasses.replace(spec, delay=delay,
                                                                      jitter=jitter))
    stt.generate(design, tmp_path / "out", precision="double")
    prefix = spec.c_name.upper()
    header = (tmp_path / "out" / f"{spec.c_name}.h").read_text()
    assert _macro(header, prefix, "PERIOD") == 1.0 / spec.rate_hz
    assert _macro(header, prefix, "DELAY") == delay
    assert _macro(header, prefix, "JITTER") == jitter
    assert "Timing contract" in header and "before the first u is applied" in header
    module = types.ModuleType("generated")
    exec((tmp_path / "out" / f"{spec.c_name}.py").read_text(), module.__dict__)
    assert (module.PERIOD, module.DELAY, module.JITTER) == (1.0 / spec.rate_hz, delay, jitter)
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler (Debian package gcc): the self-test is not run")
    run = subprocess.run(["make", "-s", "-C", str(tmp_path / "out"), "selftest"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip().splitlines()[-1].endswith(" 0 failed")


def test_the_single_precision_header_prints_float_literals(tmp_path):
    spec = stt.load_spec("omnirobot-s1")
    stt.generate(stt.design_tube(spec), tmp_path / "out", languages=["c"], precision="single")
    header = (tmp_path / "out" / f"{spec.c_name}.h").read_text()
    assert re.search(r"^#define OMNIROBOT_S1_PERIOD 0\.001f$", header, flags=re.M)


def test_the_design_document_states_the_timing():
    spec = dataclasses.replace(stt.load_spec("omnirobot-s1"), delay=0.00005, jitter=0.000001)
    timing = stt.design_tube(spec).to_json()["timing"]
    assert timing == {"rate_hz": 1000.0, "period_s": 0.001, "delay_s": 0.00005,
                      "jitter_s": 0.000001}
