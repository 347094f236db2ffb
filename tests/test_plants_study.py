"""The wide study (bench/plants_study.py) and its time-invariant adversary
(verification/class_search.py): the study plants' own Lipschitz bounds, the adversary's member,
the table. docs/sampled-data.md, "The wide study, and how much a sound check can accept"."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import designed

from stt_codegen_bench import plants_study
from stt_codegen.design.samples import sample_tube
from stt_codegen.spec.assumptions import Assumptions
from stt_codegen.verification.class_search import (class_matrices, fixed_directions, replay,
                                             search_time_invariant, unit_skew, within_class)

PLANTS = [(case, i) for case in plants_study.CASES for i in (0, 1, 5)]


def _functions(p: dict, spec):
    """The study plant's ``f`` and ``g``, as in plants_study's simulation."""
    centre = (np.array(spec.state_space.lower) + np.array(spec.state_space.upper)) / 2
    k_mat = unit_skew(p["skew_axis"])

    def f(x):
        return p["f_amp"] * np.sin(p["W"] @ x + p["phi"]) + p["L"] @ (x - centre)

    def g(x):
        return p["sym"] + p["skew"] * np.tanh(p["v"] @ x) * k_mat
    return f, g


@pytest.mark.parametrize("case,index", PLANTS)
def test_own_lipschitz_bounds_hold_and_are_nearly_reached(case, index):
    spec = designed(case)[0]
    p = plants_study.plant_parameters(plants_study.draw(case, index))
    bounds = plants_study.own_bounds(p, spec, lipschitz=True)
    assert plants_study.own_bounds(p, spec).input_gain_lipschitz is None
    f, g = _functions(p, spec)
    g_rates, f_rates = (np.array(bounds.input_gain_lipschitz), np.array(bounds.drift_lipschitz))
    assert g_rates.shape == f_rates.shape == (3,) and (g_rates >= 0).all()
    lower, upper = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    rng = np.random.default_rng([index, 5])
    for _ in range(300):                                 # any two points: the bound holds
        x, y = rng.uniform(lower, upper), rng.uniform(lower, upper)
        step = np.abs(x - y)
        assert np.linalg.norm(g(x) - g(y), 2) <= g_rates @ step * (1 + 1e-12) + 1e-15
        assert np.linalg.norm(f(x) - f(y)) <= f_rates @ step * (1 + 1e-12) + 1e-15
    v = p["v"]
    for j in range(3):            # small moves along one state: reached within a factor 1.25
        best_g = best_f = 0.0     # (g's where v . x = 0, tanh's steepest: the bounds hold
        for _ in range(400):      # on all of R^n, the state space need not contain it)
            x = rng.uniform(lower, upper)
            x_flat = x - (v @ x) / (v @ v) * v
            step = np.eye(3)[j] * 1e-4
            best_g = max(best_g, np.linalg.norm(g(x_flat) - g(x_flat + step), 2) / 1e-4)
            best_f = max(best_f, np.linalg.norm(f(x) - f(x + step)) / 1e-4)
        assert best_g <= g_rates[j] * (1 + 1e-9) and best_f <= f_rates[j] * (1 + 1e-9)
        assert best_g >= 0.8 * g_rates[j]
        assert best_f >= 0.8 * f_rates[j]


def test_fixed_directions_are_unit_and_seeded():
    units = fixed_directions(3)
    assert units.shape == (10, 3)
    assert np.allclose(np.linalg.norm(units, axis=1), 1.0)
    assert np.array_equal(units, fixed_directions(3))
    assert not np.array_equal(units, fixed_directions(3, seed=1))


def test_the_time_invariant_adversary_breaks_a_weak_class_with_a_constant_member():
    """``g`` barely acts (``g_min`` 0.02) and the drift is large: a constant plant of the
    class drifts out of the tube. The member found holds ``g`` and ``f`` over the whole
    path, both in the class, and only ``w`` is chosen, within its bound."""
    spec, design, _ = designed("omnirobot-s1")
    samples = sample_tube(design)
    bounds = Assumptions((0.02, 0.05), 0.0, 0.0, 5.0, 0.2)
    found = search_time_invariant(design, samples, bounds)
    assert found is not None and found.strategy.startswith("time-invariant pair ")
    assert found.depth >= 1.0 and found.gain_rates and found.drift_rates
    k = len(found.gains)
    assert k == round(found.time * design.rate_hz) and k > 0
    assert (found.gains == found.gains[0]).all() and within_class(found.gains[0], bounds)
    assert any(np.array_equal(found.gains[0], m) for m in class_matrices(bounds, 3))
    assert (found.drifts == found.drifts[0]).all()
    assert np.linalg.norm(found.drifts[0]) == pytest.approx(bounds.drift_bound)
    w = found.pushes - found.drifts
    assert np.allclose(np.linalg.norm(w, axis=1), bounds.disturbance_bound)
    assert replay(design, found, backend="python")                # the deployed law agrees
    again = search_time_invariant(design, samples, bounds)        # derandomized
    assert again.strategy == found.strategy and np.array_equal(again.pushes, found.pushes)


def _row(case, index, held=True, accepts=False, accepts_lip=False, **found):
    row = {"case": case, "index": index, "held": held, "check_accepts": accepts,
           "check_accepts_lipschitz": accepts_lip}
    if held:
        row.update({k: found.get(k) for k in plants_study.ADVERSARIES})
    return row


def test_the_table_counts_each_column_and_flags_what_the_check_may_not_accept():
    member = {"strategy": "x", "time": 0.1, "dimension": 0, "depth": 1.2, "max_abs_e": 0.9,
              "replayed_on_c": True}
    s1, s2, s3 = plants_study.CASES
    rows = [_row(s1, 0, switching=member),                                   # only switching
            _row(s1, 1, accepts_lip=True, switching=member),                 # fine: Lipschitz
            _row(s1, 2, switching=member, lipschitz=member, time_invariant=member),
            _row(s2, 0, held=False),
            _row(s2, 1, accepts=True, accepts_lip=True),                     # unbroken, both
            _row(s3, 0, accepts_lip=True, lipschitz=member)]                 # unsound
    counts = plants_study.table(rows)
    assert counts[0] == [6, 5, 3, 2, 1, 3, 1, 3, 2, 1]
    assert counts[1] == [3, 3, 3, 1, 1, 2, 0, 1, 1, 0]
    assert counts[2] == [2, 1, 0, 0, 0, 1, 1, 1, 1, 0]
    assert counts[3] == [1, 1, 0, 1, 0, 0, 0, 1, 0, 1]
    assert [(r["case"], r["index"]) for r in plants_study.unsound(rows)] == [(s3, 0)]
    text = plants_study.summary(rows)
    for column in plants_study.COLUMNS:
        assert column in text
    assert "| all | 6 | 5 | 3 | 2 | 1 | 3 | 1 | 3 | 2 | 1 |" in text
    assert plants_study.unsound([_row(s2, 2, held=False, accepts=True)])


@pytest.mark.slow
def test_recheck_recomputes_the_check_columns_only():
    case, index = "omnirobot-s3", 1
    gain = designed(case)[1].gain
    fresh = plants_study.check_columns(case, index, gain)
    assert set(fresh) == {"check_accepts", "check_s", "check_fails_at",
                          "check_accepts_lipschitz", "check_s_lipschitz",
                          "check_fails_at_lipschitz"}
    stale = {"case": case, "index": index, "gain": gain, "held": True, "switching": None,
             "check_accepts": not fresh["check_accepts"], "check_s": -1.0,
             "check_fails_at": 123.0, "check_accepts_lipschitz": None}
    row, = plants_study.recheck([stale], workers=1)
    assert row["switching"] is None and row["held"] is True
    for key in ("check_accepts", "check_fails_at", "check_accepts_lipschitz",
                "check_fails_at_lipschitz"):
        assert row[key] == fresh[key]
    assert row["check_s"] >= 0.0
