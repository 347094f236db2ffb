"""The sampled check with coupled plants: the robot judged with its own bounds,
plants of that class simulated against the bound the check proves, a plant outside its
bounds refused, and a derandomized sample of the wide study (no accepted plant fails)."""

from __future__ import annotations

import dataclasses
import math

import control as ct
import numpy as np
import pytest
from conftest import CASES, designed
from plants_helpers import plant_system, plant_within

from stt_codegen_bench.plants_study import study_one
from stt_codegen.design.samples import sample_tube
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.assumptions import Assumptions
from stt_codegen.tube import reference
from stt_codegen.verification.command import verify_design
from stt_codegen.design.certificate.plant_class import PlantClass, plant_class
from stt_codegen.design.certificate.sampled import check_sampled

_SAMPLES: dict = {}


#: The robot class's checks keep one case in the fast tier; the other two are slow.
ONE_CASE_FAST = ["omnirobot-s1", *(pytest.param(c, marks=pytest.mark.slow)
                                   for c in ("omnirobot-s2", "omnirobot-s3"))]


def samples_of(case: str):
    if case not in _SAMPLES:
        _SAMPLES[case] = sample_tube(designed(case)[1])
    return _SAMPLES[case]


@pytest.mark.parametrize("case", ONE_CASE_FAST)
def test_the_robot_cases_pass_at_their_rate_with_the_robots_own_bounds(case):
    spec, design, _ = designed(case)
    a = spec.assumptions
    assert a.model == "omnidirectional" and a.declared == () and a.blocks == ((0, 1), (2,))
    result = check_sampled(design, samples_of(case), plant_class(spec))
    assert result.passed, result.reason
    assert result.data["refined_on_the_tube"] == ["input_gain", "input_gain_skew",
                                                  "input_gain_coupling"]
    assert 0 < result.level < 0.9 and result.margin > 0.1


def test_over_the_whole_heading_range_the_robot_class_is_not_proved(case):
    """A documented limit: the same bounds taken uniformly over the state space (g_min =
    cos 1.2, skew sin 1.2 on every interval) are not proved at 1 kHz."""
    spec, design, _ = designed(case)
    assert not check_sampled(design, samples_of(case), PlantClass(spec.assumptions)).passed


def _rotation_plant(kind: str, disturbance: np.ndarray):
    """Plants of the robot's class: ``g(x)`` with symmetric part ``diag(cos x3, cos x3, 1)``
    and skew part ``+-sin(x3)`` in the (x1, x2) plane, constant ``w``."""
    def g_of(x):
        c, s = math.cos(x[2]), math.sin(x[2])
        sign = {"model": 1.0, "mirrored": -1.0, "symmetric": 0.0}[kind]
        return np.array([[c, -sign * s, 0.0], [sign * s, c, 0.0], [0.0, 0.0, 1.0]])

    def rhs(t, x, u, params):
        return g_of(x) @ np.asarray(u, float) + disturbance

    return ct.nlsys(rhs, None, inputs=3, states=3, outputs=3)


def _max_sampled_error(design, result) -> float:
    tr = result.trajectory
    lo, hi, _, _ = reference.adaptive_tube(design, tr.t, tr.alpha)
    return float(np.abs((2 * tr.x - (hi + lo)) / (hi - lo)).max())


@pytest.mark.parametrize("case", ONE_CASE_FAST)
@pytest.mark.parametrize("kind", ["model", *(pytest.param(k, marks=pytest.mark.slow)
                                          for k in ("mirrored", "symmetric"))])
def test_plants_of_the_robot_class_stay_within_the_proved_error(case, kind):
    spec, design, _ = designed(case)
    result = check_sampled(design, samples_of(case), plant_class(spec))
    w = spec.assumptions.disturbance_bound * np.array([1.0, -1.0, 1.0]) / math.sqrt(3)
    run = run_closed_loop(spec, design, backend="c", plant=_rotation_plant(kind, w))
    assert run.stayed_in_tube and run.satisfied
    assert _max_sampled_error(design, run) <= result.level


@pytest.mark.slow
def test_a_plant_outside_its_declared_bounds_is_not_accepted():
    """A spec changed in Python to bounds its model violates: verify fails, and says why."""
    spec, design, _ = designed("omnirobot-s1")
    narrow = dataclasses.replace(spec, assumptions=dataclasses.replace(
        spec.assumptions, input_gain=(0.9, 1.0)))
    checks = {c.name: c for c in verify_design(narrow, design)}
    within = checks["sampled.plant_within_assumptions"]
    assert not within.passed and "outside input_gain" in within.detail
    assert "does not cover this plant" in within.detail


@pytest.mark.slow
def test_a_coupled_class_the_check_accepts_stays_within_the_proved_error():
    """A class with coupling and drift, one block of three coupled states: the check
    passes, and plants drawn within it stay below the |e| it proves. The Lyapunov balls
    never weaken the per-axis argument (they only cut its boxes).

    With the gains of the tight width (s3: k = 0.484) the check no longer proves the
    class with the largest coupling its eigenvalue range and skew allow
    ((1.2 - 0.8) / 2 + 0.3 = 0.5; margin -1.75 at t = 1.324 s); with coupling 0.4 it
    does, and there the ball cuts the per-axis |e| (0.573 < 0.576)."""
    spec, design, _ = designed("omnirobot-s3")
    a = Assumptions((0.8, 1.2), 0.3, 0.4, 0.2, 0.17)
    s = samples_of("omnirobot-s3")
    result = check_sampled(design, s, a)
    per_axis = check_sampled(design, s, a, lyapunov=False)
    assert result.passed and per_axis.passed and result.level <= per_axis.level
    for seed in range(2):
        plant = plant_system(plant_within(np.random.default_rng(seed), a, spec.state_space))
        run = run_closed_loop(dataclasses.replace(spec, assumptions=a), design, backend="c",
                       plant=plant)
        assert run.stayed_in_tube and run.satisfied
        assert _max_sampled_error(design, run) <= result.level


# the wide study (bench/plants_study.py): plants 0-1 of each case, and the plants the check
# accepts among the first 100 of each case at the spec's rate with the gains of the tight
# width (s1: k = 0.200, s2: 0.323, s3: 0.484): s1 47, s3 41 and 44; none of s2
ACCEPTED = [("omnirobot-s1", 47), ("omnirobot-s3", 41), ("omnirobot-s3", 44)]
WIDE = [(c, i) for c in CASES for i in range(2)] + ACCEPTED


@pytest.mark.slow          # about 20 s: a closed loop per plant of the sample
def test_a_sample_of_the_wide_study_no_accepted_plant_fails():
    rows = [study_one(job) for job in WIDE]
    accepted = {(r["case"], r["index"]) for r in rows if r["check_accepts"]}
    assert accepted >= set(ACCEPTED), rows     # else the soundness below proves nothing
    assert all(r["held"] for r in rows if r["check_accepts"]), rows
