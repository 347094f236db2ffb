"""The command line: JSON report, exit codes 0/1/2, errors without tracebacks, demo."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import CASES, EXTRA_CASES, TASK_CASES, arena_toml

from stt_codegen.spec.loader import bundled_cases

REQUIRED_KEYS = {"spec", "backend", "satisfied", "reached", "reach_time", "prescribed_time",
                 "collision", "min_obstacle_clearance", "left_state_space", "stayed_in_tube",
                 "max_abs_u", "steps"}


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=600)


def test_cases_lists_bundled_specs():
    out = run("cases")
    assert out.returncode == 0
    assert out.stdout.split() == ["crossing-moving", "hall-crossing", "office-base", "omnirobot-s1",
                                  "omnirobot-s2", "omnirobot-s3", "pointmaze-umaze",
                                  "second-order-quadrotor", "second-order-s1", "tasks-stay",
                                  "tasks-visit"]


def test_bundled_cases_are_the_paper_cases_and_the_examples():
    """The conftest's CASES (the parameters of the ``case`` fixture) are the paper's bundled
    specs; the others are the timed-task examples (TASK_CASES), the moving-obstacle and MuJoCo
    examples (EXTRA_CASES), the second-order cases and the differential-drive base
    (office-base), with tests of their own."""
    first_order = [c for c in bundled_cases()
                   if not c.startswith("second-order-") and c != "office-base"]
    assert first_order == sorted(CASES + TASK_CASES + EXTRA_CASES)


@pytest.mark.slow
def test_simulate_json_reports_definition_2_1():
    out = run("simulate", "omnirobot-s3", "--backend", "casadi", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert REQUIRED_KEYS <= set(data)
    assert data["satisfied"] is True and data["reach_time"] < data["prescribed_time"] == 9.0
    assert data["backend"] == "casadi" and data["steps"] == 9000


@pytest.mark.slow
def test_simulate_exit_1_when_not_satisfied():
    out = run("simulate", "omnirobot-s1", "--backend", "casadi", "--horizon", "2", "--json")
    assert out.returncode == 1
    assert json.loads(out.stdout)["satisfied"] is False


BAD_SPEC = """name = "x"
prescribed_time = -3
[state_space]
lower = [0.0]
upper = [1.0]
[initial]
lower = [0.0]
upper = [0.2]
[target]
lower = [0.8]
upper = [1.0]
"""


# --horizon -1 repeats test_errors_and_imports.py's in-process check: it and nan are slow-tier
@pytest.mark.parametrize("args, message", [
    (["simulate", "no-such-case"], "no bundled case and no file named 'no-such-case'"),
    pytest.param(["simulate", "omnirobot-s1", "--horizon", "-1"],
                 "--horizon: must be a positive", marks=pytest.mark.slow),
    pytest.param(["simulate", "omnirobot-s1", "--horizon", "nan"],
                 "--horizon: must be a positive", marks=pytest.mark.slow),
    (["simulate", "BADFILE"], "prescribed_time: must be positive"),
])
def test_bad_input_exit_2_without_traceback(tmp_path, args, message):
    bad = tmp_path / "bad.toml"
    bad.write_text(BAD_SPEC)
    args = [str(bad) if a == "BADFILE" else a for a in args]
    out = run(*args)
    assert out.returncode == 2
    assert message in out.stderr
    assert "Traceback" not in out.stderr and out.stderr.startswith("error: ")


def test_bad_arguments_exit_2():
    out = run("simulate", "omnirobot-s1", "--backend", "fortran")
    assert out.returncode == 2 and "Traceback" not in out.stderr


def test_plot_into_missing_folder_fails_before_simulating(tmp_path):
    out = run("simulate", "omnirobot-s1", "--plot", str(tmp_path / "no" / "x.png"))
    assert out.returncode == 2 and "does not exist" in out.stderr
    assert not (tmp_path / "no").exists()


@pytest.mark.slow
def test_plot_is_written(tmp_path):
    png = tmp_path / "run.png"
    out = run("simulate", "omnirobot-s2", "--backend", "casadi", "--plot", str(png))
    assert out.returncode == 0, out.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.png"]   # no temporary left


@pytest.mark.slow
def test_demo_generates_code_and_runs_the_c_controller(tmp_path):
    out = run("demo", "--out", str(tmp_path / "demo"))
    assert out.returncode == 0, out.stderr
    assert "run the c controller" in out.stdout
    for name in CASES + TASK_CASES + EXTRA_CASES:
        assert name in out.stdout
        assert (tmp_path / "demo" / f"{name}.png").stat().st_size > 10_000
        c_name = name.replace("-", "_")
        sensed = name == "hall-crossing"        # the C with the tube as data, no Python
        for suffix in (".c", ".h", "_selftest.c") + (() if sensed else (".py",)):
            assert (tmp_path / "demo" / name / f"{c_name}{suffix}").is_file()
    header = (tmp_path / "demo" / "hall-crossing" / "hall_crossing.h").read_text()
    assert "hall_crossing_switch(" in header
    assert "hall-crossing: the C with the tube as data" in out.stdout
    for name in ("second-order-s1", "second-order-quadrotor", "office-base"):   # the variants
        assert name in out.stdout
        assert (tmp_path / "demo" / f"{name}.png").stat().st_size > 10_000
        c_name = name.replace("-", "_")
        for suffix in (".c", ".h", ".py", "_selftest.c", "_vectors.json"):
            assert (tmp_path / "demo" / name / f"{c_name}{suffix}").is_file()
    assert out.stdout.count(" yes ") == len(CASES + TASK_CASES + EXTRA_CASES) + 3
    # the bundled fleet: a folder per robot, every robot satisfied, the closest approach
    assert "fleet warehouse-fleet: 8 robots, 28 pairs certified apart" in out.stdout
    assert "every robot satisfied, closest approach " in out.stdout
    assert (tmp_path / "demo" / "warehouse-fleet" / "base1" / "base1.c").is_file()
    assert (tmp_path / "demo" / "warehouse-fleet.png").stat().st_size > 10_000
    again = run("demo", "--out", str(tmp_path / "demo"))     # its own files: overwritten
    assert again.returncode == 0, again.stderr


def test_demo_jobs_below_one_is_bad_input_before_any_work(tmp_path):
    out = run("demo", "--out", str(tmp_path / "demo"), "--jobs", "0")
    assert out.returncode == 2 and out.stderr == "error: --jobs: must be at least 1, got 0\n"
    assert not (tmp_path / "demo").exists()


def test_demo_in_two_processes_reports_a_case_without_design(tmp_path, monkeypatch, capsys):
    """A worker's DesignError reaches the command line as the same one line, exit 1."""
    from stt_codegen import cases
    from stt_codegen.cli import main
    paths = []
    for name in ("reversed-a", "reversed-b"):
        paths.append(tmp_path / f"{name}.toml")
        paths[-1].write_text(REVERSED_PLANT.replace('name = "reversed"', f'name = "{name}"'))
    monkeypatch.setattr(cases, "bundled_cases", lambda: [str(p) for p in paths])
    monkeypatch.setattr(cases, "bundled_fleets", lambda: [])
    assert main(["demo", "--out", str(tmp_path / "out"), "--jobs", "2"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err


def test_atomic_write_leaves_a_normal_file_or_nothing(tmp_path):
    """The file gets the permissions of any new file (not a temporary file's 0600), and a
    writer that fails leaves nothing behind."""
    import os

    from stt_codegen.system import atomic_write
    mask = os.umask(0o022)
    try:
        atomic_write(tmp_path / "a.png", lambda tmp: tmp.write_bytes(b"png"))

        def failing(tmp):
            tmp.write_bytes(b"half")
            raise RuntimeError("disk full")
        with pytest.raises(RuntimeError):
            atomic_write(tmp_path / "b.png", failing)
    finally:
        os.umask(mask)
    assert (tmp_path / "a.png").read_bytes() == b"png"
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]


@pytest.mark.parametrize("command", ["simulate", "embedded"])
@pytest.mark.parametrize("seed", ["-5", str(2**32)])
def test_a_seed_outside_32_bits_is_bad_input_named_by_its_flag(command, seed, capsys):
    """``--seed -5`` ended in a traceback; now one line, exit 2, before any work."""
    from stt_codegen.cli import main
    assert main([command, "omnirobot-s1", "--seed", seed]) == 2
    captured = capsys.readouterr()
    assert captured.err == f"error: --seed: must be an integer in [0, 2**32), got {seed}\n"
    assert captured.out == ""


#: A valid spec the design refuses at once: its linear plant has g = -I (Assumption 2).
REVERSED_PLANT = arena_toml("reversed", 9.0,
                            '[plant]\nmodel = "linear"\ng = [[-1.0, 0.0], [0.0, -1.0]]\n')


@pytest.mark.parametrize("command, json_option", [
    (["design"], True), (["simulate", "--backend", "casadi"], True), (["verify"], True),
    (["embedded"], True), (["generate", "-o", "OUT"], False), (["demo", "--out", "OUT"], False),
])
def test_every_command_that_designs_says_why_there_is_no_design(command, json_option, tmp_path,
                                                               monkeypatch, capsys):
    """Exit 1, the design's reason as one line on stderr, nothing written; with ``--json``,
    one document of one shape on stdout (``simulate --json`` printed nothing)."""
    from stt_codegen import cases
    from stt_codegen.cli import main
    from stt_codegen.design.search import design_tube
    from stt_codegen.errors import DesignError
    from stt_codegen.spec.loader import parse_spec
    path = tmp_path / "reversed.toml"
    path.write_text(REVERSED_PLANT)
    with pytest.raises(DesignError) as refused:
        design_tube(parse_spec(REVERSED_PLANT))
    name, *options = [str(tmp_path / "out") if a == "OUT" else a for a in command]
    if name == "demo":      # the demo designs the bundled cases: make the spec one of them
        monkeypatch.setattr(cases, "bundled_cases", lambda: [str(path)])
        argv = [name, *options]
    else:
        argv = [name, str(path), *options]
    for as_json in ([False, True] if json_option else [False]):
        assert main(argv + ["--json"] * as_json) == 1
        captured = capsys.readouterr()
        assert captured.err == f"error: {refused.value}\n"
        if as_json:
            assert json.loads(captured.out) == {
                "spec": "reversed", "designed": False, "reason": str(refused.value),
                "kind": refused.value.kind.value}
    assert not (tmp_path / "out").exists() or name == "demo"


def test_a_design_document_says_it_is_one(capsys):
    from stt_codegen.cli import main
    assert main(["design", "omnirobot-s1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["designed"] is True and data["spec"] == "omnirobot-s1"
