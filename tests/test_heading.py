"""A differential-drive base's turn bounded from the heading it can have
(``stt_codegen.design.heading``; docs/differential-drive.md, "The heading the base can
have").

The enclosure of the heading and the bound of ``|omega|`` are checked against bases drawn
within the wheel model (random commands in the boxes, wheel errors and slip at random and
at their ends), against the closed loop of a designed base, and against the worst
heading's bound, which they never pass; and the AGV with a short look-ahead, refused at the
worst heading, is certified with them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.heading import command_bounds, corner_boxes
from stt_codegen.design.look_ahead import heading_bounds
from stt_codegen.spec.loader import parse_spec

SPECS = Path(__file__).parent / "specs"


def _random_boxes(rng, count: int) -> np.ndarray:
    """Boxes of ``u`` drifting along a turning route: some exclude 0 on an axis, some
    straddle it on both (a stop)."""
    angle = np.cumsum(rng.normal(0.0, 0.05, count)) + rng.uniform(-math.pi, math.pi)
    speed = np.abs(np.sin(np.linspace(0.0, 3.0 * math.pi, count))) * rng.uniform(0.3, 1.5)
    centre = np.stack([speed * np.cos(angle), speed * np.sin(angle)], axis=1)
    half = rng.uniform(0.02, 0.3, (count, 2)) * (0.2 + speed[:, None])
    return np.stack([centre - half, centre + half], axis=2)


@pytest.mark.parametrize("seed", range(6))
def test_the_enclosure_holds_for_bases_drawn_within_the_model(seed):
    """Commands anywhere in their boxes (corners half the time), ``1 + m`` and ``d`` at
    random or at their ends, slip within its bound: the heading stays in its enclosure at
    every sample and the commanded ``|omega|`` within its bound, which is never above the
    worst heading's ``|u| / l``."""
    rng = np.random.default_rng(seed)
    count, dt = 600, 0.02
    l, b = rng.uniform(0.1, 0.8), rng.uniform(0.3, 0.6)
    gains, d_max, slip = (0.95, 1.05), 0.03, 0.05
    boxes = _random_boxes(rng, count)
    heading0 = rng.uniform(-math.pi, math.pi)
    bounds = command_bounds(boxes, heading0, dt, l, b, gains, d_max, slip)
    worst = np.hypot(*np.abs(boxes).max(axis=2).T) / l
    assert np.all(bounds.turn <= worst * (1.0 + 1e-8))
    assert np.all(bounds.backward <= worst * l * (1.0 + 1e-8))
    for run in range(40):
        theta = heading0
        gain = rng.choice(gains) if run % 2 else rng.uniform(*gains)
        d = rng.choice([-d_max, d_max]) if run % 3 else rng.uniform(-d_max, d_max)
        for k in range(count):
            lo, hi = bounds.heading[k]
            assert lo <= theta <= hi, (run, k)
            pick = rng.integers(0, 2, 2) if run % 2 else rng.uniform(0.0, 1.0, 2)
            u = boxes[k, :, 0] + pick * (boxes[k, :, 1] - boxes[k, :, 0])
            along = u[0] * math.cos(theta) + u[1] * math.sin(theta)
            across = -u[0] * math.sin(theta) + u[1] * math.cos(theta)
            assert abs(across) / l <= bounds.turn[k], (run, k)
            assert -along <= bounds.backward[k], (run, k)
            rate = 2.0 * d / b * along + gain * across / l + rng.uniform(-slip, slip)
            theta += dt * rate


def test_an_aligned_command_bounds_the_turn_well_below_the_worst_heading():
    """A command along x within +-0.05 m/s across, the base facing x: the turn is bounded
    by about the command's lean over ``l``, a tenth of ``|u| / l``; facing across, the
    first sample's is the whole command's ``|u_x| / l``, and the base then turns to it."""
    count = 200
    boxes = np.tile(np.array([[[0.95, 1.05], [-0.05, 0.05]]]), (count, 1, 1))
    aligned = command_bounds(boxes, 0.0, 0.01, 0.5, 0.4, (1.0, 1.0), 0.0, 0.0)
    assert aligned.turn.max() < 0.15 * 1.05 / 0.5
    across = command_bounds(boxes, math.pi / 2, 0.01, 0.5, 0.4, (1.0, 1.0), 0.0, 0.0)
    assert across.turn[0] == pytest.approx(1.05 / 0.5, rel=1e-6)
    assert across.turn[-1] < 0.15 * 1.05 / 0.5              # it has turned to the command
    # backing up: none facing the command (but the rounding); facing across, the command's
    # lean of 0.05 against the heading; facing away, all of u_x
    assert aligned.backward.max() < 1e-8
    assert across.backward[0] == pytest.approx(0.05, rel=1e-6)
    facing_back = command_bounds(boxes, math.pi, 0.01, 0.5, 0.4, (1.0, 1.0), 0.0, 0.0)
    assert facing_back.backward[0] == pytest.approx(1.05, rel=1e-6)     # v = -u_x


