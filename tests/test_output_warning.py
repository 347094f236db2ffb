"""A second-order or differential-drive design without ``[actuator]`` is warned that its
command is bounded only inside the declared class (design/output_bound.py): the proved peak
inside, and the deployed clamp's bound outside, which the deployed step reaches."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.design.output_bound import clamp_phi
from stt_codegen.tube import cascade_reference

CASES = Path(stt.__file__).parent / "cases"


def _free_office(tmp_path: Path) -> Path:
    """office-base without its [actuator] table."""
    text = (CASES / "office-base.toml").read_text()
    free = re.sub(r"\[actuator\]\ninput_bound = \[[^\]]*\]\n", "", text)
    assert free != text
    path = tmp_path / "office-free.toml"
    path.write_text(free)
    return path


def test_the_cascade_without_actuator_is_warned_with_its_proved_peak():
    design = design_of("second-order-s1")
    words = design.output_warning
    report = design.second_stage[1]["certificate"]
    for name, peak in zip(design.spec.input_names, report["peak_input"]):
        assert f"|{name}| <= {peak:.4g} N" in words
    assert "give [actuator] input_bound" in words


def test_the_cascades_clamp_bound_is_what_the_deployed_step_reaches():
    """Far outside the velocity tube the deployed step's force reaches ``2 k2 phi(E_MAX) /
    rho2`` (rho2 at its floor late in the run) and never more."""
    design = design_of("second-order-s1")
    stage = design.second_stage[0]
    n = design.tube.dimension
    clamp = [2.0 * stage.velocity_gain * clamp_phi() / f for f in stage.width_floor]
    t = np.array([200.0 / stage.decay])                      # rho2 = its floor
    x1 = 0.5 * (np.array(design.tube.segments[-1].lower_to)
                + np.array(design.tube.segments[-1].upper_to))
    for sign in (1.0, -1.0):
        x = np.concatenate([x1, np.full(n, sign * 1e6)])[None, :]
        u = cascade_reference.cascade_step(design.tube, stage, x, t, np.array([1e-3]),
                                           np.zeros((1, 2 * n)))[0][0]
        assert np.all(np.abs(u) <= np.array(clamp))
        assert np.all(np.abs(u) >= 0.999 * np.array(clamp))
    assert f"|F1| <= {clamp[0]:.3g} N" in design.output_warning


def test_the_differential_drive_without_actuator_is_warned(tmp_path):
    design = stt.design_tube(stt.load_spec(str(_free_office(tmp_path))))
    words = design.output_warning
    assert words.startswith("no [actuator] input_bound: the base's command (v, omega) is "
                            "proved |v| <= ")
    speed = (np.sqrt(2) * 4.0 * design.tube.gain * clamp_phi() / 1e-6)
    assert f"|omega| <= {speed / design.spec.drive.axle_offset:.3g}" in words


@pytest.mark.parametrize("name", ["omnirobot-s1", "office-base"])
def test_no_warning_for_the_first_order_or_with_actuator(name):
    design = design_of(name)
    assert design.output_warning is None
    assert design.to_json()["warnings"] == []


def test_design_and_its_json_print_the_warning():
    done = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", "second-order-s1"],
                          capture_output=True, text=True, check=True)
    assert "  warning: no [actuator] input_bound: the cascade's input u" in done.stdout
    done = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", "second-order-s1",
                           "--json"], capture_output=True, text=True, check=True)
    assert json.loads(done.stdout)["warnings"][0].startswith("no [actuator] input_bound")


def test_the_headers_state_the_clamps_bound_without_actuator(tmp_path):
    """The cascade's and the base's generated headers give the clamp's bound in words when
    no [actuator] bounds the command, and not when one does."""
    from stt_codegen.design.output_bound import base_clamp, cascade_clamp
    design = design_of("second-order-s1")
    header = (Path(__file__).parents[1] / "generated" / "second-order-s1" / "double"
              / "second_order_s1.h").read_text()
    clamp = ", ".join(f"{c:.3g}" for c in cascade_clamp(design.second_stage[0]))
    assert f"Whatever the inputs, |u_i| <= {clamp} (i = 0, 1, ...)" in header
    office = (Path(__file__).parents[1] / "generated" / "office-base" / "double"
              / "office_base.h").read_text()
    assert "Output bound:" not in office                    # [actuator]: clamped to it
    free = stt.design_tube(stt.load_spec(str(_free_office(tmp_path))))
    files = stt.generate(free, tmp_path / "out", languages=("c",))
    text = next(p for p in files if p.suffix == ".h").read_text()
    v, omega = base_clamp(free.tube.gain, free.spec.drive.axle_offset)
    assert f"|v| <= {v:.3g} m/s and |omega| <= {omega:.3g} rad/s" in text
