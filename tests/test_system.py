"""stt_codegen.system: the one place that writes a file atomically or looks a tool up."""

from __future__ import annotations

import ast
import os
from pathlib import Path

import pytest

import stt_codegen
from stt_codegen import cli, system
from stt_codegen.errors import SpecError, ToolchainError
from stt_codegen.system import MissingTool, atomic_write, find_tool, write_durably

PACKAGE = Path(stt_codegen.__file__).parent


def test_find_tool_returns_the_first_installed(tmp_path, monkeypatch):
    for name in ("second", "third"):
        tool = tmp_path / name
        tool.write_text("#!/bin/sh\n")
        tool.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert find_tool("first", "second", "third", package="p") == str(tmp_path / "second")


def test_a_missing_tool_names_its_debian_package(monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    with pytest.raises(MissingTool) as info:
        find_tool("valgrind", package="valgrind")
    assert isinstance(info.value, ToolchainError) and cli.exit_code(info.value) == 3
    assert (info.value.tool, info.value.package) == ("valgrind", "valgrind")
    assert "apt-get install -y valgrind" in str(info.value)


def test_no_c_compiler_is_a_missing_tool(monkeypatch):
    from stt_codegen.runtime.compiled import compiler
    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.delenv("CC", raising=False)
    with pytest.raises(MissingTool, match="install the Debian package gcc"):
        compiler()


def test_one_missing_tool_error_and_one_lookup():
    """Every lookup goes through system.find_tool: nothing else calls shutil.which, and the
    embedded harness's MissingTool is this one."""
    from stt_codegen.embedded import MissingTool as embedded_missing
    assert embedded_missing is MissingTool
    callers = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Attribute) and node.attr in ("which", "mkstemp")
                    or isinstance(node, ast.ClassDef) and node.name == "MissingTool"):
                callers.append(str(path.relative_to(PACKAGE)))
    assert callers == ["system.py", "system.py"], callers     # the class and the lookup


def test_atomic_write_replaces_whole_or_not_at_all(tmp_path):
    target = tmp_path / "a.json"
    mask = os.umask(0o022)
    try:
        atomic_write(target, b"old")
        atomic_write(target, b"new")

        def failing(tmp: Path) -> None:
            tmp.write_bytes(b"half")
            raise RuntimeError("disk full")
        with pytest.raises(RuntimeError):
            atomic_write(target, failing)
        atomic_write(tmp_path / "b.png", lambda tmp: tmp.write_bytes(b"png"))
    finally:
        os.umask(mask)
    assert target.read_bytes() == b"new" and target.stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "b.png").stat().st_mode & 0o777 == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.png"]


def test_atomic_write_into_a_missing_folder_names_the_field(tmp_path):
    with pytest.raises(SpecError) as info:
        atomic_write(tmp_path / "no" / "a.png", b"x", field="plot")
    assert info.value.field == "plot"
    assert not (tmp_path / "no").exists()


def test_write_durably_never_overwrites(tmp_path):
    write_durably(tmp_path / "a", b"1")
    with pytest.raises(FileExistsError):
        write_durably(tmp_path / "a", b"2")
    assert (tmp_path / "a").read_bytes() == b"1"


def test_the_module_imports_nothing_of_the_package_but_errors():
    imported = [node.module for node in ast.parse(Path(system.__file__).read_text()).body
                if isinstance(node, ast.ImportFrom) and node.level]
    assert imported == ["errors"]
