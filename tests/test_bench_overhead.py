"""bench overhead: the command's CPU beside its library call (no timing is asserted)."""

from __future__ import annotations

import pytest

from stt_codegen.cli import main
from stt_codegen_bench.overhead import COMMANDS, format_overhead_report, run_overhead_bench


def test_unknown_command_or_no_run_is_refused(capsys):
    with pytest.raises(ValueError, match="commands"):
        run_overhead_bench(commands=("simulate",))
    with pytest.raises(ValueError, match="runs"):
        run_overhead_bench(runs=0)
    assert main(["bench", "overhead", "--commands", "design,plot"]) == 2
    assert "error: --commands: unknown commands ['plot']" in capsys.readouterr().err


def test_report_lists_each_command_with_its_differences():
    row = {"command": "design", "command_s": 1.25, "script_s": 1.2, "call_s": 0.5,
           "over_call_s": 0.75, "over_script_s": 0.05}
    text = format_overhead_report({"spec": "omnirobot-s1", "runs": 5, "rows": [row],
                                   "cpus": 2, "load": [1.0, 1.5], "bytecode_cached": False})
    lines = text.splitlines()
    assert lines[2].split() == ["design", "1.250", "1.200", "0.500", "0.750", "0.050"]
    assert "least of 5 runs" in lines[0] and "every process compiles" in lines[-1]


@pytest.mark.bench
def test_one_run_measures_the_command_the_script_and_the_call():
    report = run_overhead_bench("omnirobot-s1", ("design",), runs=1)
    (row,) = report["rows"]
    assert set(COMMANDS) >= {row["command"]} and report["runs"] == 1
    # the call is part of the script's process; the command makes the same call
    assert 0 < row["call_s"] < row["script_s"] and 0 < row["call_s"] < row["command_s"]
    assert row["over_call_s"] == pytest.approx(row["command_s"] - row["call_s"])
