"""The tube out: ``Design.tube_table`` and ``stt-codegen design --export`` (CSV, NumPy)."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest
from conftest import design_of, model_of

from stt_codegen.errors import SpecError


def _design(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=600)


def test_the_csv_is_the_models_tube_at_the_controllers_rate(tmp_path):
    out = _design("omnirobot-s1", "--export", "tube.csv", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    with open(tmp_path / "tube.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t [s]"] + [f"gamma_{side}_{i} [state units]" for i in (1, 2, 3)
                                   for side in "LU"]
    data = np.array(rows[1:], dtype=float)
    design = design_of("omnirobot-s1")
    dt = 1.0 / design.tube.rate_hz
    assert data[0, 0] == 0.0 and np.array_equal(data[:, 0], np.arange(len(data)) * dt)
    assert data[-1, 0] >= design.spec.prescribed_time
    # the CasADi model's gamma (eq. (10)) at those t, its alpha from the model's own
    # implicit step from alpha(0) = 0
    model = model_of("omnirobot-s1")
    alpha = np.zeros(6)
    picked = range(0, len(data), 97)
    expected = {}
    for k in range(max(picked) + 1):
        if k in picked:
            g_l, g_u = (np.array(v).ravel() for v in model["tube"](data[k, 0], alpha)[:2])
            expected[k] = np.column_stack([g_l, g_u]).ravel()
        alpha = np.array(model["alpha_step"](data[k, 0], dt, alpha)).ravel()
    for k, row in expected.items():
        np.testing.assert_allclose(data[k, 1:], row, rtol=1e-9, atol=1e-12)


@pytest.mark.slow
def test_the_npz_holds_the_same_columns(tmp_path):
    out = _design("office-base", "--export", "tube.npz", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    table = design_of("office-base").tube_table()
    with np.load(tmp_path / "tube.npz") as saved:
        assert list(saved) == list(table) == ["t", "gamma_L_1", "gamma_U_1", "gamma_L_2",
                                              "gamma_U_2"]
        for name in table:
            assert np.array_equal(saved[name], table[name])


@pytest.mark.parametrize("path, message", [("tube.txt", "must end in .csv or .npz"),
                                           ("missing/tube.csv", "does not exist")])
def test_a_bad_export_path_is_refused_before_any_work(tmp_path, path, message):
    out = _design("omnirobot-s1", "--export", path, cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert f"error: --export: " in out.stderr and message in out.stderr
    assert out.stdout == "" and list(tmp_path.iterdir()) == []


def test_a_bad_horizon_is_a_spec_error():
    with pytest.raises(SpecError, match="horizon"):
        design_of("omnirobot-s1").tube_table(horizon=-1.0)
    assert design_of("omnirobot-s1").tube_table(horizon=0.5)["t"][-1] == pytest.approx(0.5)
