"""The sampled cascade's certificate (stt_codegen/design/certificate/cascade_sampled.py,
docs/second-order.md, "The sampled cascade (certificate)"): what it accepts stays in both
tubes under plants at the corners of the class and an adversary switching between them;
what it refuses includes the U-maze at 100 Hz, which diverged."""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.design.cascade_gain import derived_second_stage
from stt_codegen.design.failures import FailureKind
from stt_codegen.errors import DesignError
from stt_codegen.tube import cascade_reference, reference
from stt_codegen.design.certificate.cascade_sampled import cascade_check_of, cascade_class

UMAZE = pathlib.Path(__file__).parent / "specs" / "umaze-cascade.toml"


def _umaze(rate_hz: float):
    return dataclasses.replace(stt.load_spec(str(UMAZE)), rate_hz=rate_hz)


def adversary_run(design, stage, plants, strategy: str, seed: int = 0):
    """The sampled cascade (numpy reference step) on a diagonal plant chosen per interval:
    ``g_ii`` in ``{g_min, g_max}``, ``f_i + w_i`` at ``+-(F + W)``, integrated exactly
    (constant acceleration on each interval).

    Strategies: ``"g_min"``/``"g_max"`` (a corner, the drift pushing the velocity error
    outward), ``"switch"`` (``g`` the extreme that moves ``z`` furthest outward or
    overshoots most, the drift outward), ``"random"`` (both extremes drawn per interval,
    seeded), ``"damping"`` (``f = -c x2`` with ``c = F / velocity_bound``, the most damping
    the drift bound allows, at ``g_min``).

    Returns ``(max |e1|, max |e2|, max |u|)`` over the samples; ``inf`` once a tube is left.
    """
    tube, n = design.tube, design.tube.dimension
    h = 1.0 / tube.rate_hz
    steps = int(np.ceil(1.1 * tube.prescribed_time * tube.rate_hz))
    rng = np.random.default_rng(seed)
    push = plants.drift_bound + plants.disturbance_bound
    x1 = np.array([tube.initial_state], dtype=float)
    x2 = np.array([design.spec.second_order.initial_velocity], dtype=float)
    alpha = np.zeros((1, 2 * n))
    worst = [0.0, 0.0, 0.0]
    with reference.numpy_math():
        for k in range(steps):
            t = k * h
            u, alpha_next, r, inside1, inside2, _ = cascade_reference.cascade_step(
                tube, stage, np.hstack([x1, x2]), np.array([t]), np.array([h]), alpha)
            if inside1[0] < 1 or inside2[0] < 1:
                return np.inf, np.inf, np.inf
            g_l, g_u, _, _ = reference.adaptive_tube(tube, np.array([t]), alpha)
            e1 = (2 * x1 - g_u - g_l) / (g_u - g_l)
            rho2 = cascade_reference.velocity_tube(stage, t)
            z = x2 - r
            worst = [max(worst[0], float(np.abs(e1).max())),
                     max(worst[1], float(np.abs(z / rho2).max())),
                     max(worst[2], float(np.abs(u).max()))]
            outward = np.sign(z) + (z == 0)
            if strategy in ("g_min", "g_max"):
                g = np.full(n, getattr(plants, strategy))
            elif strategy == "switch":    # overshoot where u is large, lag where small
                big = (np.abs(u) * h * plants.g_max > np.abs(z))[0]
                g = np.where(big, plants.g_max, plants.g_min)
            elif strategy == "random":
                g = rng.choice([plants.g_min, plants.g_max], size=n)
            else:
                g = np.full(n, plants.g_min)
            if strategy == "damping":
                c = plants.drift_bound / np.array(plants.velocity_bound)
                acc0 = g * u[0] + outward[0] * plants.disturbance_bound
                # x2_dot = acc0 - c x2, exact on the interval
                decay = np.exp(-c * h)
                x2_new = x2[0] * decay + acc0 / c * (1 - decay)
                x1 = x1 + (acc0 / c * h + (x2[0] - acc0 / c) * (1 - decay) / c)[None]
                x2 = x2_new[None]
            else:
                acc = g * u[0] + outward[0] * push
                x1 = x1 + h * x2 + 0.5 * h * h * acc[None]
                x2 = x2 + h * acc[None]
            alpha = alpha_next
    return tuple(worst)


@pytest.mark.slow
def test_umaze_at_100_hz_is_refused_naming_a_rate_that_is_certified() -> None:
    spec = _umaze(100.0)
    with pytest.raises(DesignError) as caught:
        stt.design_tube(spec)
    assert caught.value.kind is FailureKind.SAMPLING_RATE
    message = str(caught.value)
    assert "100 Hz" in message and "is certified" in message
    named = float(message.split("controller.rate_hz = ")[-1].split(" is certified")[0])
    assert 100.0 < named <= 1000.0
    design = stt.design_tube(_umaze(named))           # the rate named: accepted
    stage, derivation = design.second_stage
    assert derivation["certificate"]["passed"]


