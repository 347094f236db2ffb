"""The firmware's closed loop applies the spec's computation delay as ``simulate`` does:
the program of ``stt-codegen embedded`` (single-precision controller, double plant),
compiled for the host with gcc, follows the delayed host run and not the undelayed one."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.embedded import look_ahead_loop, programs
from stt_codegen.runtime.state_split import positions


@pytest.fixture(scope="module", autouse=True)
def _gcc() -> None:
    if shutil.which("gcc") is None:
        pytest.skip("host C compiler missing: install the Debian package gcc")


def _law13_program(design) -> str:
    return programs.closed_loop_source(design.spec, design.tube, decimate=50)


def _look_ahead_program(design) -> str:
    return look_ahead_loop.closed_loop_program(design, design.spec.c_name, 0)


def _firmware_points(design, program, state_size, tmp_path) -> tuple[dict, str]:
    """The printed samples of the firmware's loop built for the host, as tube points."""
    spec = design.spec
    stt.generate(design, tmp_path, languages=["c"], precision="single")
    (tmp_path / "loop.c").write_text(program(design))
    build = subprocess.run(["gcc", "-O2", "-o", str(tmp_path / "loop"), str(tmp_path / "loop.c"),
                            str(tmp_path / f"{spec.c_name}.c"), "-I", str(tmp_path), "-lm"],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(tmp_path / "loop")], capture_output=True, text=True)
    states = programs.parse_closed_loop(run.stdout, spec.dimension, state_size).states
    return {k: positions(spec, np.array(x)[None])[0] for k, x in states.items()}, run.stdout


@pytest.mark.parametrize("case, delay, program, state_size", [
    ("omnirobot-s1", 0.0002, _law13_program, None),
    ("office-base", 0.0005, _look_ahead_program, 3)])
def test_the_firmware_loop_runs_the_delay_of_the_spec(tmp_path, case, delay, program,
                                                      state_size):
    design = stt.design_tube(stt.load_spec(case))
    late = dataclasses.replace(design, spec=dataclasses.replace(design.spec, delay=delay))
    points, stdout = _firmware_points(late, program, state_size, tmp_path)
    assert "satisfied=1" in stdout
    delayed = stt.simulate(late, backend="c")
    prompt = stt.simulate(design, backend="c")
    assert delayed.stayed_in_tube
    with_delay = max(np.max(np.abs(p - delayed.trajectory.x[k])) for k, p in points.items())
    without = max(np.max(np.abs(p - prompt.trajectory.x[k])) for k, p in points.items())
    # the float controller follows the double one closely; the delay moves the run by
    # more than ten times that
    assert 10 * with_delay < without, (with_delay, without)


@pytest.mark.parametrize("spec_file, program, state_size", [
    ("umaze-first-compensated.toml", _law13_program, None),
    pytest.param("kobuki-office-compensated.toml", _look_ahead_program, 3,
                 marks=pytest.mark.slow)])
def test_the_firmware_loop_runs_the_prediction_of_the_spec(tmp_path, spec_file, program,
                                                           state_size):
    """With [controller] compensate_delay the firmware calls P_predict before P_step: it
    follows the host's predicted run, not the same delay run without the prediction."""
    from pathlib import Path
    design = stt.design_tube(stt.load_spec(Path(__file__).parent / "specs" / spec_file))
    points, stdout = _firmware_points(design, program, state_size, tmp_path)
    assert "satisfied=1" in stdout
    predicted = stt.simulate(design, backend="c")
    unpredicted = stt.simulate(dataclasses.replace(design, spec=dataclasses.replace(
        design.spec, compensate_delay=False)), backend="c")
    assert predicted.stayed_in_tube
    with_prediction = max(np.max(np.abs(p - predicted.trajectory.x[k]))
                          for k, p in points.items())
    without = max(np.max(np.abs(p - unpredicted.trajectory.x[k])) for k, p in points.items())
    assert 10 * with_prediction < without, (with_prediction, without)
