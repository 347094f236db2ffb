"""The spec's [second_order] table (stt_codegen/spec/second_order.py, docs/spec-format.md)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import stt_codegen as stt
from stt_codegen.cases import bundled_spec_bytes
from stt_codegen.errors import SpecError

REPO = Path(__file__).resolve().parents[1]


def _doc(**second_order) -> dict:
    data = tomllib.loads(bundled_spec_bytes("second-order-quadrotor").decode())
    data["second_order"].update(second_order)
    return data


def test_bundled_second_order_cases_parse() -> None:
    spec = stt.load_spec("second-order-quadrotor")
    order = spec.second_order
    assert order.model == "quadrotor" and order.parameters == (1.2, 0.3, 9.81)
    assert order.velocity_bound == (3.0, 3.0, 3.0) and order.input_gain == (0.625, 1.25)
    s1 = stt.load_spec("second-order-s1").second_order
    assert s1.model == "double-integrator" and s1.initial_velocity == (0.0, 0.0)
    assert stt.load_spec("omnirobot-s1").second_order is None


def test_defaults() -> None:
    data = _doc()
    for key in ("parameters", "initial_velocity", "velocity_bound", "input_gain",
                "drift_bound"):
        data["second_order"].pop(key)
    order = stt.Spec.from_dict(data).second_order
    assert order.parameters == (1.0, 0.3, 9.81)         # the model's nominal ones
    assert order.initial_velocity == (0.0, 0.0, 0.0) and order.velocity_bound is None
    assert order.input_gain == (1.0, 1.0) and order.drift_bound == 0.0


@pytest.mark.parametrize("change,field", [
    ({"model": "two-link-arm"}, "second_order.model"),
    ({"parameters": [1.0, 0.3]}, "second_order.parameters"),
    ({"parameters": [-1.0, 0.3, 9.81]}, "second_order.parameters"),
    ({"initial_velocity": [0.0, 0.0]}, "second_order.initial_velocity"),
    ({"initial_velocity": [0.0, 3.5, 0.0]}, "second_order.initial_velocity"),
    ({"velocity_bound": [3.0, 3.0]}, "second_order.velocity_bound"),
    ({"input_gain": [2.0, 1.0]}, "second_order.input_gain"),
])
def test_bad_tables_name_the_field(change, field) -> None:
    with pytest.raises(SpecError) as info:
        stt.Spec.from_dict(_doc(**change))
    assert info.value.field == field


def test_schema_refuses_unknown_models_and_keys() -> None:
    for change in ({"model": "blimp"}, {"thrust": 1.0}):
        with pytest.raises(SpecError) as info:
            stt.Spec.from_dict(_doc(**change))
        assert info.value.field.startswith("second_order")


def test_the_documented_table_loads() -> None:
    text = (REPO / "docs" / "spec-format.md").read_text()
    block = re.search(r"^```text\n(\[second_order\].*?)^```$", text, flags=re.S | re.M)
    data = tomllib.loads(bundled_spec_bytes("second-order-quadrotor").decode())
    data["second_order"] = tomllib.loads(block.group(1))["second_order"]
    assert stt.Spec.from_dict(data).second_order.model == "quadrotor"


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


@pytest.mark.slow
def test_a_bad_table_exits_2_without_traceback(tmp_path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(bundled_spec_bytes("second-order-s1").decode().replace(
        "initial_velocity = [0.0, 0.0]", "initial_velocity = [0.0]"))
    out = _cli("design", str(path))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "second_order.initial_velocity" in out.stderr


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_simulate_runs_the_cascade(tmp_path) -> None:
    out = _cli("simulate", "second-order-s1", "--backend", "c", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["satisfied"] and data["stayed_in_velocity_tube"]
    assert data["model"] == "double-integrator" and data["backend"] == "c"


@pytest.mark.slow
def test_generate_writes_the_cascade(tmp_path) -> None:
    out = _cli("generate", "second-order-s1", "-o", str(tmp_path / "out"))
    assert out.returncode == 0, out.stderr
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["manifest.json", "second_order_s1_cascade.c", "second_order_s1_cascade.h",
                     "second_order_s1_cascade.py", "second_order_s1_cascade_vectors.json"]
    committed = REPO / "generated" / "second-order-s1" / "double" / "second_order_s1_cascade.c"
    assert (tmp_path / "out" / "second_order_s1_cascade.c").read_bytes() == committed.read_bytes()