@pytest.mark.slow
def test_the_shape_that_diverged_at_100_hz_is_refused_by_the_check() -> None:
    """The gains the toolkit deployed on the U-maze at 100 Hz (the linearized defaults)
    diverge in simulation; the certificate must refuse them."""
    spec = _umaze(100.0)
    design = stt.design_tube(_umaze(1000.0))
    tube = dataclasses.replace(design.tube, rate_hz=100.0)
    order = spec.second_order
    from stt_codegen.design.certificate import certify_tube
    width = certify_tube(tube, spec).min_width
    stage, _ = derived_second_stage(tube, width, order.input_gain,
                                    order.drift_bound + spec.disturbance_amplitude,
                                    order.initial_velocity, (0.1, 10.0, 4.0))
    check = cascade_check_of(tube, spec, stage)
    assert not check.passed and "may leave" in check.reason


@pytest.mark.slow
@pytest.mark.parametrize("strategy", ["g_min", "g_max", "switch", "random", "damping"])
def test_umaze_at_1_khz_is_certified_and_no_adversary_leaves_a_tube(strategy) -> None:
    design = stt.design_tube(_umaze(1000.0))
    stage, derivation = design.second_stage
    certificate = derivation["certificate"]
    assert certificate["passed"]
    plants = cascade_class(design.spec)
    e1, e2, u = adversary_run(design, stage, plants, strategy)
    # inside both tubes, and within the certificate's own bounds
    assert e1 <= certificate["max_abs_e1"] < 1
    assert e2 <= certificate["max_abs_e2"] < 1
    assert u <= max(certificate["peak_input"])


@pytest.mark.slow
@pytest.mark.parametrize("strategy", ["g_min", "g_max", "switch", "random"])
def test_s1_certificate_contains_the_adversaries(strategy) -> None:
    design = design_of("second-order-s1")
    stage, derivation = design.second_stage
    certificate = derivation["certificate"]
    e1, e2, u = adversary_run(design, stage, cascade_class(design.spec), strategy)
    assert e1 <= certificate["max_abs_e1"] < 1
    assert e2 <= certificate["max_abs_e2"] < 1
    assert u <= max(certificate["peak_input"])


def test_a_mutated_gain_or_rate_is_refused() -> None:
    design = design_of("second-order-s1")
    stage, _ = design.second_stage
    assert cascade_check_of(design.tube, design.spec, stage).passed
    # k2 twenty times larger: the held input overshoots the velocity tube
    loud = dataclasses.replace(stage, velocity_gain=20 * stage.velocity_gain)
    assert not cascade_check_of(design.tube, design.spec, loud).passed
    # the same gains at a tenth of the rate
    slow = dataclasses.replace(design.tube, rate_hz=design.tube.rate_hz / 10)
    assert not cascade_check_of(slow, design.spec, stage).passed
    # a velocity tube too narrow for the declared drift
    narrow = dataclasses.replace(stage, width_floor=tuple(v / 50 for v in stage.width_floor))
    assert not cascade_check_of(design.tube, design.spec, narrow).passed


def test_the_bounds_of_the_change_of_r_hold_on_random_steps() -> None:
    """:func:`step_velocity_change` and :func:`virtual_velocity_change` against the exact
    change of ``r = -(2 k1 / half) phi(e1)`` on seeded random steps consistent with their
    premises (the tube's centre and half-width at both ends, ``x1`` moved by ``h (r_k +
    z) + delta``)."""
    from stt_codegen.design.certificate.cascade_sampled import step_velocity_change, virtual_velocity_change
    from stt_codegen.design.certificate.sampled_axis import phi_scalar
    rng = np.random.default_rng(7)
    worst_step = worst_path = 0.0
    for _ in range(3000):
        k1, h = rng.uniform(0.001, 0.1), rng.choice([1e-3, 1e-2])
        half_k = rng.uniform(0.1, 1.0)
        half_n = half_k * (1 + rng.uniform(-0.02, 0.02))
        c_k = rng.uniform(-1, 1)
        c_n = c_k + rng.uniform(-0.02, 0.02)
        a = rng.uniform(-0.9, 0.8)
        b = min(a + rng.uniform(0, 0.2), 0.9)
        e = rng.uniform(a, b)
        z_max, acc = rng.uniform(0, 1), rng.uniform(0, 10)
        z, delta = rng.uniform(-z_max, z_max), rng.uniform(-1, 1) * 0.5 * h * h * acc
        r_k = -(2 * k1 / half_k) * phi_scalar(e)
        x1_n = c_k + e * half_k + h * (r_k + z) + delta
        e_n = (x1_n - c_n) / half_n
        if abs(e_n) >= 0.95:
            continue
        r_n = -(2 * k1 / half_n) * phi_scalar(e_n)
        bound = step_velocity_change(k1, h, a, b, (c_k - c_n) / half_n, half_k / half_n,
                                     max(abs(a), abs(b), abs(e_n)), half_k, half_n,
                                     h * z_max + 0.5 * h * h * acc)
        assert abs(r_n - r_k) <= bound * (1 + 1e-12) + 1e-15
        worst_step = max(worst_step, abs(r_n - r_k) / bound if bound else 0.0)
        # the between-samples bound: the tube anywhere within spans covering both ends
        speed = abs(r_k) + z_max + h * acc
        move = 2 * (abs(c_n - c_k) + abs(half_n - half_k))
        w_lo, w_hi = 2 * min(half_k, half_n), 2 * max(half_k, half_n)
        path = virtual_velocity_change(k1, h, abs(e), max(abs(e), abs(e_n)), speed, move,
                                       w_lo, w_hi)
        assert abs(r_n - r_k) <= path * (1 + 1e-12) + 1e-15
        worst_path = max(worst_path, abs(r_n - r_k) / path if path else 0.0)
    # the bounds are not vacuous: some steps come within a factor 3 of them
    assert worst_step > 1 / 3 and worst_path > 1 / 20


