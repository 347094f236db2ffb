"""bench stl: stlpy's scenarios written as specs, the rtamt judge, the CLI and its errors."""

from __future__ import annotations

import json
import sys
import tomllib

import numpy as np
import pytest

from stt_codegen.cli import main
from stt_codegen.errors import SpecError

pytest.importorskip("stlpy", reason='stlpy is not installed: pip install ".[stl]"')
pytest.importorskip("rtamt", reason='rtamt is not installed: pip install ".[stl]"')

from stt_codegen_bench.stl_bench import (judge_positions, run_stl_bench,  # noqa: E402
                                         solve_with_stlpy)
from stt_codegen_bench.stl_judge import (formula_text, robustness,  # noqa: E402
                                         stlpy_robustness)
from stt_codegen_bench.stl_scenarios import (DEFINED_BOUNDS, SCENARIOS,  # noqa: E402
                                             SKIPPED, double_integrators, make_scenario,
                                             scenario_names, scenario_spec, spec_toml,
                                             step_seconds)
from stt_codegen.spec.loader import Spec  # noqa: E402


def _signal(scenario, positions: np.ndarray) -> np.ndarray:
    y = np.full((positions.shape[0], scenario.GetSystem().p), np.nan)
    y[:, :2] = positions
    return y


@pytest.mark.parametrize("name", scenario_names())
def test_rtamt_equals_stlpy_at_the_samples(name):
    """The formula read back into rtamt gives stlpy's own robustness at the samples, on
    random walks (mostly violating) and on walks drawn near the scenario's regions."""
    sc = make_scenario(name)
    formula, dt = sc.GetSpecification(), step_seconds(sc)
    rng = np.random.default_rng(1)
    times = np.arange(sc.T + 1) * dt
    for _ in range(4):
        walk = np.cumsum(rng.normal(0.0, 0.6, (sc.T + 1, 2)), axis=0) + rng.uniform(1, 9, 2)
        y = _signal(sc, walk)
        expected = stlpy_robustness(formula, np.nan_to_num(y))
        assert robustness(formula, dt, times, y, dt) == pytest.approx(expected, abs=1e-12)


def test_formula_text_reads_the_unrolled_operators():
    text, predicates = formula_text(make_scenario("DoorPuzzle").GetSpecification(), 1.0)
    assert text.count("until[0,25]") == 2 and text.count("always[0,25]") == 1
    assert text.count("eventually[0,25]") == 1 and len(predicates) == 40
    # evaluated on a signal ending at 25 s, the top-level untils are rtamt's unbounded one
    whole, _ = formula_text(make_scenario("DoorPuzzle").GetSpecification(), 1.0, 25.0)
    assert whole.count(" until ") == 2 and "until[" not in whole
    # under a temporal operator an until keeps its window
    inner = make_scenario("DoorPuzzle").GetSpecification().subformula_list[-1]
    assert "always[0,3]" in formula_text(inner.always(0, 3), 1.0, 25.0)[0]
    text, _ = formula_text(make_scenario("EitherOr").GetSpecification(), 1.0)
    assert "eventually[0,15]" in text and "always[0,5]" in text
    text, _ = formula_text(make_scenario("NonlinearReachAvoid").GetSpecification(), 0.1)
    assert "always[0,1.5]" in text and "eventually[0,1.5]" in text


def test_grid_catches_a_cut_between_samples():
    """ReachAvoid: samples on the diagonal through the obstacle [3, 5] x [4, 6], 0.1 clear of
    it at every sample but jumping across it in one step, then at the goal: satisfied at the
    samples, violated on the 100 Hz grid (the segment crosses the obstacle's middle)."""
    sc = make_scenario("ReachAvoid")
    path = [(1.0, 2.0), (2.0, 3.0), (2.9, 3.9), (5.1, 6.1), (6.5, 7.5)] + [(7.5, 8.5)] * 6
    times = np.arange(len(path)) * 1.0
    scores = judge_positions(sc.GetSpecification(), 1.0, sc.T, 6, times, np.array(path))
    assert scores["samples"] == pytest.approx(0.1)
    assert scores["stlpy_samples"] == pytest.approx(0.1)
    assert scores["grid"] == pytest.approx(-1.0, abs=0.01)   # the obstacle's centre


