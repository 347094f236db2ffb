"""The generated C and Python controllers satisfy the bundled tasks in closed loop.

Both are bit-identical to the CasADi model (tests/test_codegen_c.py, test_codegen_python.py),
whose loops test_simulate.py runs on every case: here S1 runs in the fast tier, S2 and S3
in the slow one.
"""

from __future__ import annotations

import json

import pytest
from conftest import CASES

from stt_codegen.cli import main


@pytest.mark.parametrize("backend", ["c", "python"])
@pytest.mark.parametrize("case", [CASES[0]] + [pytest.param(c, marks=pytest.mark.slow)
                                                for c in CASES[1:]])
def test_simulate_satisfied(case, backend, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    code = main(["simulate", case, "--backend", backend, "--json"])
    data = json.loads(capsys.readouterr().out)
    assert data["satisfied"] is True and data["stayed_in_tube"] is True, data
    assert data["backend"] == backend and code == 0
    if backend == "c":
        assert list((tmp_path / "cache").glob("*.so"))
