"""The benchmarks are a distribution of their own (tests/benchmarks): ``stt-codegen bench``
comes through the entry-point group, and without it the command says how to install it."""

from __future__ import annotations

import importlib.metadata
import tomllib
from pathlib import Path

import pytest

from stt_codegen.cli import COMMAND_GROUP, OPTIONAL_COMMANDS, main

REPO = Path(__file__).resolve().parents[1]
#: What only the benchmarks use (tqdm is the library's own, for the command line's progress bar).
BENCH_ONLY = ("networkx", "distributed", "ompl")


def _names(requirements: list[str]) -> set[str]:
    return {r.split(";")[0].split("[")[0].split(">")[0].split("=")[0].split("<")[0].strip()
            for r in requirements}


def test_the_library_neither_ships_nor_needs_the_benchmarks():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    core = _names(project["project"]["dependencies"])
    test_extra = _names(project["project"]["optional-dependencies"]["test"])
    assert not (core | test_extra) & set(BENCH_ONLY)
    packages = project["tool"]["setuptools"]["packages"]
    assert not [p for p in packages if "bench" in p]
    assert not list((REPO / "stt_codegen" / "bench").glob("*.py"))
    assert not [p for p in (REPO / "stt_codegen").rglob("*.py")
                if "import stt_codegen_bench" in p.read_text()
                or "from stt_codegen_bench" in p.read_text()]


def test_the_benchmark_distribution_declares_the_command():
    bench = tomllib.loads((REPO / "tests" / "benchmarks" / "pyproject.toml").read_text())
    assert set(BENCH_ONLY) | {"stt-codegen"} <= _names(bench["project"]["dependencies"])
    points = bench["project"]["entry-points"][COMMAND_GROUP]
    assert points == {"bench": "stt_codegen_bench.cli:configure_bench"}
    assert "bench" in OPTIONAL_COMMANDS


def test_installed_the_command_is_the_distributions(capsys):
    found = importlib.metadata.entry_points(group=COMMAND_GROUP, name="bench")
    assert [p.value for p in found] == ["stt_codegen_bench.cli:configure_bench"]
    with pytest.raises(SystemExit) as exc:
        main(["bench", "--help"])
    assert exc.value.code == 0
    assert "covering" in capsys.readouterr().out


def test_not_installed_the_command_names_the_install_and_exits_3(monkeypatch, capsys):
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda **kw: ())
    assert main(["bench", "arenas", "--count", "2"]) == 3
    err = capsys.readouterr().err
    assert err == ("error: stt-codegen bench is not installed; install it with "
                   "python3 -m pip install ./tests/benchmarks\n")
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "bench" in capsys.readouterr().out
