"""The default backend is the fastest available: the generated C where a C compiler is found,
else the numpy reference; the result names it."""

from __future__ import annotations

import shutil

import pytest

import stt_codegen as stt
from stt_codegen.runtime.backends import default_backend


def test_without_a_compiler_the_reference_runs(monkeypatch, tmp_path) -> None:
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))          # an empty folder: no cc, gcc, clang
    assert default_backend() == "reference"


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                    reason="no C compiler: install the Debian package gcc")
def test_with_a_compiler_the_generated_c_runs_and_the_result_says_so() -> None:
    assert default_backend() == "c"
    design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    result = stt.simulate(design, horizon=0.05)
    assert result.backend == "c"
    assert stt.simulate(design, backend="reference", horizon=0.05).backend == "reference"
