"""``[plant] model = "mujoco"``: a spec whose plant is an MJCF model stepped by MuJoCo (the
bundled ``pointmaze-umaze``, gymnasium-robotics' mazes imported with ``--model mujoco``),
its declared bounds, what ``verify`` says of it, and bad input."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

mujoco = pytest.importorskip(
    "mujoco", reason="MuJoCo is not installed: pip install . (it is a dependency)")

import stt_codegen as stt  # noqa: E402  (after the skip)
from stt_codegen.cases import bundled_folder, bundled_spec_bytes  # noqa: E402
from stt_codegen.errors import SpecError  # noqa: E402
from stt_codegen.runtime.dynamics import plant_function  # noqa: E402
from stt_codegen.runtime.mujoco_plant import MujocoPlant  # noqa: E402
from stt_codegen.runtime.plants import make_plant, spec_plant  # noqa: E402


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args],
                          capture_output=True, text=True, timeout=600, cwd=cwd)


def _doc() -> dict:
    return tomllib.loads(bundled_spec_bytes("pointmaze-umaze").decode())


def _copy(tmp_path: Path) -> Path:
    """The bundled case and its MJCF, copied into ``tmp_path``."""
    (tmp_path / "pointmaze-umaze.xml").write_bytes(
        (bundled_folder() / "pointmaze-umaze.xml").read_bytes())
    text = bundled_spec_bytes("pointmaze-umaze").decode()
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def design():
    return stt.design_tube(stt.load_spec("pointmaze-umaze"))


def test_the_bundled_case_runs_on_mujoco_satisfied_without_contact(design):
    spec = design.spec
    assert spec.mujoco is not None and spec.mujoco.path.is_file()
    assert spec.mujoco.path.parent == bundled_folder()
    plant = spec_plant(spec)
    assert isinstance(plant, MujocoPlant) and plant.nstates == 2 and plant.ninputs == 2
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_tube, result.to_json()
    assert result.contacts == 0 and result.first_contact is None
    assert result.min_obstacle_clearance > 0


@pytest.mark.slow
def test_the_command_line_simulates_it_and_writes_the_plot(tmp_path):
    out = _cli("simulate", "pointmaze-umaze", "--plot", str(tmp_path / "run.png"))
    assert out.returncode == 0, out.stdout + out.stderr
    assert "MuJoCo contacts (other than with the ground): 0 timesteps" in out.stdout
    assert (tmp_path / "run.png").stat().st_size > 10_000


def test_the_spec_file_names_its_mjcf_relative_to_itself(tmp_path):
    path = _copy(tmp_path)
    spec = stt.load_spec(path)
    assert spec.mujoco.path == tmp_path / "pointmaze-umaze.xml"
    (tmp_path / "pointmaze-umaze.xml").unlink()
    with pytest.raises(SpecError) as err:
        stt.load_spec(path)
    assert err.value.field == "plant.mjcf" and "no file 'pointmaze-umaze.xml'" in err.value.reason
    out = _cli("design", str(path))
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "plant.mjcf" in out.stderr


def test_verify_says_what_it_cannot_prove_about_an_mjcf_plant(design):
    report = stt.verify(design)
    assert list(report.failed) == []
    checks = {c.name: c for c in report.checks}
    a2 = checks["assumption2.declared"]
    assert a2.passed and "not proved: that the mujoco plant meets the declared" in a2.detail
    within = checks["sampled.plant_within_assumptions"]
    assert within.passed and within.detail.startswith("not checked")
    assert "no equations here" in checks["sampled.tube_kept"].detail


@pytest.mark.parametrize("change, field, words", [
    ({"joints": ["ball_x"]}, "plant.joints", "must name 2 joints"),
    ({"actuators": ["vel_x", "vel_y", "vel_z"]}, "plant.actuators", "must name 2 actuators"),
    ({"mjcf": None}, "plant.mjcf", "missing"),
])
def test_bad_mujoco_keys_name_the_field(change, field, words):
    doc = _doc()
    for key, value in change.items():
        if value is None:
            del doc["plant"][key]
        else:
            doc["plant"][key] = value
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == field and words in err.value.reason


@pytest.mark.parametrize("key", ["input_gain", "drift_bound"])
def test_the_bounds_of_a_plant_without_equations_are_required(key):
    doc = _doc()
    del doc["assumptions"][key]
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == f"assumptions.{key}" and "no equations" in err.value.reason


def test_mujoco_keys_on_another_model_are_refused():
    doc = _doc()
    doc["plant"] = {"model": "single-integrator", "mjcf": "x.xml"}
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == "plant.mjcf"
    assert "only the mujoco, differential-drive and mujoco-force models take mjcf" in err.value.reason


def test_an_unknown_joint_is_named_when_the_plant_is_built(tmp_path):
    path = _copy(tmp_path)
    path.write_text(path.read_text().replace('"ball_y"]', '"ball_z"]'))
    design = stt.design_tube(stt.load_spec(path))
    with pytest.raises(SpecError) as err:
        stt.simulate(design, backend="python")
    assert err.value.field == "plant.joints" and "'ball_z'" in err.value.reason
    out = _cli("simulate", str(path))
    assert out.returncode == 2 and "Traceback" not in out.stderr


def test_no_equations_are_made_up_for_it(design):
    """The MuJoCo model is never handled as another model: no g(x) to print, no
    python-control plant, no firmware closed loop."""
    with pytest.raises(ValueError, match="no equations"):
        plant_function("mujoco", 2)
    with pytest.raises(SpecError, match="spec_plant"):
        make_plant("mujoco", 2, 0.05)
    from stt_codegen.embedded.deploy import run_embedded
    with pytest.raises(SpecError) as err:
        run_embedded(design)
    assert err.value.field == "plant.model" and "runs on the host" in err.value.reason


def test_the_importer_refuses_a_force_driven_mujoco_plant(tmp_path):
    """The importer writes the ball on velocity servos only: a second-order MuJoCo model is
    refused by name, and nothing is written."""
    pytest.importorskip("gymnasium_robotics", reason="gymnasium-robotics is not installed: "
                                                     "pip install \".[mujoco]\"")
    out = _cli("import", "pointmaze", "UMaze", "-o", "maze.toml", "--mjcf", "maze.xml",
               "--model", "mujoco-force", cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "'mujoco-force' is not written by the importer" in out.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.parametrize("maze", ["UMaze", "Medium"])
def test_imported_pointmazes_run_on_mujoco(tmp_path, maze):
    """``stt-codegen import pointmaze NAME --model mujoco --mjcf``: the spec and
    gymnasium-robotics' maze with the ball on velocity servos; designed, and satisfied on
    MuJoCo without a wall contact."""
    pytest.importorskip("gymnasium_robotics", reason="gymnasium-robotics is not installed: "
                                                     "pip install \".[mujoco]\"")
    out = _cli("import", "pointmaze", maze, "-o", "maze.toml", "--mjcf", "maze.xml",
               "--model", "mujoco", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    spec = stt.load_spec(tmp_path / "maze.toml")
    assert spec.mujoco.actuators == ("vel_x", "vel_y")
    result = stt.simulate(stt.design_tube(spec), backend="c")
    assert result.satisfied and result.contacts == 0, result.to_json()


@pytest.mark.slow
def test_a_force_driven_mjcf_runs_the_cascade_on_mujoco():
    """``plant.model = "mujoco-force"`` (tests/specs/umaze-mujoco-force.toml): PointMaze's
    ball through its force motors is second order; the cascade at 1 kHz keeps both tubes
    on MuJoCo within the motors' range, without a wall contact; verify proves the
    cascade's certificate for the declared class and says it did not check the plant."""
    spec = stt.load_spec(Path(__file__).parent / "specs" / "umaze-mujoco-force.toml")
    assert spec.order == 2 and spec.input_names == ("motor_x", "motor_y")
    design = stt.design_tube(spec)
    plant = spec_plant(spec)
    assert isinstance(plant, MujocoPlant) and plant.nstates == 4
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_velocity_tube, result.to_json()
    assert result.contacts == 0 and max(result.max_abs_u) <= 1.0
    report = stt.verify(design)
    assert list(report.failed) == []
    checks = {c.name: c for c in report.checks}
    assert checks["cascade.sampled"].passed
    assert checks["cascade.plant_within_assumptions"].detail.startswith("not checked")
    from stt_codegen.embedded.cascade_loop import closed_loop_program
    with pytest.raises(SpecError) as err:
        closed_loop_program(design, "p")
    assert err.value.field == "plant.model"


def test_an_input_bound_of_a_mujoco_plant_is_per_actuator():
    doc = _doc()
    doc["actuator"] = {"input_bound": [1.0]}
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == "actuator.input_bound"
    assert "vel_x, vel_y" in err.value.reason and "got 1" in err.value.reason


def test_a_force_driven_mjcf_needs_its_declared_class():
    doc = tomllib.loads((Path(__file__).parent / "specs" / "umaze-mujoco-force.toml")
                        .read_text())
    del doc["assumptions"]["drift_bound"]
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field == "assumptions.drift_bound" and "no equations" in err.value.reason
