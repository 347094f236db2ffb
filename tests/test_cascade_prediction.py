"""The cascade's delay-compensating prediction (``[controller] compensate_delay`` on a
second-order plant): its certificate (which proves a whole period of delay on the U-maze at
400 Hz where the plain cascade's cannot, and fails where it should), the refusals, the closed
loop that runs it, and the generated ``predict`` of C and Python, bit for bit the CasADi
predictor (its MISRA check is tests/test_delay_prediction.py's; docs/second-order.md,
"Compensating a delay")."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

import control as ct

import stt_codegen as stt
from stt_codegen.design.certificate.cascade_sampled import (cascade_check_of, cascade_class,
                                                            check_cascade_sampled)
from stt_codegen.design.prediction import mid_gain
from stt_codegen.design.samples import sample_tube
from stt_codegen.runtime.state_split import initial_state
from stt_codegen.tube import cascade_reference, reference
from stt_codegen.tube.parameters import Status

SPECS = Path(__file__).parent / "specs"
CASCADE = SPECS / "umaze-cascade-compensated.toml"    # 400 Hz, a 2.5 ms delay, compensated
PERIOD = 1.0 / 400.0


@lru_cache(maxsize=None)
def _design(path: Path):
    return stt.design_tube(stt.load_spec(path))


def _check(design, spec, delay: float, compensate: bool):
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    return check_cascade_sampled(design.tube, samples, design.stage, cascade_class(spec),
                                 spec.second_order.initial_velocity, delay=delay,
                                 compensate=compensate)


def test_the_cascade_predicts_at_the_middle_of_its_own_input_gain() -> None:
    """g_mid is the second-order plant's (the cascade's class), not [assumptions]'."""
    spec = stt.load_spec(CASCADE)
    low, high = spec.second_order.input_gain
    assert mid_gain(spec) == 0.5 * (low + high)
    assert mid_gain(spec) != 0.5 * sum(spec.assumptions.input_gain)


# ---------------------------------------------------------------------- the certificate
@pytest.mark.slow
def test_a_one_period_delay_is_certified_with_the_prediction_and_not_without() -> None:
    design = _design(CASCADE)
    spec = design.spec
    assert spec.compensate_delay and spec.delay == PERIOD
    check = cascade_check_of(design.tube, spec, design.stage)
    assert check.passed and check.data["compensate_delay"]
    assert check.max_abs_e1 < 1.0 and check.max_abs_e2 < 1.0
    assert check.position_margin > 0.0 and check.velocity_margin > 0.0
    plain = _check(design, spec, PERIOD, compensate=False)
    assert not plain.passed and "velocity error may leave its tube" in plain.reason


@pytest.mark.slow
def test_the_predicted_check_can_fail_and_reports_where() -> None:
    """The same stage with a wider gain range (g_max three times g_min) and a whole period:
    the prediction's miss grows with |g - g_mid| and the check fails, naming where."""
    design = _design(CASCADE)
    spec = design.spec
    low, _ = spec.second_order.input_gain
    wide = dataclasses.replace(cascade_class(spec), g_max=3.0 * low,
                               coupling=0.0)
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    failed = check_cascade_sampled(design.tube, samples, design.stage, wide,
                                   spec.second_order.initial_velocity, delay=PERIOD,
                                   compensate=True)
    assert not failed.passed
    assert re.search(r"on \[[0-9.]+, [0-9.]+\] s", failed.reason), failed.reason
    assert min(failed.position_margin, failed.velocity_margin) <= 0.0


@pytest.mark.slow
def test_a_prediction_over_a_vanishing_delay_is_the_plain_check() -> None:
    """Over a delay of 1e-12 s the predicted check's margins are the plain check's to
    within 1 % (the enclosures of the actuation interval tend to the sampling interval's)."""
    design = _design(CASCADE)
    spec = design.spec
    predicted = _check(design, spec, 1e-12, compensate=True)
    plain = _check(design, spec, 0.0, compensate=False)
    assert predicted.passed and plain.passed
    assert predicted.data["compensate_delay"] and "compensate_delay" not in plain.data
    assert predicted.velocity_margin == pytest.approx(plain.velocity_margin, rel=1e-2)
    assert predicted.position_margin == pytest.approx(plain.position_margin, rel=1e-2)


@pytest.mark.slow
def test_the_plain_cascade_with_the_delay_is_refused_naming_compensate_delay() -> None:
    spec = dataclasses.replace(stt.load_spec(CASCADE), compensate_delay=False)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    assert ("controller.compensate_delay = true is certified with controller.delay = "
            "0.0025 s at 400 Hz") in str(raised.value)
    assert raised.value.advice["controller.compensate_delay"] is True