@pytest.mark.parametrize("name", scenario_names())
def test_every_spec_loads(name):
    doc = scenario_spec(name)
    spec = Spec.from_dict(doc)
    # the TOML file written by --specs is the same spec
    assert Spec.from_dict(tomllib.loads(spec_toml(doc, "h"))).source_hash == spec.source_hash
    sc = make_scenario(name)
    assert spec.prescribed_time == pytest.approx(sc.T * step_seconds(sc))
    lower, upper = doc["state_space"]["lower"], doc["state_space"]["upper"]
    for entry in doc.get("obstacles", []):   # clipped to the field of view
        if "lower" in entry:
            assert all(lo >= l0 for lo, l0 in zip(entry["lower"], lower))
            assert all(hi <= h0 for hi, h0 in zip(entry["upper"], upper))


@pytest.mark.parametrize("name", [
    "EitherOr", pytest.param("RandomMultitarget", marks=pytest.mark.slow), "DoorPuzzle",
    "NonlinearReachAvoid"])
def test_scenarios_with_a_bound_design_within_it(name):
    """The examples' bounds (|v| <= 1, DoorPuzzle 2; the unicycle's |v| <= 10,
    |omega| <= 5) are kept: each design is proved to keep law (13) within them (the legs'
    times follow their paths, the cruise profile's peak is 1.25 times its mean, the
    shortest plan first; the unicycle's via tube with cruise segments) and certified."""
    from stt_codegen.design.search import design_tube
    doc = scenario_spec(name)
    bound = tuple(doc["actuator"]["input_bound"])
    design = design_tube(Spec.from_dict(doc))
    assert design.certificate.passed and design.tube.input_bound == bound
    assert design.input_proof.proved and design.input_proof.meets(bound)
    assert max(p / b for p, b in zip(design.input_proof.peak, bound)) <= 1.0


def test_specs_carry_the_formulas_structure():
    either = scenario_spec("EitherOr")
    (stay,) = either["tasks"]
    assert stay["kind"] == "stay" and stay["duration"] == 5.0 and len(stay["any_of"]) == 2
    assert stay["window"] == [0.0, 20.0] and either["actuator"]["input_bound"] == [1.0, 1.0]
    assert len(scenario_spec("NarrowPassage")["target"]["any_of"]) == 2
    multi = scenario_spec("RandomMultitarget")
    assert len(multi["tasks"]) == 4 and multi["task_order"] == {"order": "any"}
    assert all(len(t["any_of"]) == 2 for t in multi["tasks"])
    door = scenario_spec("DoorPuzzle")
    assert [o.get("active_until") for o in door["obstacles"]][-2:] == ["T1", "T2"]
    assert [t["kind"] for t in door["tasks"]] == ["reach", "reach"]
    assert "actuator" not in scenario_spec("ReachAvoid")   # its example passes no bounds
    unicycle = scenario_spec("NonlinearReachAvoid")
    assert unicycle["prescribed_time"] == pytest.approx(1.5)
    assert unicycle["plant"] == {"model": "omnidirectional"}
    assert unicycle["obstacles"] == [{"center": [3.5, 5.0], "radius": 1.5}]


@pytest.mark.parametrize("name", double_integrators())
def test_a_double_integrator_is_also_written_as_itself(name):
    """``order="second"``: the double-integrator model with unit mass (stlpy's input is the
    acceleration), the example's |v| as the velocity bound and its |u| as the input bound
    (ReachAvoid's defined but unpassed ones), everything else as the first-order spec."""
    first, doc = scenario_spec(name), scenario_spec(name, order="second")
    spec = Spec.from_dict(doc)
    force, speed = DEFINED_BOUNDS.get(name, (SCENARIOS[name].input_bound,
                                             SCENARIOS[name].velocity_bound))
    assert spec.second_order.model == "double-integrator"
    assert spec.second_order.parameters == (1.0,) and spec.second_order.input_gain == (1.0, 1.0)
    assert spec.second_order.velocity_bound == tuple(speed)
    assert spec.input_bound == tuple(force) and max(force) == 0.5
    assert doc["name"] == first["name"] + "-second-order"
    same = {k: v for k, v in doc.items() if k not in ("name", "plant", "actuator")}
    same["state_space"] = {k: v for k, v in same["state_space"].items()
                           if k != "velocity_bound"}
    assert same == {k: v for k, v in first.items() if k not in ("name", "actuator")}


