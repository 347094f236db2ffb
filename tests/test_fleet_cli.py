"""Fleets on the command line (docs/fleets.md): design, generate and simulate a fleet file."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from stt_codegen.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from test_fleet import TWO  # noqa: E402

TWO_TOML = """name = "two"
[state_space]
lower = [0.0, 0.0]
upper = [12.0, 8.0]

[[obstacles]]
lower = [3.0, 2.0]
upper = [9.0, 6.0]
""" + "".join(f"""
[[robots]]
name = "{r['name']}"
radius = 0.2
prescribed_time = 20.0
initial = {{lower = {r['initial']['lower']}, upper = {r['initial']['upper']}}}
target = {{lower = {r['target']['lower']}, upper = {r['target']['upper']}}}
controller = {{rate_hz = 100.0}}
plant = {{model = "single-integrator", disturbance_amplitude = 0.05}}
""" for r in TWO["robots"])


@pytest.fixture
def fleet_file(tmp_path) -> Path:
    path = tmp_path / "two.toml"
    path.write_text(TWO_TOML)
    return path


def test_design_of_a_fleet_file_reports_every_pair(fleet_file, capsys):
    assert main(["design", str(fleet_file), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["certified"] is True and sorted(data["robots"]) == ["a", "b"]
    (pair,) = data["pairs"]
    assert pair["pair"] == ["a", "b"] and pair["passed"] and pair["margin"] > 0


def test_a_bad_robot_is_exit_2_naming_it(fleet_file, capsys):
    fleet_file.write_text(TWO_TOML.replace("upper = [11.6, 7.4]", "upper = [10.0, 7.4]", 1))
    assert main(["design", str(fleet_file)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: robots[0].target.lower: ") and "Traceback" not in err


def test_a_fleet_plot_in_a_missing_folder_is_exit_2_before_any_work(fleet_file, tmp_path,
                                                                       capsys):
    assert main(["design", str(fleet_file), "--plot", str(tmp_path / "no" / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --plot: folder ") and "Traceback" not in err


def test_a_fleet_has_no_log(fleet_file, tmp_path, capsys):
    assert main(["simulate", str(fleet_file), "--log", str(tmp_path / "x.mcap")]) == 2
    assert "--log: is for a single spec, not a fleet" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == [fleet_file]


@pytest.mark.slow
def test_design_of_a_fleet_draws_it_in_time_slices(fleet_file, tmp_path, capsys):
    out = tmp_path / "figs"
    out.mkdir()
    assert main(["design", str(fleet_file), "--plot", str(out / "fleet.png")]) == 0
    assert [p.name for p in out.iterdir()] == ["fleet.png"]          # nothing half-written
    assert (out / "fleet.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_generate_writes_one_folder_per_robot_and_simulate_measures_the_pairs(
        fleet_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["generate", str(fleet_file), "-o", str(out), "--lang", "c,python"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["a", "b"]
    for name in ("a", "b"):
        files = sorted(p.name for p in (out / name).iterdir())
        assert f"{name}.c" in files and f"{name}.py" in files and "manifest.json" in files
        assert json.loads((out / name / "manifest.json").read_text())["spec"]["name"] == name
    capsys.readouterr()
    assert main(["simulate", str(fleet_file), "--backend", "c", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["satisfied"] is True
    (approach,) = data["approaches"]
    assert approach["pair"] == ["a", "b"] and approach["clearance"] > 0