@pytest.mark.slow
def test_at_the_plain_certified_rate_a_period_is_refused_naming_a_delay_then_certified():
    """umaze-cascade's plain certified rate is 230 Hz; there a whole period (4.35 ms)
    compensated is refused, naming the largest delay certified at 230 Hz, which designs."""
    base = stt.load_spec(CASCADE)
    spec = dataclasses.replace(base, rate_hz=230.0, delay=1.0 / 230.0)
    with pytest.raises(stt.DesignError) as raised:
        stt.design_tube(spec)
    shorter = raised.value.advice["controller.delay"]
    assert 0.0 < shorter < spec.delay
    assert f"controller.delay = {shorter:.3g} s is certified at 230 Hz" in str(raised.value)
    design = stt.design_tube(dataclasses.replace(spec, delay=shorter))
    assert cascade_check_of(design.tube, design.spec, design.stage).passed
    # a delay of one period of a faster rate (computed in a period, applied at the next
    # tick): the rate named is certified with it, and its loop keeps both tubes
    named = re.search(r"controller\.rate_hz = ([0-9.]+) with controller\.delay = ",
                      str(raised.value))
    assert named is not None
    rate = float(named.group(1))
    assert rate > 230.0
    design = stt.design_tube(dataclasses.replace(spec, rate_hz=rate, delay=1.0 / rate))
    assert cascade_check_of(design.tube, design.spec, design.stage).passed
    run = stt.simulate(design, backend="reference")
    assert run.stayed_in_tube and run.stayed_in_velocity_tube
    assert set(run.trajectory.status.tolist()) == {int(Status.OK)}


# ---------------------------------------------------------------------- the closed loop
@pytest.mark.slow
def test_the_closed_loop_with_the_delay_keeps_both_tubes() -> None:
    design = _design(CASCADE)
    run = stt.simulate(design, backend="reference")
    assert run.satisfied and run.stayed_in_tube and run.stayed_in_velocity_tube
    assert run.max_abs_e < 1.0
    assert set(run.trajectory.status.tolist()) == {int(Status.OK)}
    check = cascade_check_of(design.tube, design.spec, design.stage)
    assert np.all(np.abs(run.trajectory.u) <= np.array(check.peak_input))


@pytest.mark.slow
def test_the_interconnected_loop_gives_simulates_run_with_the_prediction() -> None:
    design = _design(CASCADE)
    controller = stt.controller_system(design, backend="reference")
    plant = stt.sampled_plant(design)
    states, inputs, n = plant.nstates, plant.ninputs, design.spec.dimension
    loop = ct.interconnect(
        [controller, plant], inplist=[],
        connections=[*([f"stt.x[{i}]", f"plant.x[{i}]"] for i in range(2 * n)),
                     *([f"plant.u[{j}]", f"stt.u[{j}]"] for j in range(inputs))],
        outlist=[*(f"stt.u[{j}]" for j in range(inputs)), "stt.status"])
    steps = 100
    dt = controller.dt
    x0 = np.concatenate([np.zeros(controller.nstates), initial_state(design.spec),
                         np.zeros(states - 2 * n)])
    response = ct.input_output_response(loop, np.arange(steps + 1) * dt, 0, X0=x0)
    run = stt.simulate(design, backend="reference", horizon=steps * dt)
    assert np.max(np.abs(response.outputs[:inputs].T - run.trajectory.u)) <= 1e-12
    assert np.array_equal(response.outputs[-1], run.trajectory.status.astype(float))


# ---------------------------------------------------------------------- the generated code
@pytest.mark.slow
@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None,
                    reason="host C compiler missing: install the Debian package gcc")