@pytest.mark.parametrize("order", ["first", "second"])
def test_the_disturbance_is_the_project_default_or_the_one_asked(order):
    """Without ``disturbance`` the spec takes the project's ``|w_i| <= 0.1``; with 0 (stlpy's
    model) it says so and the loaded spec has none; the rest of the document is the same."""
    default = scenario_spec("ReachAvoid", order=order)
    none = scenario_spec("ReachAvoid", order=order, disturbance=0.0)
    assert Spec.from_dict(default).disturbance_amplitude == 0.1
    assert none["plant"]["disturbance_amplitude"] == 0.0
    assert Spec.from_dict(none).disturbance_amplitude == 0.0
    none["plant"].pop("disturbance_amplitude")
    assert {k: v for k, v in none.items() if v} == default


def test_only_a_double_integrator_has_a_second_order_spec():
    with pytest.raises(ValueError, match="'second' for a double integrator"):
        scenario_spec("NonlinearReachAvoid", order="second")
    with pytest.raises(ValueError, match="order 'third'"):
        scenario_spec("ReachAvoid", order="third")
    assert "NonlinearReachAvoid" not in double_integrators()


def test_stepping_stones_is_skipped_with_its_reason():
    with pytest.raises(KeyError, match="union safe set"):
        scenario_spec("SteppingStones")
    (row,) = run_stl_bench(["SteppingStones"])["rows"]
    assert not row["written"] and "union safe set" in row["reason"]
    assert "SteppingStones" in SKIPPED


def test_stepping_stones_has_no_continuous_path():
    """The reason given for skipping it: the stones connected to x0 (closed boxes that share
    a point) do not include the target stone."""
    from stlpy.benchmarks import SteppingStones
    stones = SteppingStones(15, 15, seed=1).stones   # examples/stepping_stones.py

    def meets(a, b):
        return a[0] <= b[1] and b[0] <= a[1] and a[2] <= b[3] and b[2] <= a[3]

    reached = {i for i, s in enumerate(stones) if s[0] <= 2.0 <= s[1] and s[2] <= 1.3 <= s[3]}
    frontier = list(reached)
    while frontier:
        i = frontier.pop()
        for j, other in enumerate(stones):
            if j not in reached and meets(stones[i], other):
                reached.add(j)
                frontier.append(j)
    assert len(reached) == 3 and len(stones) - 1 not in reached


def test_missing_packages_and_unknown_names(monkeypatch, capsys):
    assert main(["bench", "stl", "--scenarios", "Nope"]) == 2
    assert "scenarios: unknown scenario 'Nope'" in capsys.readouterr().err
    with pytest.raises(SpecError, match="solver: unknown solver 'gurobi'"):
        run_stl_bench(["ReachAvoid"], solver="gurobi")
    assert main(["bench", "stl", "--scenarios", "ReachAvoid", "--disturbance", "-1"]) == 2
    assert "disturbance: must be a number >= 0" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "rtamt", None)   # import rtamt now fails
    with pytest.raises(SpecError, match=r"pip install \"\.\[stl\]\""):
        run_stl_bench(["ReachAvoid"])


@pytest.mark.bench
def test_bench_stl_designs_and_satisfies(tmp_path, monkeypatch, capsys):
    """Two scenarios end to end (one with the example's bound and an or-target), stlpy's
    solver beside: every designed run satisfied with C, robustness > 0 on the 100 Hz grid."""
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    code = main(["bench", "stl", "--scenarios", "ReachAvoid,NarrowPassage", "--json",
                 "--specs", str(tmp_path / "specs"), "--order", "first"])
    assert code == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert [r["scenario"] for r in rows] == ["ReachAvoid", "NarrowPassage"]
    for row in rows:
        assert row["written"] and row["designed"] and row["satisfied"]
        assert row["grid"] > 0 and row["samples"] > 0
        assert row["stlpy_samples"] == pytest.approx(row["samples"], abs=1e-12)
        assert row["solver"]["solver"] == "scipy"
    assert rows[1]["input_bound"] == [1.0, 1.0]
    assert max(rows[1]["peak_u"]) <= 1.0 + 1e-9
    assert sorted(p.name for p in (tmp_path / "specs").iterdir()) == [
        "stlpy-NarrowPassage.toml", "stlpy-ReachAvoid.toml"]


