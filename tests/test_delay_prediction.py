"""The delay-compensating prediction (``[controller] compensate_delay``): the spec's rules, its
certificate (which passes where the plain law's cannot and fails where it should), the closed
loop that runs it, and the generated ``predict`` of C and Python, bit for bit the CasADi
model's (docs/sampled-data.md, "Compensating a delay")."""

from __future__ import annotations

import ctypes
import dataclasses
import re
import shutil
import subprocess
import types
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from codegen_helpers import COMPILERS, compile_shared, write

import control as ct

import stt_codegen as stt
from stt_codegen.cli import main
from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.codegen.render import c_identifier
from stt_codegen.design.certificate.plant_class import plant_class
from stt_codegen.design.certificate.sampled import (check_sampled_first_per_axis,
                                                    largest_delay)
from stt_codegen.design.prediction import delay_predictor, mid_gain
from stt_codegen.design.samples import sample_tube
from stt_codegen.runtime.state_split import initial_state
from stt_codegen.tube import cascade_reference, look_ahead_reference, reference
from stt_codegen.tube.parameters import Status

SPECS = Path(__file__).parent / "specs"
BASE = SPECS / "kobuki-office-compensated.toml"       # differential drive, 50 Hz, 20 ms
FIRST = SPECS / "umaze-first-compensated.toml"        # first order, 100 Hz, 10 ms
CASCADE = SPECS / "umaze-cascade-compensated.toml"    # the cascade, 400 Hz, 2.5 ms
CASCADE = SPECS / "umaze-cascade-compensated.toml"    # the cascade, 400 Hz, 2.5 ms


@lru_cache(maxsize=None)
def _design(path: Path):
    return stt.design_tube(stt.load_spec(path))


def _check(design, delay: float, compensate: bool):
    with reference.numpy_math():
        return check_sampled_first_per_axis(design.tube, sample_tube(design.tube),
                                            plant_class(design.spec), delay=delay,
                                            compensate=compensate)