def test_the_command_box_holds_law_13():
    """``corner_boxes``: law (13)'s ``u_i = -(4 k / w_i) phi(e_i)`` for ``e_i`` and ``w_i``
    drawn in their boxes lies in the box."""
    from stt_codegen.design.certificate.sampled_axis import phi
    rng = np.random.default_rng(3)
    lo = rng.uniform(-0.9, 0.8, (50, 2))
    e_box = np.stack([lo, lo + rng.uniform(0.0, 0.1, (50, 2))], axis=2)
    w_lo = rng.uniform(0.2, 1.0, (50, 2))
    w_hi = w_lo + rng.uniform(0.0, 0.1, (50, 2))
    box = corner_boxes(e_box, w_lo, w_hi, 0.7)
    for _ in range(200):
        e = e_box[..., 0] + rng.uniform(0.0, 1.0, (50, 2)) * (e_box[..., 1] - e_box[..., 0])
        w = w_lo + rng.uniform(0.0, 1.0, (50, 2)) * (w_hi - w_lo)
        u = -4.0 * 0.7 * phi(e) / w
        assert np.all(box[..., 0] <= u) and np.all(u <= box[..., 1])


@pytest.fixture(scope="module")
def short_agv():
    """The warehouse AGV (``tests/specs/agv-warehouse.toml``) with the look-ahead 0.6 m,
    which its comment says the worst heading refuses."""
    text = (SPECS / "agv-warehouse.toml").read_text()
    assert "axle_offset = 0.8" in text
    return parse_spec(text.replace("axle_offset = 0.8", "axle_offset = 0.6"))


def test_the_agv_with_a_short_look_ahead_is_certified_by_its_heading(short_agv):
    """Certified at its 40 s within ``[1.2 m/s, 1.5 rad/s]``: the proved ``|omega|`` is
    within 1.5 where the worst heading's ``|u| / l`` is not."""
    design = stt.design_tube(short_agv)
    assert design.tube.prescribed_time == 40.0
    v, omega = design.input_proof.peak
    assert v <= 1.2 and omega <= 1.5 < v / 0.6


def _closed_loop(design, seed: int, steps_per_period: int = 4):
    """The base's sampled closed loop, written here from the wheel model: the spec's wheel
    errors, slip drawn within its amplitudes on each sub-step, the command held over the
    period. Returns the heading at each sample and the commands ``(v, omega)``."""
    from stt_codegen.runtime.backends import make_controller
    spec, drive = design.spec, design.spec.drive
    controller = make_controller("casadi", design.tube, design.look_ahead)
    rng = np.random.default_rng(seed)
    m, d, b = drive.mean_error, drive.differential_error, drive.track_width
    dt = 1.0 / design.tube.rate_hz
    x = np.array(drive.initial_axle(spec.initial_state), dtype=float)
    alpha = np.zeros(4)
    headings, commands = [], []
    for k in range(int(round(1.05 * design.tube.prescribed_time / dt))):
        headings.append(x[2])
        u, alpha, _ = controller.step(x, k * dt, dt, alpha)
        commands.append(u)
        h = dt / steps_per_period
        for _ in range(steps_per_period):
            s_v, s_lat, s_w = (a * rng.uniform(-1.0, 1.0) for a in drive.slip)
            v = (1.0 + m) * u[0] + 0.5 * b * d * u[1] + s_v
            omega = 2.0 / b * d * u[0] + (1.0 + m) * u[1] + s_w
            mid = x[2] + 0.5 * h * omega
            x = x + h * np.array([v * math.cos(mid) - s_lat * math.sin(mid),
                                  v * math.sin(mid) + s_lat * math.cos(mid), omega])
    return np.array(headings), np.array(commands)


def test_the_closed_loop_keeps_its_heading_and_turn_within_their_bounds(short_agv):
    """The AGV's closed loop (its wheel errors, slip at random within its amplitudes, three
    seeds): the heading at every sample lies in its enclosure and the commanded ``|omega|``
    within its bound there; the bound is below the worst heading's where the base is
    aligned."""
    design = stt.design_tube(short_agv)
    t, bounds = heading_bounds(design.tube, design.spec)
    for seed in range(3):
        theta, u = _closed_loop(design, seed)
        k = len(theta)
        assert np.all(bounds.heading[:k, 0] <= theta) and np.all(theta <= bounds.heading[:k, 1])
        assert np.all(np.abs(u[:, 1]) <= bounds.turn[:k])
        assert np.all(-u[:, 0] <= bounds.backward[:k])
    assert np.median(bounds.turn) < 0.6 * design.input_proof.peak[0] / 0.6
