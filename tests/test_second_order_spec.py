"""Second-order plants in the spec: a second-order ``[plant] model`` with
``initial.velocity``, ``state_space.velocity_bound`` and the second stage's
``[assumptions]`` (stt_codegen/spec/second_order.py, docs/spec-format.md)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.cases import bundled_spec_bytes
from stt_codegen.errors import SpecError
from stt_codegen.spec.plants import SECOND_ORDER_MODELS
from stt_codegen.spec.schema import json_schema

REPO = Path(__file__).resolve().parents[1]


def _doc(name: str = "second-order-quadrotor") -> dict:
    return tomllib.loads(bundled_spec_bytes(name).decode())


def _changed(changes: dict, name: str = "second-order-quadrotor") -> dict:
    """The bundled spec with ``{"table.key": value}`` set (``None``: the key removed)."""
    data = _doc(name)
    for path, value in changes.items():
        table, key = path.split(".")
        data.setdefault(table, {})
        if value is None:
            data[table].pop(key, None)
        else:
            data[table][key] = value
    return data


def test_bundled_second_order_cases_parse() -> None:
    spec = stt.load_spec("second-order-quadrotor")
    order = spec.second_order
    assert order.model == "quadrotor" and order.parameters == (1.2, 0.3, 9.81)
    assert order.velocity_bound == (3.0, 3.0, 3.0) and order.input_gain == (0.625, 1.25)
    assert order.drift_bounds == (1.5, 1.5, 11.31)   # gravity on the vertical axis only
    assert order.drift_bound == 11.31                 # their largest
    # the position stage is a single integrator; [assumptions] bound the second stage only
    assert spec.plant_model == "single-integrator" and spec.assumptions.declared == ()
    s1 = stt.load_spec("second-order-s1").second_order
    assert s1.model == "double-integrator" and s1.initial_velocity == (0.0, 0.0)
    assert stt.load_spec("omnirobot-s1").second_order is None


def test_no_second_order_table_and_the_models_are_plant_models() -> None:
    for name in ("second-order-s1", "second-order-quadrotor"):
        assert "second_order" not in _doc(name)
        assert _doc(name)["plant"]["model"] in SECOND_ORDER_MODELS
    data = _doc()
    data["second_order"] = {"model": "quadrotor"}
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(data)
    assert info.value.field == "second_order"
    schema = json_schema()
    assert "second_order" not in schema["properties"]
    assert set(SECOND_ORDER_MODELS) <= set(schema["$defs"]["PlantTable"]["properties"]["model"]
                                           ["enum"])


def test_defaults() -> None:
    data = _changed({"plant.parameters": None, "initial.velocity": None,
                     "state_space.velocity_bound": [3.0, 3.0, 2.0]})
    data.pop("assumptions")
    order = stt.Spec.from_dict(data).second_order
    assert order.parameters == (1.0, 0.3, 9.81)         # the model's nominal ones
    assert order.initial_velocity == (0.0, 0.0, 0.0)
    # the model's own class: g = 1 / mass; gravity plus the drag at the velocity bound
    assert order.input_gain == (1.0, 1.0)
    assert order.drift_bound == pytest.approx(max(0.3 * 3.0, 9.81 + 0.3 * 2.0), rel=1e-15)


def test_the_quadrotors_own_class_is_derived_from_its_parameters() -> None:
    data = _changed({"plant.parameters": [1.2, 0.3, 9.81],
                     "state_space.velocity_bound": [3.0, 3.0, 3.0]})
    data.pop("assumptions")
    spec = stt.Spec.from_dict(data)
    assert spec.second_order.input_gain == (1 / 1.2, 1 / 1.2)
    assert spec.second_order.drift_bound == pytest.approx(9.81 + 0.3 * 3.0 / 1.2, rel=1e-15)
    from stt_codegen.design.certificate.cascade_sampled import model_within_class
    assert model_within_class(spec)[0]          # the simulated plant is in the class
    # the drag grows with the velocity: without a velocity bound it must be declared
    data["state_space"].pop("velocity_bound")
    with pytest.raises(SpecError, match="give state_space.velocity_bound") as info:
        stt.Spec.from_dict(data)
    assert info.value.field == "assumptions.drift_bound"


def test_the_arms_own_class_holds_on_a_grid_of_its_states() -> None:
    """The arm's input gain and drift bound (convexity in cos q2, norms) against
    ``M(q)^-1`` and ``f`` evaluated on a grid of joint angles and velocities."""
    from stt_codegen.runtime.second_order_plants import input_matrix, second_order_rhs
    from stt_codegen.spec.second_order import MODELS, model_bounds
    params = (1.0, 1.2, 0.8, 1.1, 0.1, 0.07, 9.81)
    lower, upper, vmax = (-0.4, 0.3), (2.0, 2.9), (1.5, 2.0)
    own = model_bounds("two-link-arm", params, 2, vmax, lower, upper)
    g_of, rhs = input_matrix("two-link-arm", 2), second_order_rhs("two-link-arm", 2)
    eigen, drift = [], 0.0
    for q1 in np.linspace(lower[0], upper[0], 7):
        for q2 in np.linspace(lower[1], upper[1], 41):
            g = np.array(g_of([q1, q2], [0.0, 0.0], params))
            eigen += list(np.linalg.eigvalsh(0.5 * (g + g.T)))
            for v1 in (-vmax[0], 0.0, vmax[0]):
                for v2 in (-vmax[1], 0.0, vmax[1]):
                    acc = np.array(rhs([q1, q2], [v1, v2], [0.0, 0.0], [0.0, 0.0], params)[1])
                    drift = max(drift, float(np.max(np.abs(acc))))
    g_min, g_max = own.input_gain
    assert g_min <= min(eigen) and max(eigen) <= g_max
    assert min(eigen) < 1.05 * g_min and max(eigen) > 0.95 * g_max      # tight at the ends
    assert drift <= own.drift_bound
    assert len(MODELS["two-link-arm"].parameters) == len(params)


@pytest.mark.parametrize("change,field", [
    ({"plant.model": "two-link-arm"}, "plant.model"),
    ({"plant.parameters": [1.0, 0.3]}, "plant.parameters"),
    ({"plant.parameters": [-1.0, 0.3, 9.81]}, "plant.parameters"),
    ({"initial.velocity": [0.0, 0.0]}, "initial.velocity"),
    ({"initial.velocity": [0.0, 3.5, 0.0]}, "initial.velocity"),
    ({"state_space.velocity_bound": [3.0, 3.0]}, "state_space.velocity_bound"),
    ({"state_space.velocity_bound": [3.0, 0.0, 3.0]}, "state_space.velocity_bound"),
    ({"assumptions.input_gain": [2.0, 1.0]}, "assumptions.input_gain"),
    ({"assumptions.input_gain": [1.0]}, "assumptions.input_gain"),
    ({"assumptions.drift_bound": -1.0}, "assumptions.drift_bound"),
    # the first-order bounds have no meaning for the second stage
    ({"assumptions.input_gain_skew": 0.1}, "assumptions.input_gain_skew"),
    ({"assumptions.disturbance_bound": 0.3}, "assumptions.disturbance_bound"),
    ({"plant.a": [[0.0] * 3] * 3}, "plant.a"),
])
def test_bad_keys_name_the_field(change, field) -> None:
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(_changed(change))
    assert info.value.field == field or info.value.field.startswith(field + "[")


@pytest.mark.parametrize("key,value", [("initial.velocity", [0.0, 0.0, 0.0]),
                                       ("state_space.velocity_bound", [1.0, 1.0, 1.0]),
                                       ("plant.parameters", [1.0])])
@pytest.mark.parametrize("model", ["single-integrator", "omnidirectional", "linear"])
def test_velocity_keys_on_a_first_order_model_are_refused(key, value, model) -> None:
    data = _changed({key: value, "plant.model": model, "plant.parameters": None,
                     "initial.velocity": None, "state_space.velocity_bound": None})
    data[key.split(".")[0]][key.split(".")[1]] = value
    data.pop("assumptions")
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(data)
    assert info.value.field == key
    assert "only a second-order plant.model" in info.value.reason and model in info.value.reason


def test_a_first_order_spec_is_unchanged_by_the_second_order_keys() -> None:
    data = _changed({"plant.model": "single-integrator", "plant.parameters": None,
                     "initial.velocity": None, "state_space.velocity_bound": None,
                     "assumptions.drift_bound": 11.31})   # one number: |f(x)| of system (1)
    spec = stt.Spec.from_dict(data)        # [assumptions] are then the first-order ones
    assert spec.second_order is None and spec.plant_model == "single-integrator"
    assert spec.assumptions.input_gain == (0.625, 1.25)
    assert spec.assumptions.declared == ("input_gain", "drift_bound")


def test_schema_refuses_unknown_models_and_keys() -> None:
    for change, field in (({"plant.model": "blimp"}, "plant.model"),
                          ({"plant.thrust": 1.0}, "plant.thrust"),
                          ({"initial.initial_velocity": [0.0] * 3},
                           "initial.initial_velocity")):
        with pytest.raises(SpecError) as info:
            stt.Spec.from_dict(_changed(change))
        assert info.value.field == field


def test_the_documented_tables_load() -> None:
    text = (REPO / "docs" / "spec-format.md").read_text()
    block = re.search(r"^```text\n(\[state_space\].*?)^```$", text, flags=re.S | re.M)
    documented = tomllib.loads(block.group(1))
    data = _doc()
    for table, keys in documented.items():
        data[table] = {**data.get(table, {}), **keys}
    order = stt.Spec.from_dict(data).second_order
    assert order.model == "quadrotor" and order.velocity_bound == (3.0, 3.0, 3.0)


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


@pytest.mark.slow
def test_a_bad_table_exits_2_without_traceback(tmp_path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(bundled_spec_bytes("second-order-s1").decode().replace(
        "velocity = [0.0, 0.0]", "velocity = [0.0]"))
    out = _cli("design", str(path))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "initial.velocity" in out.stderr


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_simulate_runs_the_cascade(tmp_path) -> None:
    out = _cli("simulate", "second-order-s1", "--backend", "c", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["satisfied"] and data["stayed_in_velocity_tube"]
    assert len(data["max_abs_velocity"]) == 2 and data["backend"] == "c"
    assert not data["exceeded_velocity_bound"]


@pytest.mark.slow
def test_generate_writes_the_cascade(tmp_path) -> None:
    out = _cli("generate", "second-order-s1", "-o", str(tmp_path / "out"))
    assert out.returncode == 0, out.stderr
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["CMakeLists.txt", "Makefile", "manifest.json", "second_order_s1.c",
                     "second_order_s1.h", "second_order_s1.py", "second_order_s1_selftest.c",
                     "second_order_s1_vectors.json"]
    committed = REPO / "generated" / "second-order-s1" / "double" / "second_order_s1.c"
    assert (tmp_path / "out" / "second_order_s1.c").read_bytes() == committed.read_bytes()


SPECS = REPO / "tests" / "specs"


@pytest.mark.slow          # about 9 s; the printed states' test designs the same features fast
def test_tasks_and_moving_obstacles_take_the_same_tube_for_a_second_order_plant():
    """A second-order spec with a timed task and a moving obstacle loads and designs: the
    tube's certificate proves the task and the moving obstacle's avoidance for the
    positions, and the second stage is certified on that tube (design_tube certifies it
    whatever path designed the tube: here the moving obstacles' path)."""
    spec = stt.load_spec(SPECS / "second-order-tasks.toml")
    assert spec.order == 2 and spec.tasks and spec.moving_obstacles
    design = stt.design_tube(spec)
    names = {m.name for m in design.certificate.margins if m.passed}
    assert {"task T1 reach", "avoids moving obstacle 2"} <= names
    assert "second_stage" in design.__dict__      # computed (and cached) by design_tube
    stage, derivation = design.second_stage
    assert derivation["certificate"]["rate_hz"] == spec.rate_hz
    assert min(derivation["certificate"]["position_margin"],
               derivation["certificate"]["velocity_margin"]) > 0
    # a short run already judges the moving obstacle on the positions
    result = stt.simulate(design, horizon=1.0)
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    assert not result.collision and result.tasks[0].task == "T1"


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_a_second_order_task_with_a_moving_obstacle_is_satisfied_and_verified() -> None:
    """The generated C of the cascade meets the task, clears the moving box, stays in both
    tubes and within the force bound; verify proves everything (exit 0), the sampled
    cascade and the force bound included."""
    design = stt.design_tube(stt.load_spec(SPECS / "second-order-tasks.toml"))
    result = stt.simulate(design, backend="c")
    assert result.satisfied, result.to_json()
    assert all(task.met for task in result.tasks) and result.min_obstacle_clearance > 0
    assert result.stayed_in_tube and result.stayed_in_velocity_tube
    out = _cli("verify", str(SPECS / "second-order-tasks.toml"), "--all")
    assert out.returncode == 0, out.stdout[-3000:]
    assert "PASS  cascade.sampled: proved" in out.stdout
    assert "PASS  tube.task_T1_reach" in out.stdout
    assert "PASS  tube.avoids_moving_obstacle_2" in out.stdout
    assert "PASS  cascade.input_bound" in out.stdout          # [actuator]: forces in N
    assert all(u <= b for u, b in zip(result.max_abs_u, design.spec.input_bound))


@pytest.mark.embedded
def test_the_second_order_task_spec_on_the_cortex_m4f() -> None:
    """The same design's generated C (single precision) in the firmware's closed loop:
    satisfied, never outside a tube, never clamped."""
    from stt_codegen.embedded.cascade_loop import run_cascade_embedded
    report = run_cascade_embedded(stt.design_tube(stt.load_spec(
        SPECS / "second-order-tasks.toml")))
    assert report["satisfied"], report
    assert report["outside_position"] == report["outside_velocity"] == report["invalid"] == 0
    assert report["input_clamped"] == 0
    # the task and the moving box, judged on the firmware's own printed states
    assert [t["met"] for t in report["tasks"]] == [True] and report["moving_clearance"] > 0


@pytest.mark.slow
def test_printed_states_are_judged_on_the_tasks_and_the_moving_obstacles():
    """judge_printed (the firmware runs' judge of both orders) on the states of a host run
    of the second-order task spec, every tenth step: met; the same states judged against
    the task's box moved away, or against the moving box put on the run's path, are not."""
    from dataclasses import replace
    from stt_codegen.embedded.programs import judge_printed
    design = stt.design_tube(stt.load_spec(SPECS / "second-order-tasks.toml"))
    result = stt.simulate(design, backend="python")
    rate = design.tube.rate_hz
    steps = np.rint(result.trajectory.t * rate).astype(int)
    states = {int(k): np.concatenate([x, v]) for k, x, v in zip(
        steps, result.trajectory.x, result.trajectory.velocity) if k % 10 == 0}
    spec = design.spec
    judged = judge_printed(spec, states, rate)
    assert judged["met"] and judged["tasks"][0]["met"] and judged["moving_clearance"] > 0
    (task,) = spec.tasks
    away = replace(task, boxes=tuple(replace(b, lower=(4.4, 0.1), upper=(4.9, 0.6))
                                     for b in task.boxes))
    missed = judge_printed(replace(spec, tasks=(away,)), states, rate)
    assert not missed["met"] and not missed["tasks"][0]["met"]
    (box,) = spec.moving_obstacles
    k = len(result.trajectory.t) // 3                 # where the run is at a third of it
    centre = tuple(result.trajectory.x[k][list(box.dims)])
    on_path = replace(box, times=(0.0,), centres=(centre,), active=(0.0, 12.0))
    hit = judge_printed(replace(spec, moving_obstacles=(on_path,)), states, rate)
    assert not hit["met"] and hit["moving_clearance"] < 0


@pytest.mark.slow
def test_the_front_door_simulates_a_second_order_design_with_the_cascade(tmp_path):
    """``stt.simulate`` runs the cascade law on the spec's second-order model, in the one
    closed loop, with the one result type that ``plot_run`` draws; the command line's text
    output works."""
    design = design_of("second-order-s1")
    result = stt.simulate(design, horizon=0.5)
    assert isinstance(result, stt.SimulationResult) and result.tasks == []
    traj = result.trajectory
    assert traj.x.shape == traj.velocity.shape == traj.r.shape == (result.steps + 1, 2)
    assert result.stayed_in_velocity_tube and result.max_abs_velocity is not None
    with pytest.raises(SpecError) as info:
        stt.simulate(design, horizon=0.5, plant=object())
    assert info.value.field == "plant"
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "simulate",
                          "second-order-s1", "--backend", "reference", "--horizon", "0.5"],
                         capture_output=True, text=True, cwd=REPO, timeout=300)
    assert out.returncode == 1 and "Traceback" not in out.stderr   # not reached by 0.5 s
    assert "cascade law" in out.stdout
    assert stt.plot_run(design, result, tmp_path / "run.png").stat().st_size > 10_000