def test_the_firmware_loop_runs_the_cascades_prediction(tmp_path) -> None:
    """The cascade's firmware loop (single-precision controller, double plant, built for
    the host) calls P_predict before P_step: it follows the host's predicted run, not the
    same delayed run without the prediction."""
    from stt_codegen.embedded import cascade_loop, programs
    from stt_codegen.runtime.state_split import positions
    design = _design(CASCADE)
    spec = design.spec
    stt.generate(design, tmp_path, languages=["c"], precision="single")
    (tmp_path / "loop.c").write_text(cascade_loop.closed_loop_program(design, spec.c_name))
    build = subprocess.run(["gcc", "-O2", "-o", str(tmp_path / "loop"), str(tmp_path / "loop.c"),
                            str(tmp_path / f"{spec.c_name}.c"), "-I", str(tmp_path), "-lm"],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(tmp_path / "loop")], capture_output=True, text=True)
    assert "satisfied=1" in run.stdout
    states = programs.parse_closed_loop(run.stdout, spec.dimension, 2 * spec.dimension).states
    points = {k: positions(spec, np.array(x)[None])[0] for k, x in states.items()}
    predicted = stt.simulate(design, backend="c")
    plain = dataclasses.replace(design, spec=dataclasses.replace(spec, compensate_delay=False))
    # the same second stage (the plain cascade's certificate refuses it with the delay)
    plain.__dict__["second_stage"] = design.second_stage
    unpredicted = stt.simulate(plain, backend="c")
    assert predicted.stayed_in_tube and predicted.stayed_in_velocity_tube
    with_prediction = max(np.max(np.abs(p - positions(spec, predicted.trajectory.x[k][None])[0]))
                          for k, p in points.items())
    without = max(np.max(np.abs(p - positions(spec, unpredicted.trajectory.x[k][None])[0]))
                  for k, p in points.items())
    assert 10 * with_prediction < without, (with_prediction, without)


def _adversary_run(design, plants, strategy: str, seed: int = 0) -> tuple[float, ...]:
    """The predicted cascade (numpy oracle: the reference step at the oracle's prediction)
    on a diagonal plant with ``g_ii`` chosen per piece of each period and ``f_i + w_i`` at
    ``+-(F + W)`` pushing the velocity error outward, integrated exactly (constant
    acceleration on each piece: ``u_{k-1}`` over the delay, then ``u_k``).

    Returns ``(max |e1|, max |e2|)`` of the predicted state at the samples and ``max |e1|``
    of the true state there; ``inf`` once a tube is left."""
    tube, stage, spec = design.tube, design.stage, design.spec
    n, h, delay = tube.dimension, 1.0 / tube.rate_hz, spec.delay
    g_mid = mid_gain(spec)
    rng = np.random.default_rng(seed)
    push = plants.drift_bound + plants.disturbance_bound
    x = np.concatenate([tube.initial_state, spec.second_order.initial_velocity])[None]
    alpha, u_prev = np.zeros((1, 2 * n)), np.zeros((1, n))
    worst = [0.0, 0.0, 0.0]
    with reference.numpy_math():
        for k in range(int(np.ceil(1.1 * tube.prescribed_time * tube.rate_hz))):
            t = k * h
            x_hat = cascade_reference.predicted_state(x, u_prev, delay, g_mid)
            u, alpha_next, r, inside1, inside2, _ = cascade_reference.cascade_step(
                tube, stage, x_hat, np.array([t]), np.array([h]), alpha)
            g_l, g_u, _, _ = reference.adaptive_tube(tube, np.array([t]), alpha)
            e1_hat = (2 * x_hat[:, :n] - g_u - g_l) / (g_u - g_l)
            e1 = (2 * x[:, :n] - g_u - g_l) / (g_u - g_l)
            z = x_hat[:, n:] - r
            if inside1[0] < 1 or inside2[0] < 1 or np.abs(e1).max() >= 1.0:
                return np.inf, np.inf, np.inf
            worst = [max(worst[0], float(np.abs(e1_hat).max())),
                     max(worst[1], float(np.abs(z / cascade_reference.velocity_tube(
                         stage, t)).max())), max(worst[2], float(np.abs(e1).max()))]
            outward = (np.sign(z) + (z == 0))[0]
            for force, length in ((u_prev[0], delay), (u[0], h - delay)):
                if strategy == "random":
                    g = rng.choice([plants.g_min, plants.g_max], size=n)
                else:
                    g = np.full(n, getattr(plants, strategy))
                acc = g * force + outward * push
                x = np.concatenate([x[0, :n] + length * x[0, n:] + 0.5 * length**2 * acc,
                                    x[0, n:] + length * acc])[None]
            u_prev, alpha = u, alpha_next
    return tuple(worst)


@pytest.mark.slow
@pytest.mark.parametrize("strategy", ["g_min", "g_max", "random"])
def test_the_predicted_loop_on_extreme_plants_stays_within_the_certified_bounds(strategy):
    """Plants at the corners of the class (and switching between them), the drift pushing
    the velocity error outward: the predicted state's errors at the samples stay within
    the certificate's bounds, and the true position inside its tube."""
    design = _design(CASCADE)
    plants = cascade_class(design.spec)
    check = cascade_check_of(design.tube, design.spec, design.stage)
    e1_hat, e2_hat, e1 = _adversary_run(design, plants, strategy, seed=3)
    assert e1_hat <= check.max_abs_e1 + 1e-9 and e2_hat <= check.max_abs_e2 + 1e-9
    assert e1 < 1.0