@pytest.mark.bench
def test_reach_avoid_as_a_double_integrator_names_a_time_then_certified(tmp_path,
                                                                        monkeypatch):
    """ReachAvoid as itself at |u| <= 0.5, |v| <= 1: refused at stlpy's 10 s, naming a
    prescribed time; the spec at that time is designed within both bounds and its C run
    satisfies stlpy's formula at the horizon that covers it (rtamt > 0 on the grid). The
    named time is reported over stlpy's horizon (the issue asks for at most 1.5; see
    docs/performance.md)."""
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    refused, longer = run_stl_bench(["ReachAvoid"], solver=None, orders=("second",),
                                    specs=tmp_path)["rows"]
    assert refused["variant"] == "second order" and not refused["designed"]
    named = refused["advice"]["prescribed_time"]
    assert refused["ratio"] == pytest.approx(named / 10.0)
    assert longer["variant"] == f"second order, t_c = {named:g} s"
    assert longer["designed"] and longer["satisfied"] and longer["grid"] > 0
    assert all(p <= 0.5 + 1e-9 for p in longer["peak_u"])
    assert [p.name for p in tmp_path.glob("*.toml")] == ["stlpy-ReachAvoid-second-order.toml"]


@pytest.mark.bench
def test_narrow_passage_as_a_double_integrator_is_certified_at_stlpy_s_horizon(
        tmp_path, monkeypatch):
    """NarrowPassage as itself at |u| <= 0.5, |v| <= 1, its target one of two boxes:
    designed at stlpy's own 25 s within both bounds (refused there, naming 31 s, before the
    change of ``r`` was bounded with its causes together), and its C run satisfies
    stlpy's formula (rtamt > 0 on the grid)."""
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    rows = run_stl_bench(["NarrowPassage"], solver=None, orders=("second",),
                         specs=tmp_path)["rows"]
    assert len(rows) == 1
    row = rows[0]
    assert row["variant"] == "second order" and row["designed"], row
    assert row["satisfied"] and row["grid"] > 0
    assert all(p <= 0.5 + 1e-9 for p in row["peak_u"])


@pytest.mark.bench
def test_drake_branch_and_bound_runs_or_says_why():
    """stlpy's MICP with Drake's branch and bound (no licence), importable beside Drake 1.51
    through the two aliases: on ReachAvoid it gives a plan judged like any other, or (as on
    this machine, the example passing no bounds) a note; the unicycle is refused by name."""
    pytest.importorskip("pydrake", reason="Drake is not installed: pip install drake")
    assert "MICP needs a linear system" in solve_with_stlpy(
        "NonlinearReachAvoid", solver="drake-bnb")["note"]
    plan = solve_with_stlpy("ReachAvoid", solver="drake-bnb")
    assert plan["solver"] == "drake-bnb"
    if plan["plan"] is None:
        assert plan["note"].startswith(("failed:", "no solution"))
    else:
        sc = make_scenario("ReachAvoid")
        scores = judge_positions(sc.GetSpecification(), 1.0, sc.T, 6, *plan["plan"])
        assert scores["samples"] == pytest.approx(scores["stlpy_samples"], abs=1e-12)


@pytest.mark.bench
def test_bench_stl_every_designed_run_is_satisfied(tmp_path, monkeypatch):
    """All scenarios without stlpy's solver: each is written, and every row designed (as
    written, or without the bound) is satisfied with C with robustness > 0 on the grid;
    every double-integrator example with a bound is designed within it, its run's peak
    input within it too."""
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    rows = run_stl_bench(solver=None, orders=("first",))["rows"]
    assert {r["scenario"] for r in rows if r["written"]} == set(scenario_names())
    designed = [r for r in rows if r["designed"]]
    assert designed
    for row in designed:
        assert row["satisfied"] and row["grid"] > 0, row["scenario"]
    within = {r["scenario"]: r for r in designed if r["input_bound"]}
    assert set(within) == {"EitherOr", "NarrowPassage", "RandomMultitarget", "DoorPuzzle",
                           "NonlinearReachAvoid"}
    assert not [r for r in rows if r["variant"] == "no bound"]   # none refused by its bound
    for row in within.values():
        assert all(p <= b + 1e-9 for p, b in zip(row["peak_u"], row["input_bound"]))
