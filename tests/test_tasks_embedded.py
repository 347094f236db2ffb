"""The timed-task examples on the emulated Cortex-M4F (`stt-codegen embedded`): the
self-test passes and the closed loop on the target meets every task (judged on the
states the target prints) and agrees with the host."""

from __future__ import annotations

import json

import pytest

from conftest import TASK_CASES
from stt_codegen.cli import main


@pytest.mark.embedded
@pytest.mark.parametrize("case", TASK_CASES)
def test_task_example_on_the_cortex_m4f(case, tmp_path, capsys) -> None:
    code = main(["embedded", case, "--json", "--build-dir", str(tmp_path / "b")])
    r = json.loads(capsys.readouterr().out)
    assert code == 0 and r["ok"]
    assert r["vectors_failed"] == 0 and r["vectors_passed"] > 500
    assert r["closed_loop_satisfied"] and r["outside_tube_steps"] == 0
    assert [t["met"] for t in r["tasks"]] == [True] * len(r["tasks"]) and r["tasks"]
    assert all(t["margin"] > 0 for t in r["tasks"])
    assert r["host_satisfied"] and r["max_state_deviation"] < 1e-3