# ---------------------------------------------------------------------- the spec's rules
@pytest.mark.parametrize("source, edit, field", [
    ("second-order-s1", "delay = 0.0005\njitter = 0.0001\ncompensate_delay = true",
     "controller.jitter"),
    ("kobuki", "compensate_delay = true", "controller.compensate_delay"),
    ("kobuki", "delay = 0.02\njitter = 0.001\ncompensate_delay = true", "controller.jitter"),
    ("kobuki", "delay = 0.03\ncompensate_delay = true", "controller.delay"),
])
def test_the_loader_refuses_a_compensation_it_cannot_prove(tmp_path, source, edit, field,
                                                            capsys):
    if source == "kobuki":
        text = (SPECS / "kobuki-office.toml").read_text().replace(
            "rate_hz = 50.0\n", f"rate_hz = 50.0\n{edit}\n")
    else:
        text = (Path(stt.__file__).parent / "cases" / f"{source}.toml").read_text()
        assert "[controller]\n" in text
        text = text.replace("[controller]\n", f"[controller]\n{edit}\n")
    path = tmp_path / "spec.toml"
    path.write_text(text)
    with pytest.raises(stt.SpecError) as raised:
        stt.load_spec(path)
    assert raised.value.field == field
    # on the command line: exit code 2, the field named, no traceback
    assert main(["design", str(path)]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err


def test_a_delay_beyond_the_plain_limit_names_compensate_delay(tmp_path) -> None:
    text = (SPECS / "kobuki-office.toml").read_text().replace(
        "rate_hz = 50.0\n", "rate_hz = 50.0\ndelay = 0.03\n")
    (tmp_path / "spec.toml").write_text(text)
    with pytest.raises(stt.SpecError, match="compensate_delay covers a delay up to one period"):
        stt.load_spec(tmp_path / "spec.toml")


# ---------------------------------------------------------------------- the certificate
@pytest.mark.parametrize("path", [BASE, FIRST])
def test_a_one_period_delay_is_certified_with_the_prediction_and_not_without(path) -> None:
    design = _design(path)
    spec, dt = design.spec, 1.0 / design.tube.rate_hz
    assert spec.compensate_delay and spec.delay == pytest.approx(dt)
    predicted = _check(design, spec.delay, True)
    assert predicted.passed and predicted.data["compensate_delay"]
    assert predicted.level < 1.0 and predicted.margin > 0.0
    # the plain law with the same design: a whole period is beyond its check (at half of it
    # too, for these plants)
    assert not _check(design, 0.5 * dt, False).passed


def test_the_predicted_check_can_fail_and_reports_where() -> None:
    """omnirobot-s1 at 1 kHz (g in [0.362, 1]): the prediction's miss grows with the gain's
    spread; half a period is proved, a whole period is not."""
    design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    dt = 1.0 / design.tube.rate_hz
    assert _check(design, 0.5 * dt, True).passed
    failed = _check(design, dt, True)
    assert not failed.passed and failed.margin < 0.0
    assert "may leave the tube in dimension" in failed.reason


@pytest.mark.slow
def test_the_largest_predicted_delay_fails_when_doubled() -> None:
    spec = dataclasses.replace(stt.load_spec("omnirobot-s1"), compensate_delay=True)
    design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    dt = 1.0 / design.tube.rate_hz
    largest = largest_delay(design.tube, spec)
    plain = largest_delay(design.tube, stt.load_spec("omnirobot-s1"))
    assert largest is not None and plain is not None
    assert 2.0 * plain < largest < dt        # the prediction proves more than twice as much
    assert _check(design, largest, True).passed
    assert not _check(design, min(2.0 * largest, dt), True).passed


@pytest.mark.slow
def test_the_plain_refusal_names_compensate_delay_which_then_designs(tmp_path) -> None:
    text = (SPECS / "kobuki-office.toml").read_text().replace(
        "rate_hz = 50.0\n", "rate_hz = 50.0\ndelay = 0.02\n")
    (tmp_path / "spec.toml").write_text(text)
    with pytest.raises(stt.DesignError) as refused:
        stt.design_tube(stt.load_spec(tmp_path / "spec.toml"))
    assert "controller.compensate_delay = true is certified" in str(refused.value)
    assert refused.value.advice == {"controller.compensate_delay": True}


# ---------------------------------------------------------------------- the closed loop
@pytest.mark.parametrize("path", [pytest.param(BASE, marks=pytest.mark.slow), FIRST])
def test_the_closed_loop_with_the_delay_keeps_its_tube_and_its_bound(path) -> None:
    design = _design(path)
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and run.stayed_in_tube and run.max_abs_e < 1.0
    assert set(run.trajectory.status.tolist()) == {int(Status.OK)}
    bound = design.spec.input_bound
    if bound is not None:
        assert np.all(np.abs(run.trajectory.u) <= np.array(bound))


def test_the_loop_runs_the_prediction() -> None:
    """Without the prediction the same loop, with the same delay, runs another trajectory."""
    design = _design(FIRST)
    plain = dataclasses.replace(design, spec=dataclasses.replace(design.spec,
                                                                 compensate_delay=False))
    with_prediction = stt.simulate(design, backend="reference", horizon=1.0)
    without = stt.simulate(plain, backend="reference", horizon=1.0)
    assert not np.array_equal(with_prediction.trajectory.u, without.trajectory.u)


def test_the_interconnected_loop_gives_simulates_run_with_the_prediction() -> None:
    design = _design(BASE)
    controller = stt.controller_system(design, backend="reference")
    plant = stt.sampled_plant(design)
    states, inputs = plant.nstates, plant.ninputs
    assert controller.nstates == 2 * 2 + inputs      # alpha, then the held command
    loop = ct.interconnect(
        [controller, plant], inplist=[],
        connections=[*([f"stt.x[{i}]", f"plant.x[{i}]"] for i in range(3)),
                     *([f"plant.u[{j}]", f"stt.u[{j}]"] for j in range(inputs))],
        outlist=[*(f"plant.x[{i}]" for i in range(3)), *(f"stt.u[{j}]" for j in range(inputs)),
                 "stt.status"])
    steps = 100
    dt = controller.dt
    x0 = np.concatenate([np.zeros(controller.nstates), initial_state(design.spec),
                         np.zeros(states - 3)])
    response = ct.input_output_response(loop, np.arange(steps + 1) * dt, 0, X0=x0)
    run = stt.simulate(design, backend="reference", horizon=steps * dt)
    assert np.max(np.abs(response.outputs[3:3 + inputs].T - run.trajectory.u)) <= 1e-12
    assert np.array_equal(response.outputs[-1], run.trajectory.status.astype(float))


# ---------------------------------------------------------------------- the generated code
def _points(count: int, size: tuple[int, int], seed: int):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-3.0, 3.0, size[0]), rng.uniform(-2.0, 2.0, size[1]))
            for _ in range(count)]


