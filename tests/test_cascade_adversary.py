"""The adversary of the sampled cascade (design/certificate/cascade_adversary.py): it breaks what the
certificate refuses, and never what it proves (docs/second-order.md, "The adversary")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen_bench.second_order_study import random_parameters, run_second_order_study
from stt_codegen.design.certificate.cascade_adversary import STRATEGIES, search_cascade
from stt_codegen.design.certificate.cascade_sampled import cascade_class, certify_stage


@pytest.fixture(scope="module")
def s1():
    design = stt.design_tube(stt.load_spec("second-order-s1"))
    return design, design.second_stage[0]


def test_the_adversary_breaks_the_stage_at_a_rate_the_certificate_refuses(s1) -> None:
    """The certified stage of second-order-s1 (1 kHz) run at 50 Hz: the certificate refuses
    it, and the adversary finds members of the same class that leave a tube in every
    strategy, within half a second."""
    design, stage = s1
    slow = dataclasses.replace(design.tube, rate_hz=50.0)
    passed, report = certify_stage(slow, design.spec, stage)
    assert not passed and report["reason"]
    exits = search_cascade(slow, stage, cascade_class(design.spec),
                           design.spec.second_order.initial_velocity, horizon=0.5)
    assert {e.strategy for e in exits} >= {"position", "velocity", "both"}
    assert all(e.depth >= 1.0 and 0.0 < e.time <= 0.5 for e in exits)


def test_strategies_are_checked(s1) -> None:
    design, stage = s1
    with pytest.raises(ValueError, match="unknown strategies"):
        search_cascade(design.tube, stage, cascade_class(design.spec), [0.0, 0.0],
                       strategies=("random",))
    assert STRATEGIES[-1] == "held"


def test_corner_parameters_are_at_the_ends_of_the_declared_range() -> None:
    rng = np.random.default_rng(0)
    masses = {random_parameters("double-integrator", (0.8, 1.25), rng, corners=True)[0]
              for _ in range(40)}
    assert masses == {1 / 0.8, 1 / 1.25}
    drags = {random_parameters("quadrotor", (0.8, 1.25), rng, corners=True)[1]
             for _ in range(40)}
    assert drags == {0.0, 0.4}


@pytest.mark.slow
def test_no_member_of_a_certified_class_leaves_a_tube(s1) -> None:
    """The certified design of second-order-s1 at its own rate: the adversary (greedy on
    both errors, and each extreme member held) finds no member leaving a tube over the
    whole horizon."""
    design, stage = s1
    exits = search_cascade(design.tube, stage, cascade_class(design.spec),
                           design.spec.second_order.initial_velocity,
                           strategies=("both", "held"))
    assert exits == []


@pytest.mark.slow
def test_corner_plants_of_the_certified_class_stay_in_both_tubes() -> None:
    """A derandomized slice of the study: plants at the corners of the declared bounds
    with the largest disturbance, on the generated C, all satisfied in both tubes."""
    report = run_second_order_study("second-order-s1", count=6, seed=1, corners=True)
    assert report["in_both_tubes"] == report["satisfied"] == 6, report["failures"]
