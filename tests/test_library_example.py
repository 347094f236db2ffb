"""The library examples of docs/library.md (and the README's "Use from Python") and
docs/mujoco.md, run verbatim."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

import stt_codegen

DOC = Path(__file__).parent.parent / "docs" / "library.md"
MUJOCO_DOC = DOC.parent / "mujoco.md"


def python_blocks_of(markdown: str) -> list[str]:
    """The ```python fenced blocks of a markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```$", markdown, flags=re.S | re.M)


def python_blocks(path: Path) -> list[str]:
    """The ```python fenced blocks of a markdown file, in order."""
    return python_blocks_of(path.read_text())


def test_the_document_has_the_examples():
    blocks = python_blocks(DOC)
    assert len(blocks) == 4
    assert "stt.load_spec" in blocks[0] and "stt.Spec.from_dict" in blocks[1]
    assert "progress=" in blocks[2] and "summary()" in blocks[2]
    assert "controller_system" in blocks[3] and "ct.input_output_response" in blocks[3]
    assert ["MujocoPlant" in b for b in python_blocks(MUJOCO_DOC)] == [True]


def test_the_readme_example_is_the_documents():
    """The README's "Use from Python" shows the first example of docs/library.md, verbatim
    (so the test below runs the README's code too)."""
    readme = (DOC.parent.parent / "README.md").read_text()
    if "## Use from Python" not in readme:
        pytest.skip("the README has no section 'Use from Python' yet")
    section = readme.split("## Use from Python", 1)[1].split("\n## ", 1)[0]
    assert python_blocks_of(section)[0] == python_blocks(DOC)[0]


@pytest.mark.parametrize("k", [pytest.param(0, marks=pytest.mark.slow), 1, 2, 3])
def test_library_example_runs_verbatim(k, tmp_path, monkeypatch, capsys):
    if k in (0, 3) and shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("the example compiles C: install the Debian package gcc")
    monkeypatch.chdir(tmp_path)
    exec(compile(python_blocks(DOC)[k], f"{DOC.name}[{k}]", "exec"), {})
    out = capsys.readouterr().out
    if k == 0:
        assert "omnirobot-s1: " in out and "checks passed" in out
        assert sorted(p.name for p in (tmp_path / "omnirobot-s1-float").iterdir()) == [
            "CMakeLists.txt", "Makefile", "manifest.json", "omnirobot_s1.c", "omnirobot_s1.h",
            "omnirobot_s1_selftest.c", "omnirobot_s1_vectors.json"]
    elif k == 2:
        lines = out.splitlines()
        assert lines[:3] == ["1.0 True", "[\"Design(spec='second-order-s1'\", \" variant='cascade'\"]",
                             "0.0 True"]
        assert lines[3] == ("Run of second-order-s1 (backend casadi, 1000 steps): "
                            "Definition 2.1 not satisfied")
    elif k == 3:     # the python-control loop is simulate's run
        assert out.splitlines() == ["True", "True"]
    else:
        lines = out.splitlines()
        assert lines[0] == "True"
        assert lines[1].startswith("prescribed_time - must be positive")
        assert lines[2].startswith("no design: ")


def test_every_public_name_has_a_docstring():
    names = [n for n in stt_codegen.__all__ if n != "__version__"]
    assert {"load_spec", "Spec", "design_tube", "generate", "simulate", "verify",
            "SpecError", "DesignError", "ToolchainError"} <= set(names)
    for name in names:
        obj = getattr(stt_codegen, name)
        doc = obj.__doc__ or ""
        assert len(doc.strip()) > 20, name
    for name in ("generate", "simulate", "load_spec", "design_tube"):
        doc = getattr(stt_codegen, name).__doc__
        assert "Parameters\n" in doc and "Returns\n" in doc and "Raises\n" in doc, name
    from stt_codegen.verification.command import verify
    assert "Parameters\n" in verify.__doc__ and "Examples\n" in verify.__doc__
    assert stt_codegen.Spec.from_dict.__doc__


@pytest.mark.slow
def test_the_mujoco_example_runs_verbatim(monkeypatch, capsys):
    """The MuJoCo example of docs/mujoco.md, from the repository's root (its files are the
    tests' own)."""
    pytest.importorskip("mujoco", reason="MuJoCo is not installed: pip install mujoco")
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("the example compiles C: install the Debian package gcc")
    monkeypatch.chdir(DOC.parent.parent)
    exec(compile(python_blocks(MUJOCO_DOC)[0], f"{MUJOCO_DOC.name}[0]", "exec"), {})
    satisfied, contacts, peak = capsys.readouterr().out.split()
    assert satisfied == "True" and contacts == "0" and float(peak) < 1.0
