"""The class search (verification/class_search.py): members of a plant class that leave the tube.

A counterexample is a plant of the class under the sampled law (13): its gains are members
of the class, its push within the bound, and the deployed controller (the generated
Python), replayed on it, reports the state outside the tube. The sampled check, being
sound, must reject every class the search breaks; and the classes the check accepts must
resist the search (docs/sampled-data.md, "How much a sound check can accept")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import designed

from stt_codegen_bench import plants_study
from stt_codegen.verification.class_search import class_matrices, replay, search_class, within_class
from stt_codegen.design.samples import sample_tube
from stt_codegen.spec.assumptions import Assumptions
from stt_codegen.design.certificate.plant_class import PlantClass
from stt_codegen.design.certificate.sampled import check_sampled

_SAMPLES: dict = {}


def _tube(case: str):
    spec, design, _ = designed(case)
    if case not in _SAMPLES:
        _SAMPLES[case] = sample_tube(design)
    return spec, design, _SAMPLES[case]


def _study_bounds(case: str, index: int, decoupled: bool = False) -> Assumptions:
    """The wide study's plant ``index``'s own bounds; ``decoupled``: with its skew and
    coupling set to 0 (a narrower class, of diagonal ``g``)."""
    spec = designed(case)[0]
    bounds = plants_study.own_bounds(plants_study.plant_parameters(
        plants_study.draw(case, index)), spec)
    return (dataclasses.replace(bounds, input_gain_skew=0.0, input_gain_coupling=0.0)
            if decoupled else bounds)


@pytest.mark.parametrize("bounds", [
    Assumptions((0.3, 2.0), 0.6, 1.0, 1.0, 0.1),
    Assumptions((0.5, 0.5), 0.0, 0.0, 1.0, 0.1),
    Assumptions((0.36, 1.0), 0.93, 0.93, 0.0, 0.17, blocks=((0, 1), (2,))),
    Assumptions((0.2, 3.0), 0.9, 0.5, 1.0, 0.1),
], ids=["coupled", "diagonal", "robot-blocks", "coupling-caps-skew"])
def test_the_members_are_in_the_class_and_reach_its_extremes(bounds):
    members = class_matrices(bounds, 3)
    assert members and all(within_class(g, bounds) for g in members)
    eig = np.array([np.linalg.eigvalsh(0.5 * (g + g.T))[[0, -1]] for g in members])
    assert eig[:, 0].min() == pytest.approx(bounds.input_gain[0])
    assert eig[:, 1].max() == pytest.approx(bounds.input_gain[1])
    skew = max(np.linalg.norm(0.5 * (g - g.T), 2) for g in members)
    rows = max(np.linalg.norm(g - np.diag(np.diag(g)), axis=1).max() for g in members)
    assert skew <= bounds.input_gain_skew * (1 + 1e-9)
    assert rows <= bounds.input_gain_coupling * (1 + 1e-9) + 1e-12
    if bounds.input_gain_coupling >= 2 * bounds.input_gain_skew > 0:
        assert skew == pytest.approx(bounds.input_gain_skew)   # the largest skew is tried
    for g in members:                                          # nothing between blocks
        for block in bounds.coupled_blocks(3):
            others = [j for j in range(3) if j not in block]
            assert not g[np.ix_(block, others)].any()


def test_within_class_refuses_what_is_outside():
    bounds = Assumptions((0.5, 2.0), 0.3, 0.6, 0.0, 0.0)
    assert within_class(np.diag([0.5, 1.0, 2.0]), bounds)
    assert not within_class(np.diag([0.49, 1.0, 2.0]), bounds)       # g_min
    assert not within_class(np.diag([0.5, 1.0, 2.01]), bounds)       # g_max
    skewed = np.diag([1.0, 1.0, 1.0]) + 0.31 * np.array([[0, -1, 0], [1, 0, 0], [0, 0, 0]])
    assert not within_class(skewed, bounds)                          # skew
    sym = np.array([[1.2, 0.5, 0.4], [0.5, 1.2, 0.0], [0.4, 0.0, 1.2]])
    assert np.linalg.eigvalsh(sym).min() >= 0.5           # in the eigenvalue range, but
    assert not within_class(sym, bounds)                  # its first row's coupling is 0.64
    crossing = np.eye(3)
    crossing[0, 2] = 0.1
    assert within_class(crossing, bounds)
    blocked = Assumptions((0.5, 2.0), 0.3, 0.6, 0.0, 0.0, blocks=((0, 1), (2,)))
    assert not within_class(crossing, blocked)            # x3's input moves x1


def test_a_counterexample_is_a_member_that_the_deployed_controller_reports_outside():
    """Replayed on the generated Python controller: every interval's ``g`` is in the class,
    the push is within the bound, and the controller reports the state outside the tube
    (here exactly at the search's exit: one interval short, it is still inside)."""
    case = "omnirobot-s1"
    spec, design, samples = _tube(case)
    bounds = _study_bounds(case, 0)
    found = search_class(design, samples, bounds)
    assert found is not None and found.depth >= 1.0 and found.max_abs_e < 1.0
    steps = len(found.gains)
    assert len(found.pushes) == steps and np.isclose(samples.t[steps], found.time)
    push = bounds.drift_bound + bounds.disturbance_bound
    assert all(within_class(g, bounds) for g in found.gains)
    assert np.linalg.norm(found.pushes, axis=1).max() <= push * (1 + 1e-12)
    assert replay(design, found, "python")
    # the same path one interval short ends inside the tube: the exit is where it says
    early = dataclasses.replace(found, gains=found.gains[:-1], pushes=found.pushes[:-1])
    assert not replay(design, early, "python")


@pytest.mark.slow          # about 10 s; the Lipschitz counterexample's test stays fast
def test_the_robot_class_over_the_whole_heading_range_has_a_member_that_leaves():
    """Why the check refuses the robot's bounds taken over the whole state space
    (tests/test_verify_coupled.py): a member of that class whose ``g`` may jump leaves the
    tube; only the bounds on the tube (the heading's range there) are proved. With the
    robot's own Lipschitz bound (``g = R(x3)`` moves by at most ``|dx3|``) the search finds
    no member that leaves."""
    spec, design, samples = _tube("omnirobot-s1")
    bounds = spec.assumptions
    assert bounds.blocks == ((0, 1), (2,)) and bounds.input_gain_lipschitz == (0.0, 0.0, 1.0)
    jumping = dataclasses.replace(bounds, input_gain_lipschitz=None, drift_lipschitz=None)
    found = search_class(design, samples, jumping)
    assert found is not None and not found.lipschitz
    assert not check_sampled(design, samples, PlantClass(bounds)).passed
    assert search_class(design, samples, bounds, held_runs=0) is None


def _path(design, samples, found):
    """The states at the samples of a counterexample's path (law (13), numpy reference)."""
    from stt_codegen.tube import reference
    dt = 1.0 / design.rate_hz
    x = np.array(design.initial_state, dtype=float)
    states = [x]
    for k, (g, push) in enumerate(zip(found.gains, found.pushes)):
        u = reference.law(design.gain, x[None, :], samples.gamma_lower[k][None, :],
                          samples.gamma_upper[k][None, :])[0][0]
        x = x + dt * (g @ u + push)
        states.append(x)
    return np.array(states)


@pytest.mark.parametrize("index, rates, drift_rates", [
    pytest.param(0, (0.0, 0.0, 300.0), None, marks=pytest.mark.slow),
    pytest.param(9, (0.0, 0.0, 1.0), None, marks=pytest.mark.slow),
    (9, (0.0, 0.0, 300.0), (5.0, 5.0, 5.0))])
def test_a_lipschitz_counterexample_respects_the_declared_rates(index, rates, drift_rates):
    """In the Lipschitz mode every interval's ``g`` is in the class and differs from the
    previous one by at most ``sum_j L_j |dx_j|`` (spectral norm), ``f`` likewise with its
    own rates and ``|f| <= drift_bound``, ``|w| <= disturbance_bound``; and the deployed
    controller confirms the exit."""
    case = "omnirobot-s1"
    spec, design, samples = _tube(case)
    bounds = dataclasses.replace(_study_bounds(case, index), input_gain_lipschitz=rates,
                                 drift_lipschitz=drift_rates)
    found = search_class(design, samples, bounds, held_runs=0)
    assert found is not None and found.gain_rates and found.depth >= 1.0
    assert found.drift_rates == (drift_rates is not None)
    assert all(within_class(g, bounds) for g in found.gains)
    moves = np.abs(np.diff(_path(design, samples, found), axis=0))[:-1]    # (K-1, n)
    changes = np.linalg.norm(np.diff(found.gains, axis=0), 2, axis=(1, 2))
    assert np.all(changes <= moves @ np.array(rates) * (1 + 1e-9) + 1e-12)
    assert changes.max() > 0.0                           # the adversary does use its budget
    drifts = found.drifts
    disturbance = np.linalg.norm(found.pushes - drifts, axis=1)
    if drift_rates is None:                              # f + w together, as without rates
        assert np.linalg.norm(found.pushes, axis=1).max() <= \
            (bounds.drift_bound + bounds.disturbance_bound) * (1 + 1e-12)
    else:
        assert np.linalg.norm(drifts, axis=1).max() <= bounds.drift_bound * (1 + 1e-12)
        assert disturbance.max() <= bounds.disturbance_bound * (1 + 1e-12)
        f_changes = np.linalg.norm(np.diff(drifts, axis=0), axis=1)
        assert np.all(f_changes <= moves @ np.array(drift_rates) * (1 + 1e-9) + 1e-12)
    assert replay(design, found, "python")


def test_without_rates_the_search_is_unchanged():
    """A class declared without Lipschitz bounds is searched as before: the jumping
    adversary, and the same counterexample whatever rates it would have been given."""
    case = "omnirobot-s1"
    spec, design, samples = _tube(case)
    bounds = _study_bounds(case, 0)
    assert bounds.input_gain_lipschitz is None and bounds.drift_lipschitz is None
    found = search_class(design, samples, bounds, held_runs=0)
    assert found is not None and not found.lipschitz and found.strategy == "greedy max"
    huge = dataclasses.replace(bounds, input_gain_lipschitz=(1e9,) * 3)
    same = search_class(design, samples, huge, held_runs=0)
    assert same.time == found.time and same.depth == pytest.approx(found.depth)


@pytest.mark.parametrize("case,index,decoupled", [
    ("omnirobot-s1", 0, False), ("omnirobot-s1", 9, False), ("omnirobot-s2", 1, False),
    ("omnirobot-s3", 0, False), ("omnirobot-s1", 2, True)])
def test_the_check_rejects_the_classes_the_search_breaks(case, index, decoupled):
    spec, design, samples = _tube(case)
    bounds = _study_bounds(case, index, decoupled)
    assert search_class(design, samples, bounds) is not None
    assert not check_sampled(design, samples, bounds).passed


@pytest.mark.slow
@pytest.mark.parametrize("case,index,decoupled", [
    ("omnirobot-s1", 47, False), ("omnirobot-s3", 41, False), ("omnirobot-s3", 44, False),
    ("omnirobot-s1", 9, True)])
def test_the_classes_the_check_accepts_resist_the_search(case, index, decoupled):
    """The wide study's plants the check accepts (and one decoupled class it accepts): a
    counterexample here would be a hole in the check (the search is independent of its
    argument)."""
    spec, design, samples = _tube(case)
    bounds = _study_bounds(case, index, decoupled)
    assert check_sampled(design, samples, bounds).passed
    assert search_class(design, samples, bounds) is None
