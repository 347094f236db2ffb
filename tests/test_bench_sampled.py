"""``bench sampled``: law (13)'s per-axis sampled check, the folded step beside the loop."""

from __future__ import annotations

import json

import pytest

from stt_codegen.cli import main

pytestmark = pytest.mark.bench


def test_the_fold_gives_the_loops_results_on_a_base_and_a_diagonal_robot(capsys) -> None:
    assert main(["bench", "sampled", "--specs", "crossing-moving,office-base", "--runs", "1",
                 "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert [(r["spec"], r["turns"]) for r in rows] == [("crossing-moving", False),
                                                       ("office-base", True)]
    for row in rows:
        assert row["same"] and row["passed"] and row["samples"] > 1000
        assert row["loop_s"] > 0.0 and row["folded_s"] > 0.0


def test_a_spec_that_does_not_exist_is_refused(capsys) -> None:
    assert main(["bench", "sampled", "--specs", "no-such-case"]) == 2
    assert "no-such-case" in capsys.readouterr().err
