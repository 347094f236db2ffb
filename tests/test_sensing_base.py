"""Obstacles sensed at run time on a differential-drive base (docs/sensing.md, "A
differential-drive base"): the replanner designs the look-ahead variant's tubes for the
point ahead of the axle, a sensed obstacle grown by the body's radius plus the look-ahead
distance; the closed loop switches them on the base's command."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.runtime.sensed import bundled_people
from stt_codegen.spec.loader import parse_spec
from stt_codegen.tube.look_ahead import LookAhead
from test_sensing_replan import oracle_tube

SPEC = Path(__file__).parent / "specs" / "hall-crossing-base.toml"
REACH = 0.2 + 0.2                       # robot.radius + plant.axle_offset


@pytest.fixture(scope="module")
def base():
    return stt.design_tube(stt.load_spec(SPEC))


def person():
    return stt.SensedObstacle.ball((4.0, 2.8), 0.3, seen_at=1.0)


def test_the_base_grows_a_sensed_obstacle_by_its_body_and_look_ahead(base):
    assert base.spec.variant == "look-ahead"
    assert base.spec.robot.radius == pytest.approx(REACH)


def test_a_person_in_the_bases_way_gives_a_new_certified_look_ahead_tube(base):
    """The new tube is the look-ahead variant's (its stage, its certificate), and the
    numpy oracle's tube, grown by 0.4 m, misses the person's reachable box at every sample
    of its horizon."""
    start = stt.start_plan(base)
    sensing = base.spec.sensing
    new = stt.replan(start, 1.0, (1.2, 3.0), [person()])
    assert isinstance(new, stt.SensedPlan) and not new.kept
    assert isinstance(new.design.stage, LookAhead) and new.design.certificate.passed
    assert new.sensed_margin > 0 and new.region_margin > 0
    ts, lows, highs = oracle_tube(new.design.tube, sensing.horizon, base.spec.rate_hz)
    for t, lo, hi in zip(ts, lows, highs):
        p_lo, p_hi = person().reach_box(new.start + t, sensing.max_obstacle_speed)
        assert np.any((hi + REACH < p_lo) | (lo - REACH > p_hi)), t


def test_a_base_with_actuator_limits_replans_within_them(base):
    """With ``[actuator] input_bound``, a new tube's controller is proved within the
    base's ``(v_max, omega_max)`` as the spec's own design is."""
    text = SPEC.read_text() + "\n[actuator]\ninput_bound = [1.5, 6.0]\n"
    limited = stt.design_tube(parse_spec(text))
    new = stt.replan(stt.start_plan(limited), 1.0, (1.2, 3.0), [person()])
    assert isinstance(new, stt.SensedPlan) and not new.kept
    proof = new.design.input_proof
    assert proof is not None and proof.meets((1.5, 6.0)) and proof.complete
    assert new.design.stage.input_bound == pytest.approx((1.5, 6.0))   # the clamp


@pytest.mark.slow
def test_the_base_crosses_the_hall_among_people_certified_throughout(base):
    """The demo's people walk across the base's way: the base switches tubes, never
    refuses or fails, is certified throughout, stays in whichever tube is active, touches
    no one and arrives by t_c; its own generated C (per tube) and the CasADi model drive
    it through the same states, bit for bit."""
    runs = [stt.simulate_sensed(base, bundled_people("hall-crossing"), backend=b)
            for b in ("casadi", "c")]
    run, record = runs[1], runs[1].sensing
    assert record.switches >= 3 and record.refused == 0 and record.failures == 0
    assert record.guaranteed and not record.outside_envelope
    assert run.stayed_in_tube and not record.sensed_collision and not run.collision
    assert run.satisfied and record.min_sensed_clearance > 0.0
    for name in ("x", "u", "alpha", "tube"):
        assert np.array_equal(getattr(runs[0].trajectory, name),
                              getattr(run.trajectory, name)), name