def _oracle(design, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The numpy oracle's prediction of ``x`` over the spec's delay, for each variant."""
    spec = design.spec
    if spec.variant == "cascade":
        return cascade_reference.predicted_state(x[None], u[None], spec.delay,
                                                 mid_gain(spec))[0]
    step = spec.delay * mid_gain(spec)
    if spec.variant == "look-ahead":
        return look_ahead_reference.predicted_pose(x[None], u[None],
                                                   design.stage.axle_offset, step)[0]
    return reference.predicted_state(x, u, step)


@pytest.mark.skipif(not COMPILERS, reason="needs a C compiler: apt install gcc")
@pytest.mark.parametrize("path", [BASE, FIRST, CASCADE])
def test_the_generated_predict_is_the_models_bit_for_bit_and_the_oracles(tmp_path,
                                                                          path) -> None:
    """Every variant's generated predict, in double C and in Python, is the CasADi
    predictor's bit for bit, and within 1e-14 of the numpy oracle's."""
    design = _design(path)
    spec = design.spec
    stt.generate(design, tmp_path / "out", ("c", "python"))
    prefix = c_identifier(spec.c_name)
    predictor = delay_predictor(spec, design.tube, design.stage)
    assert predictor is not None
    lib = ctypes.CDLL(str(compile_shared(tmp_path / "out", prefix, COMPILERS[0], "double")))
    real_p = ctypes.POINTER(ctypes.c_double)
    predict = getattr(lib, f"{prefix}_predict")
    predict.argtypes, predict.restype = [real_p, real_p, real_p], ctypes.c_int
    module = types.ModuleType(prefix)
    exec((tmp_path / "out" / f"{prefix}.py").read_text(), module.__dict__)
    states, inputs = initial_state(spec).size, spec.dimension
    for x, u in _points(100, (states, inputs), seed=11):
        x_hat = np.zeros(states)
        code = predict(x.ctypes.data_as(real_p), u.ctypes.data_as(real_p),
                       x_hat.ctypes.data_as(real_p))
        model = np.array(predictor(x, u)).ravel()
        py_hat, py_code = module.predict(list(x), list(u))
        assert code == py_code == int(Status.OK)
        assert np.array_equal(x_hat, model) and np.array_equal(py_hat, model)
        np.testing.assert_allclose(x_hat, _oracle(design, x, u), rtol=1e-14, atol=1e-14)
    # a non-finite entry: INVALID_INPUT and a zero x_hat, in C and in Python
    x, u = np.full(states, np.nan), np.zeros(inputs)
    x_hat = np.ones(states)
    assert predict(x.ctypes.data_as(real_p), u.ctypes.data_as(real_p),
                   x_hat.ctypes.data_as(real_p)) == int(Status.INVALID_INPUT)
    assert not x_hat.any()
    assert module.predict(list(x), list(u)) == ([0.0] * states, int(Status.INVALID_INPUT))


def test_a_spec_without_compensation_generates_no_predict() -> None:
    spec = stt.load_spec("omnirobot-s1")
    design = stt.design_tube(spec)
    files = generate_files(spec, design.tube, Options(("c", "python"), "double"))
    assert not any(b"predict" in data for data in files.values())


def test_the_single_precision_predict_compiles_strictly(tmp_path) -> None:
    if not COMPILERS:
        pytest.skip("needs a C compiler: apt install gcc")
    design = _design(FIRST)
    files = generate_files(design.spec, design.tube, Options(("c",), "single"))
    folder = write(tmp_path, files)
    compile_shared(folder, c_identifier(design.spec.c_name), COMPILERS[0], "single")


@pytest.mark.skipif(shutil.which("cppcheck") is None,
                    reason="cppcheck missing: install the Debian package cppcheck")
@pytest.mark.parametrize("path, precision", [(FIRST, "double"),
                                             pytest.param(BASE, "single",
                                                          marks=pytest.mark.slow),
                                             pytest.param(CASCADE, "double",
                                                          marks=pytest.mark.slow)])
def test_the_generated_predict_keeps_misra_clean(tmp_path, path, precision) -> None:
    """cppcheck's MISRA C:2012 addon finds in P_predict only the API's own deviation
    (tests/test_codegen_misra.py: an API function the file does not call)."""
    from test_codegen_misra import DEVIATIONS
    design = _design(path)
    prefix = c_identifier(design.spec.c_name)
    folder = tmp_path / "gen"
    stt.generate(design, folder, ("c",), precision)
    proc = subprocess.run(["cppcheck", "--enable=all", "--addon=misra", "--std=c99",
                           "--suppress=missingIncludeSystem", "--quiet",
                           "--template={file}:{line}:{id}", f"{prefix}.c"],
                          cwd=folder, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    unused = set()
    for name, line, check in (f.split(":") for f in proc.stderr.splitlines()
                              if f.count(":") >= 2):
        text = (folder / name).read_text().splitlines()[int(line) - 1]
        assert any(d[0] == check and re.search(d[1], text) for d in DEVIATIONS), \
            f"{name}:{line}: {check}: {text!r}"
        if check == "unusedFunction":
            unused.add(re.match(rf"^int {prefix}_(\w+)\(", text).group(1))
    assert "predict" in unused                  # it is there, and clean


def _office_at_50_hz(tmp_path, extra: str) -> Path:
    """The bundled office-base at 50 Hz with a 20 ms delay (and ``extra`` in
    [controller])."""
    text = (Path(stt.__file__).parent / "cases" / "office-base.toml").read_text()
    text = re.sub(r"rate_hz = [0-9.]+", "rate_hz = 50.0", text)
    text = text.replace("[controller]\n", f"[controller]\ndelay = 0.02\n{extra}")
    path = tmp_path / "office50.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_the_bundled_base_at_50_hz_with_a_period_of_delay_names_what_works(tmp_path):
    """office-base at 50 Hz is refused without delay (the held command turns too far);
    with a 20 ms delay compensated it is refused naming the prescribed_time that is then
    certified, and whose closed loop keeps the tube; with the plain law the refusal names
    both."""
    path = _office_at_50_hz(tmp_path, "compensate_delay = true\n")
    with pytest.raises(stt.DesignError) as refused:
        stt.design_tube(stt.load_spec(path))
    later = refused.value.advice["prescribed_time"]
    assert f"prescribed_time = {later:g} s is certified" in str(refused.value)
    text = re.sub(r"prescribed_time = [0-9.]+", f"prescribed_time = {later!r}",
                  path.read_text(), count=1)
    path.write_text(text)
    design = stt.design_tube(stt.load_spec(path))
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and run.stayed_in_tube
    assert set(run.trajectory.status.tolist()) == {int(Status.OK)}
    plain = _office_at_50_hz(tmp_path, "")
    with pytest.raises(stt.DesignError) as refused:
        stt.design_tube(stt.load_spec(plain))
    assert refused.value.advice == {"controller.compensate_delay": True,
                                    "prescribed_time": later}


@pytest.mark.slow
def test_on_mujoco_the_compensated_base_keeps_its_tube_off_the_limits() -> None:
    """The Kobuki-like base on MuJoCo (office-drive.xml's wheels) at 50 Hz with a 20 ms
    delay: with the prediction every sample is OK and the command stays far inside its
    limits; the same design without the prediction, under the same delay, rides them."""
    pytest.importorskip("mujoco", reason="MuJoCo missing: pip install '.[mujoco]'")
    design = stt.design_tube(stt.load_spec(SPECS / "kobuki-office-mujoco.toml"))
    run = stt.simulate(design, backend="c")
    assert run.satisfied and run.stayed_in_tube and run.contacts == 0
    assert set(run.trajectory.status.tolist()) == {int(Status.OK)}
    bound = np.array(design.spec.input_bound)
    assert np.all(np.array(run.max_abs_u) < 0.5 * bound)
    plain = stt.simulate(dataclasses.replace(design, spec=dataclasses.replace(
        design.spec, compensate_delay=False)), backend="c")
    clamped = np.sum(plain.trajectory.status == int(Status.INPUT_CLAMPED))
    assert clamped > 0.1 * len(plain.trajectory.status)
    assert run.max_abs_e < plain.max_abs_e