def test_the_step_bound_keeps_the_tube_s_widening_and_the_step_together() -> None:
    """A robot tracking a tube that widens as it moves: its ``e1`` drifts outward while
    ``1 / half`` falls, and the two changes of ``r = -(2 k1 / half) phi(e1)`` partly cancel.
    With ``e1(t_k)`` known (``a = b``) and nothing else in the step, the bound of
    :func:`step_velocity_change` is within 5 % of the exact change; bounding the two terms
    apart (the triangle inequality) gives about twice it here, on figures rounded from
    stlpy's EitherOr at 30 s (three times on the design's own: docs/second-order.md, "The
    sampled cascade (certificate)")."""
    from stt_codegen.design.certificate.cascade_sampled import step_velocity_change
    from stt_codegen.design.certificate.sampled_axis import phi_scalar, phi_slope_scalar
    # the figures of stlpy's EitherOr at 30 s, axis 0 at t = 10.824 s
    k1, h, half_k, half_n, c_k, c_n, e = 0.048, 1e-3, 0.1280, 0.1281, 0.0, 4.762e-4, -0.2674
    r_k = -(2 * k1 / half_k) * phi_scalar(e)
    e_n = (c_k + e * half_k + h * r_k - c_n) / half_n
    exact = abs(-(2 * k1 / half_n) * phi_scalar(e_n) - r_k)
    bound = step_velocity_change(k1, h, e, e, (c_k - c_n) / half_n, half_k / half_n,
                                 max(abs(e), abs(e_n)), half_k, half_n, 0.0)
    apart = (2 * k1 / half_n * phi_slope_scalar(max(abs(e), abs(e_n))) * abs(e_n - e)
             + 2 * k1 * abs(phi_scalar(e)) * abs(1 / half_n - 1 / half_k))
    assert exact <= bound <= 1.05 * exact
    assert apart > 1.8 * exact
    # and on seeded random steps with e1(t_k) known and no other term: within 25 % (the
    # range of phi' between e1 and e1 + m widens with the step; median 0.3 %, largest 17 %)
    rng = np.random.default_rng(11)
    for _ in range(500):
        k1, h = rng.uniform(0.01, 0.1), 1e-3
        half_k = rng.uniform(0.05, 0.5)
        half_n = half_k * (1 + rng.uniform(-1e-3, 1e-3))
        e = rng.uniform(-0.6, 0.6)
        c_n = rng.uniform(-1e-3, 1e-3)
        r_k = -(2 * k1 / half_k) * phi_scalar(e)
        e_n = (e * half_k + h * r_k - c_n) / half_n
        exact = abs(-(2 * k1 / half_n) * phi_scalar(e_n) - r_k)
        bound = step_velocity_change(k1, h, e, e, -c_n / half_n, half_k / half_n,
                                     max(abs(e), abs(e_n)), half_k, half_n, 0.0)
        assert exact <= bound * (1 + 1e-12) + 1e-15
        assert bound <= 1.25 * exact + 1e-12


def test_the_spec_s_own_plant_is_checked_against_the_class() -> None:
    from stt_codegen.verification.cascade import plant_within_class_check
    for name in ("second-order-s1", "second-order-quadrotor", str(UMAZE)):
        check = plant_within_class_check(stt.load_spec(name))
        assert check.passed, check.detail
    spec = stt.load_spec("second-order-quadrotor")
    # gravity alone exceeds a drift bound of 5: the certificate would not cover the plant
    low = dataclasses.replace(spec, second_order=dataclasses.replace(
        spec.second_order, drift_bounds=(5.0,) * 3))
    check = plant_within_class_check(low)
    assert not check.passed and "drift_bound" in check.detail
    heavy = dataclasses.replace(spec, second_order=dataclasses.replace(
        spec.second_order, parameters=(2.0, 0.3, 9.81)))
    assert not plant_within_class_check(heavy).passed       # 1/m = 0.5 < g_min = 0.625
